#include "cli/cli_files.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "mbsgen/runtime/error.hpp"

namespace mbsgen::cli {

namespace fs = std::filesystem;

namespace {

Error system_error(const std::string& what, const fs::path& path, int error) {
  return Error(what + " " + path.string() + ": " + std::strerror(error));
}

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISLNK(mode)) return "a symbolic link";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  return "not a regular file";
}

// Whether path exists (as a regular file; anything else is refused).
bool exists_regular(const fs::path& path, const std::string& what) {
  struct stat st;
  if (::lstat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) return false;
    throw system_error(what + ": cannot inspect", path, errno);
  }
  if (!S_ISREG(st.st_mode))
    throw Error(what + ": refusing to write " + path.string() + ": it is " + kind_of(st.st_mode) +
                ", not a regular file");
  return true;
}

// The first max bytes of a regular file (opened without following links or blocking).
std::string head_of(const fs::path& path, std::size_t max, const std::string& what) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw system_error(what + ": cannot read", path, errno);
  std::string s(max, '\0');
  std::size_t n = 0;
  while (n < max) {
    const ssize_t r = ::read(fd, s.data() + n, max - n);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) break;
    n += static_cast<std::size_t>(r);
  }
  ::close(fd);
  s.resize(n);
  return s;
}

mode_t file_mode() {
  const mode_t mask = ::umask(0);
  ::umask(mask);
  return 0666 & ~mask;
}

// Writes content to a new temporary file beside path and returns its name; leaves nothing behind
// when the write fails.
fs::path write_temporary(const fs::path& path, const std::string& content, const std::string& what) {
  std::string name = (path.parent_path() / ("." + path.filename().string() + ".mbsgen-XXXXXX.tmp")).string();
  const int fd = ::mkstemps(name.data(), 4);
  if (fd < 0) throw system_error(what + ": cannot create a temporary file for", path, errno);
  int error = 0;
  for (std::size_t n = 0; n < content.size() && !error;) {
    const ssize_t w = ::write(fd, content.data() + n, content.size() - n);
    if (w < 0 && errno == EINTR) continue;
    if (w < 0) error = errno;
    else n += static_cast<std::size_t>(w);
  }
  if (!error && ::fchmod(fd, file_mode()) != 0) error = errno;
  if (::close(fd) != 0 && !error) error = errno;
  if (error) {
    ::unlink(name.c_str());
    throw system_error(what + ": cannot write", path, error);
  }
  return name;
}

}  // namespace

void refuse_special_file(const fs::path& path, const std::string& what) {
  (void)exists_regular(path, what);
}

void refuse_non_directory(const fs::path& path, const std::string& what) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) return;
    throw system_error(what + ": cannot inspect", path, errno);
  }
  if (!S_ISDIR(st.st_mode))
    throw Error(what + ": " + path.string() + ": it is " + (S_ISREG(st.st_mode) ? "a regular file" : kind_of(st.st_mode)) +
                ", not a directory");
}

void refuse_foreign_files(const std::vector<fs::path>& paths, const std::string& marker, const std::string& what) {
  for (const auto& p : paths)
    if (exists_regular(p, what) && head_of(p, 400, what).find(marker) == std::string::npos)
      throw Error(what + ": refusing to overwrite " + p.string() +
                  ": it exists and was not written by mbsgen (move it, or choose another directory); "
                  "nothing was written");
}

void write_all_or_nothing(const std::vector<OutputFile>& files, const std::string& marker,
                          const std::string& what) {
  std::vector<fs::path> paths;
  for (const auto& f : files) paths.push_back(f.path);
  refuse_foreign_files(paths, marker, what);
  std::vector<fs::path> temporaries;
  auto remove_from = [&temporaries](std::size_t first) {
    for (std::size_t i = first; i < temporaries.size(); ++i) ::unlink(temporaries[i].c_str());
  };
  try {
    for (const auto& f : files) temporaries.push_back(write_temporary(f.path, f.content, what));
  } catch (const Error& e) {
    remove_from(0);
    throw Error(std::string(e.what()) + " (nothing was written)");
  }
  for (std::size_t i = 0; i < files.size(); ++i)
    if (::rename(temporaries[i].c_str(), files[i].path.c_str()) != 0) {
      const int error = errno;
      remove_from(i);
      throw system_error(what + ": cannot replace", files[i].path, error);
    }
}

}  // namespace mbsgen::cli
