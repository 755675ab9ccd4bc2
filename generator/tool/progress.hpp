// Progress of a long `mbsgen check`, `info`, `generate` or `run` on a terminal (issues 14 §4, 17 §1): after
// kQuietSeconds, one line on stderr names the stage and the elapsed time, rewritten in place
// twice a second and erased at the end. Nothing is written when stderr is not a terminal
// (pipes, files, ctest), so that captured output and messages stay as they are.
#pragma once

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <string>
#include <thread>

namespace mbsgen::tool {

class Progress {
 public:
  static constexpr double kQuietSeconds = 2.0;  ///< shorter runs print nothing

  /// `command`: "check", "info", "generate" or "run", shown in the line.
  explicit Progress(std::string command) : command_(std::move(command)) {
    if (isatty(STDERR_FILENO) == 1)
      thread_ = std::thread([this] {
        // Termination signals go to the main thread, whose waits they interrupt (run.cpp).
        sigset_t signals;
        sigemptyset(&signals);
        for (int s : {SIGTERM, SIGHUP, SIGINT}) sigaddset(&signals, s);
        pthread_sigmask(SIG_BLOCK, &signals, nullptr);
        run();
      });
  }
  ~Progress() { stop(); }
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  /// The stage now running (a string literal: only its address is kept).
  void stage(const char* name) {
    stage_.store(name);
    detail(std::string());
  }

  /// Shown after the stage, e.g. "3 of 5 files" while compiling.
  void detail(std::string text) {
    std::lock_guard<std::mutex> lock(mutex_);
    detail_ = std::move(text);
  }

  /// f() run while the thread is not writing: a child process forked meanwhile (emit_ahead)
  /// inherits no lock the thread held.
  template <class F>
  auto paused(F f) {
    std::lock_guard<std::mutex> lock(mutex_);
    return f();
  }

  /// Stops the thread and erases the line; call before writing anything else to stderr.
  void stop() {
    if (!thread_.joinable()) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }

 private:
  void run() {
    const auto start = std::chrono::steady_clock::now();
    bool shown = false;
    std::unique_lock<std::mutex> lock(mutex_);
    while (!wake_.wait_for(lock, std::chrono::milliseconds(500), [this] { return done_; })) {
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (s < kQuietSeconds) continue;
      std::fprintf(stderr, "\r\033[Kmbsgen %s: %s%s%s (%.0f s)", command_.c_str(), stage_.load(),
                   detail_.empty() ? "" : ": ", detail_.c_str(), s);
      std::fflush(stderr);
      shown = true;
    }
    if (shown) {
      std::fputs("\r\033[K", stderr);
      std::fflush(stderr);
    }
  }

  std::string command_;
  std::atomic<const char*> stage_{"reading the model"};
  std::mutex mutex_;
  std::string detail_;  // guarded by mutex_
  std::condition_variable wake_;
  bool done_ = false;
  std::thread thread_;
};

}  // namespace mbsgen::tool
