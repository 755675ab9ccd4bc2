#include "codegen/child_task.hpp"

#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <exception>
#include <new>

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
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fd);
    return nullptr;
  }
  if (pid == 0) {
    // The child: ends with its parent (which may be killed before it asks for the result), and
    // exits with status 0 only with the whole result written.
    if (::prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || ::getppid() != parent) ::_exit(1);
    int status = 1;
    try {
      if (write_all(fd, work())) status = 0;
    } catch (...) {
    }
    ::_exit(status);
  }
  return std::unique_ptr<ChildTask>(new ChildTask(pid, fd));
}

bool ChildTask::reap() {
  if (reaped_) return false;
  reaped_ = true;
  int status = 0;
  pid_t r = 0;
  while ((r = ::waitpid(pid_, &status, 0)) < 0 && errno == EINTR) {
  }
  // Anything but our child's own normal end is a failure (ECHILD where SIGCHLD is ignored, or
  // where someone else's waitpid(-1) reaped it).
  return r == pid_ && WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

std::optional<std::string> ChildTask::result() {
  if (reaped_) return std::nullopt;
  const bool ok = reap();
  std::optional<std::string> r;
  try {
    if (ok) r = read_all(fd_);
  } catch (const std::bad_alloc&) {
    r.reset();
  }
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
