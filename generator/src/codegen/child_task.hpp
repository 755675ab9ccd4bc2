// Work done in a child process while the parent goes on (internal to the generator; POSIX).
//
// GiNaC is not thread-safe (its expressions share nodes with unsynchronised reference counts), so
// the generator cannot give a second core a share of its expressions in a thread. A child process
// made by fork() has its own copy of them: it computes from the parent's state at the fork and
// returns a string. emit_ahead (emit.hpp) emits the kernels that need only the derivation this
// way while the parent linearizes.
//
// The result travels through an anonymous memory file (memfd_create): nothing is created in the
// file system, and the child never waits for the parent to read, as it would on a full pipe.
#pragma once

#include <sys/types.h>

#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace mbsgen::detail {

class ChildTask {
 public:
  /// Runs work() in a child process, started at once; nullptr when no child can be started
  /// (fork or memfd_create failed): the caller then does the work itself. The child calls no
  /// destructor and no exit handler of the parent's (it ends with _exit), and is killed when
  /// the parent ends. In a process with other threads only the caller's runs in the child:
  /// work() must not need a lock another thread may hold at the fork (glibc resets its stdio and
  /// malloc locks in the child; nothing else's).
  static std::unique_ptr<ChildTask> start(const std::function<std::string()>& work);

  ChildTask(const ChildTask&) = delete;
  ChildTask& operator=(const ChildTask&) = delete;
  /// Kills and reaps a child whose result was not asked for.
  ~ChildTask();

  /// Waits for the child to end (without a time limit): work()'s result, or nothing when it
  /// threw, was killed, could not write its result or was reaped by someone else. Once only
  /// (later calls give nothing).
  std::optional<std::string> result();

 private:
  ChildTask(pid_t pid, int fd) : pid_(pid), fd_(fd) {}
  bool reap();  // true: the child ended with status 0

  pid_t pid_;
  int fd_;
  bool reaped_ = false;
};

}  // namespace mbsgen::detail
