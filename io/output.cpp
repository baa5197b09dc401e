#include "peelcd/io/output.h"

#include "peelcd/io/error.h"

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace peelcd {
namespace {

// The temporary file being written, for the signal handler (one at a time per process).
char g_temporary[4096] = {0};

extern "C" void remove_temporary_and_reraise(int sig) {
  if (g_temporary[0]) unlink(g_temporary);  // async-signal-safe
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

// The file a path names: symlinks followed (relative targets against the link's folder).
fs::path resolve(const fs::path& path) {
  fs::path p = path;
  std::error_code ec;
  for (int hops = 0; hops < 40 && fs::is_symlink(fs::symlink_status(p, ec)); ++hops) {
    const fs::path target = fs::read_symlink(p, ec);
    if (ec) break;
    p = target.is_absolute() ? target : p.parent_path() / target;
  }
  return p;
}

bool is_stream(const fs::file_status& s) {
  return s.type() == fs::file_type::fifo || s.type() == fs::file_type::character ||
         s.type() == fs::file_type::block || s.type() == fs::file_type::socket;
}

// The folder `target` would be created in exists and is writable.
void check_parent_folder(const fs::path& target, const std::string& path, const std::string& what) {
  std::error_code ec;
  const fs::path parent = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  if (!fs::is_directory(parent, ec))
    throw InputError(what + " '" + path + "': the folder '" + parent.string() + "' does not exist");
  if (access(parent.c_str(), W_OK | X_OK) != 0)
    throw InputError(what + " '" + path + "': cannot write into the folder '" + parent.string() + "'");
}

}  // namespace

void check_output_path(const std::string& path, const std::string& what) {
  if (path == "-") return;
  if (path.empty()) throw InputError(what + ": an empty path");
  const fs::path target = resolve(path);
  std::error_code ec;
  const fs::file_status st = fs::status(target, ec);
  if (fs::is_directory(st)) throw InputError(what + " '" + path + "': is a directory");
  if (is_stream(st)) return;
  check_parent_folder(target, path, what);
  if (fs::exists(st) && access(target.c_str(), W_OK) != 0)
    throw InputError(what + " '" + path + "': the file is not writable");
}

void check_output_dir(const std::string& path, const std::string& what) {
  if (path.empty()) throw InputError(what + ": an empty path");
  std::error_code ec;
  const fs::path target(path);
  if (fs::exists(target, ec)) {
    if (!fs::is_directory(target, ec)) throw InputError(what + " '" + path + "': exists and is not a folder");
    if (access(target.c_str(), W_OK | X_OK) != 0) throw InputError(what + " '" + path + "': cannot write into the folder");
    return;
  }
  check_parent_folder(target, path, what);
}

void refuse_overwriting_input(const std::string& out, const std::vector<std::string>& inputs, const std::string& what) {
  if (out.empty() || out == "-") return;
  std::error_code ec;
  if (!fs::exists(out, ec)) return;
  for (const std::string& in : inputs)
    if (fs::equivalent(out, in, ec))
      throw InputError(what + " '" + out + "': it is the input '" + in + "'; an output never overwrites an input");
}

void write_output_file(const std::string& path, const std::string& text, const std::string& what) {
  if (path == "-") {
    std::cout << text << std::flush;
    if (!std::cout) throw InputError(what + ": cannot write to stdout");
    return;
  }
  check_output_path(path, what);
  const fs::path target = resolve(path);
  std::error_code ec;
  if (is_stream(fs::status(target, ec))) {  // a FIFO or a device: in place
    std::FILE* f = std::fopen(target.c_str(), "w");
    if (!f) throw InputError(what + " '" + path + "': cannot open it: " + std::strerror(errno));
    const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
    if (std::fclose(f) != 0 || !ok) throw InputError(what + " '" + path + "': cannot write it");
    return;
  }
  const fs::path parent = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  const std::string pattern = (parent / ("." + target.filename().string() + ".XXXXXX")).string();
  if (pattern.size() >= sizeof g_temporary) throw InputError(what + " '" + path + "': the path is too long");
  std::strcpy(g_temporary, pattern.c_str());
  auto* old_int = std::signal(SIGINT, remove_temporary_and_reraise);
  auto* old_term = std::signal(SIGTERM, remove_temporary_and_reraise);
  const auto restore = [&] {
    std::signal(SIGINT, old_int);
    std::signal(SIGTERM, old_term);
  };
  const int fd = mkstemp(g_temporary);
  if (fd < 0) {
    g_temporary[0] = 0;
    restore();
    throw InputError(what + " '" + path + "': cannot create a file in '" + parent.string() + "': " + std::strerror(errno));
  }
  const std::string tmp = g_temporary;
  const auto fail = [&](const std::string& why) {
    unlink(tmp.c_str());
    g_temporary[0] = 0;
    restore();
    throw InputError(what + " '" + path + "': " + why);
  };
  // The permissions a new file gets (mkstemp makes 0600): 0666 less the umask, or the old file's.
  const mode_t mask = umask(0);
  umask(mask);
  struct stat old {};
  const mode_t mode = stat(target.c_str(), &old) == 0 ? (old.st_mode & 07777) : (0666 & ~mask);
  fchmod(fd, mode);
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n <= 0) {
      if (n < 0 && errno == EINTR) continue;
      close(fd);
      fail(std::string("cannot write it: ") + std::strerror(errno));
    }
    done += std::size_t(n);
  }
  if (fsync(fd) != 0 || close(fd) != 0) fail(std::string("cannot write it: ") + std::strerror(errno));
  if (std::rename(tmp.c_str(), target.c_str()) != 0) fail(std::string("cannot replace it: ") + std::strerror(errno));
  g_temporary[0] = 0;
  restore();
}

}  // namespace peelcd
