// Reading a file a user named, without ever blocking: FIFOs, devices, sockets and directories
// are refused before a byte is read (issue 39 §2: `--M FIFO` and `--input F=table:FIFO` waited
// forever; `/dev/zero` as a matrix ran out of memory). Private to the runtime's sources.
#pragma once

#include <cerrno>
#include <cstddef>
#include <cstring>
#include <string>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace mbsgen::detail {

/// "a directory", "a FIFO (named pipe)", "a character device", … for a file type.
inline const char* file_kind(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

/// The contents of the regular file `path`, at most max_bytes. Opened non-blocking (a FIFO
/// without a writer cannot stall the open) and checked with fstat on the same descriptor (no
/// race between check and read); anything but a regular file, or a larger one, throws E with
/// the path first: "<path>: is a FIFO (named pipe), not a regular file".
template <class E>
std::string read_regular_file(const std::string& path, std::size_t max_bytes) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) throw E(path + ": cannot open: " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    const int err = errno;
    const bool stat_failed = !S_ISREG(st.st_mode) && st.st_mode == 0;
    ::close(fd);
    if (stat_failed) throw E(path + ": cannot inspect: " + std::strerror(err));
    throw E(path + ": is " + file_kind(st.st_mode) + ", not a regular file" +
            (S_ISDIR(st.st_mode) ? "" : " (refused: reading it could block or never end)"));
  }
  if (static_cast<unsigned long long>(st.st_size) > max_bytes) {
    ::close(fd);
    throw E(path + ": is " + std::to_string(st.st_size) + " bytes; the limit for this file is " +
            std::to_string(max_bytes) + " bytes");
  }
  std::string text(static_cast<std::size_t>(st.st_size), '\0');
  std::size_t n = 0;
  for (;;) {
    if (n == text.size()) {
      if (text.size() >= max_bytes) break;
      text.resize(std::min(max_bytes, text.size() + 65536));  // the file grew while read
    }
    const ssize_t r = ::read(fd, text.data() + n, text.size() - n);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) {
      const int err = errno;
      ::close(fd);
      throw E(path + ": cannot read: " + std::strerror(err));
    }
    if (r == 0) break;
    n += static_cast<std::size_t>(r);
  }
  ::close(fd);
  text.resize(n);
  return text;
}

}  // namespace mbsgen::detail
