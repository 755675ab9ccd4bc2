#include "child_task.hpp"

#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <exception>

namespace mbsgen::detail {

namespace {

// Writes all of s at the start of fd; false on an error (a full memory limit).
bool write_all(int fd, const std::string& s) {
  std::size_t done = 0;
  while (done < s.size()) {
    const ssize_t n = ::pwrite(fd, s.data() + done, s.size() - done, static_cast<off_t>(done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

std::optional<std::string> read_all(int fd) {
  struct stat st {};
  if (::fstat(fd, &st) != 0 || st.st_size < 0) return std::nullopt;
  std::string s(static_cast<std::size_t>(st.st_size), '\0');
  std::size_t done = 0;
  while (done < s.size()) {
    const ssize_t n = ::pread(fd, s.data() + done, s.size() - done, static_cast<off_t>(done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return std::nullopt;
    done += static_cast<std::size_t>(n);
  }
  return s;
}

}  // namespace

std::unique_ptr<ChildTask> ChildTask::start(const std::function<std::string()>& work) {
  const int fd = ::memfd_create("mbsgen-child-result", MFD_CLOEXEC);
  if (fd < 0) return nullptr;
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fd);
    return nullptr;
  }
  if (pid == 0) {
    // The child: exit status 0 only with the whole result written.
    int status = 1;
    try {
      if (write_all(fd, work())) status = 0;
    } catch (...) {
    }
    ::_exit(status);
  }
  return std::unique_ptr<ChildTask>(new ChildTask(pid, fd));
}

void ChildTask::reap() {
  if (reaped_) return;
  reaped_ = true;
  int status = 0;
  while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
  }
  last_status_ = status;
}

std::optional<std::string> ChildTask::result() {
  if (reaped_) return std::nullopt;
  reap();
  std::optional<std::string> r;
  if (WIFEXITED(last_status_) && WEXITSTATUS(last_status_) == 0) r = read_all(fd_);
  ::close(fd_);
  return r;
}

ChildTask::~ChildTask() {
  if (reaped_) return;
  ::kill(pid_, SIGKILL);
  reap();
  ::close(fd_);
}

}  // namespace mbsgen::detail
