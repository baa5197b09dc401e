#pragma once
// Outputs that never destroy (the CLI's --json, --csv; usable by any program):
//   - a regular file (or a missing one) is written atomically: a temporary file in the same
//     folder, flushed to disk, renamed over the target; a reader sees the old or the new file;
//   - a symlink is followed and its target written the same way (the link stays a link);
//   - a FIFO, a character device or "-" (stdout) is written in place as a stream;
//   - a directory, a missing parent folder or a folder that cannot be written is refused with
//     an InputError naming the path; check_output_path() says so before any work is done;
//   - no temporary file is left behind, also on errors and on SIGINT / SIGTERM.
#include <signal.h>

#include <string>
#include <vector>

namespace peelcd {

// Holds SIGINT, SIGTERM and SIGHUP back while it lives (a folder of files being written and
// renamed into place, as `peelcd dump` does): a Ctrl-C then takes effect when the folder is
// complete or cleaned up, never between. The held signal is delivered when this ends.
class DeferSignals {
 public:
  DeferSignals() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGHUP);
    sigprocmask(SIG_BLOCK, &set, &old_);
  }
  ~DeferSignals() { sigprocmask(SIG_SETMASK, &old_, nullptr); }
  DeferSignals(const DeferSignals&) = delete;
  DeferSignals& operator=(const DeferSignals&) = delete;

 private:
  sigset_t old_;
};

// Throws InputError ("<what> 'path': ...") when `path` cannot be written as described above.
void check_output_path(const std::string& path, const std::string& what);

// A folder output (a plot folder): `path` is a writable folder, or does not exist and its parent
// is a writable folder. Throws InputError ("<what> 'path': ...") otherwise, before any work.
void check_output_dir(const std::string& path, const std::string& what);

// Throws InputError ("<what> 'out': it is the input 'x'; ...") when the output `out` is one of
// the `inputs` (the same file, by path or by link): an output never overwrites an input.
void refuse_overwriting_input(const std::string& out, const std::vector<std::string>& inputs, const std::string& what);

// Writes `text` to `path` as described above. Throws InputError.
void write_output_file(const std::string& path, const std::string& text, const std::string& what);

}  // namespace peelcd
