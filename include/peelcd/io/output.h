#pragma once
// Outputs that never destroy (the CLI's --json, --csv; usable by any program):
//   - a regular file (or a missing one) is written atomically: a temporary file in the same
//     folder, flushed to disk, renamed over the target; a reader sees the old or the new file;
//   - a symlink is followed and its target written the same way (the link stays a link);
//   - a FIFO, a character device or "-" (stdout) is written in place as a stream;
//   - a directory, a missing parent folder or a folder that cannot be written is refused with
//     an InputError naming the path; check_output_path() says so before any work is done;
//   - no temporary file is left behind, also on errors and on SIGINT / SIGTERM.
#include <string>

namespace peelcd {

// Throws InputError ("<what> 'path': ...") when `path` cannot be written as described above.
void check_output_path(const std::string& path, const std::string& what);

// Writes `text` to `path` as described above. Throws InputError.
void write_output_file(const std::string& path, const std::string& text, const std::string& what);

}  // namespace peelcd
