// Programs run as a user runs them, for the tests of the mbsgen command (hostile_models_test.cpp,
// cache_cli_test.cpp): no shell, output captured, in a directory of their own.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

fs::path temporary_directory() {
  std::string t = (fs::temp_directory_path() / "mbsgen-hostile-XXXXXX").string();
  if (!::mkdtemp(t.data())) throw std::runtime_error("mkdtemp failed");
  return t;
}

struct Result {
  int status = -1;
  std::string output;  // standard output and error
};

// Starts args (no shell) in cwd with extra environment variables, its standard output and error
// going to log; its process id.
pid_t start(const std::vector<std::string>& args, const fs::path& cwd, const fs::path& log,
            const std::map<std::string, std::string>& env = {}) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (::chdir(cwd.c_str()) != 0) ::_exit(126);
    FILE* f = std::freopen(log.c_str(), "w", stdout);
    if (!f || ::dup2(STDOUT_FILENO, STDERR_FILENO) < 0) ::_exit(126);
    for (const auto& [k, v] : env) ::setenv(k.c_str(), v.c_str(), 1);
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execvp(argv[0], argv.data());
    ::_exit(127);
  }
  return pid;
}

// Waits for a process start() started; its status and output (the log, removed).
Result finish(pid_t pid, const fs::path& log) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  Result r;
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.output = slurp(log);
  fs::remove(log);
  return r;
}

// Runs args (no shell) in cwd with extra environment variables; captures its output.
Result run(const std::vector<std::string>& args, const fs::path& cwd,
           const std::map<std::string, std::string>& env = {}) {
  const fs::path log = cwd / ".run-output";
  return finish(start(args, cwd, log, env), log);
}

}  // namespace
