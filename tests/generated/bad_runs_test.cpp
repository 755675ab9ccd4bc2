// The command-line bad-input corpus (issue 39): every case of tests/data/bad_runs/*.cases is run
// without a shell, with a 30 s limit (a command that blocks is a failure, not a hang of the suite),
// and must end with its exit code and print its message on stderr. Format (README of the folder):
//   # why (comment lines)
//   fifo: NAME            (optional) a FIFO @TMP@/NAME, with no writer
//   file: NAME            (optional) a file @TMP@/NAME whose lines follow, indented by two spaces
//   $ COMMAND ARGS...     the first word a shipped solver `<id>-solve`, `mbsgen` or `mbsgen-linear`
//   timeout: S           (optional) seconds instead of 30, for a case that compiles a solver
//   exit N
//   stderr: TEXT          a substring of the standard error
// @DATA@ is tests/data, @MODELS@ models/, @TMP@ a fresh directory of the case (also in stderr:).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace {

namespace fs = std::filesystem;

struct Case {
  std::string file;
  int line = 0;
  std::vector<std::string> argv;
  std::vector<std::string> fifos;
  std::vector<std::pair<std::string, std::string>> files;
  int exit_code = -1;
  std::string stderr_text;
  int timeout_s = 30;
};

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t p = 0; (p = s.find(from, p)) != std::string::npos; p += to.size()) s.replace(p, from.size(), to);
  return s;
}

std::vector<Case> read_cases(const fs::path& path) {
  std::vector<Case> out;
  std::ifstream in(path);
  std::string line;
  Case c;
  bool open = false;
  std::string* file_body = nullptr;
  auto finish = [&] {
    if (open) out.push_back(c);
    c = Case{};
    open = false;
    file_body = nullptr;
  };
  for (int number = 1; std::getline(in, line); ++number) {
    if (file_body && line.rfind("  ", 0) == 0) {
      *file_body += line.substr(2) + "\n";
      continue;
    }
    file_body = nullptr;
    if (line.empty()) {
      finish();
      continue;
    }
    if (line[0] == '#') continue;
    c.file = path.filename().string();
    if (!open) c.line = number;
    open = true;
    if (line.rfind("$ ", 0) == 0) {
      std::istringstream words(line.substr(2));
      for (std::string w; words >> w;) c.argv.push_back(w);
    } else if (line.rfind("exit ", 0) == 0) {
      c.exit_code = std::stoi(line.substr(5));
    } else if (line.rfind("stderr: ", 0) == 0) {
      c.stderr_text = line.substr(8);
    } else if (line.rfind("timeout: ", 0) == 0) {  // a case that compiles a solver
      c.timeout_s = std::stoi(line.substr(9));
    } else if (line.rfind("fifo: ", 0) == 0) {
      c.fifos.push_back(line.substr(6));
    } else if (line.rfind("file: ", 0) == 0) {
      c.files.emplace_back(line.substr(6), "");
      file_body = &c.files.back().second;
    } else {
      ADD_FAILURE() << path << ":" << number << ": unknown line '" << line << "'";
    }
  }
  finish();
  return out;
}

std::string program(const std::string& name) {
  if (name == "mbsgen") return std::string(MBSGEN_TOOL_DIR) + "/mbsgen";
  if (name == "mbsgen-linear") return MBSGEN_LINEAR_EXE;
  if (name == "mbsgen-tape") return MBSGEN_TAPE_EXE;
  return std::string(MBSGEN_GENERATED_BIN_DIR) + "/" + name;
}

struct Result {
  int status = -1;
  bool timed_out = false;
  std::string err;
};

Result run(std::vector<std::string> argv, const fs::path& dir, int timeout_s) {
  const fs::path err_file = dir / ".stderr";
  argv[0] = program(argv[0]);
  std::vector<char*> args;
  for (auto& a : argv) args.push_back(a.data());
  args.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, STDERR_FILENO, err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);  // kill the whole group on a timeout
  posix_spawnattr_setpgroup(&attr, 0);
  pid_t pid = 0;
  Result r;
  const int rc = posix_spawn(&pid, args[0], &fa, &attr, args.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  posix_spawnattr_destroy(&attr);
  if (rc != 0) {
    r.err = "cannot start " + argv[0];
    return r;
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(timeout_s);
  int status = 0;
  for (;;) {
    const pid_t w = ::waitpid(pid, &status, WNOHANG);
    if (w == pid) break;
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(-pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      r.timed_out = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  std::ifstream e(err_file);
  std::ostringstream s;
  s << e.rdbuf();
  r.err = s.str();
  return r;
}

TEST(BadRuns, EveryCaseIsRefusedWithItsMessage) {
  const fs::path data = fs::path(MBSGEN_SOURCE_DIR) / "tests" / "data";
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(data / "bad_runs"))
    if (e.path().extension() == ".cases") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  ASSERT_FALSE(files.empty());
  const fs::path root = fs::temp_directory_path() / ("mbsgen_bad_runs_" + std::to_string(::getpid()));
  int count = 0;
  for (const fs::path& f : files)
    for (Case c : read_cases(f)) {
      ++count;
      const std::string where = c.file + ":" + std::to_string(c.line);
      ASSERT_FALSE(c.argv.empty()) << where << ": no command";
      ASSERT_GE(c.exit_code, 0) << where << ": no exit line";
      const fs::path tmp = root / std::to_string(count);
      fs::create_directories(tmp);
      for (const auto& name : c.fifos) ASSERT_EQ(::mkfifo((tmp / name).c_str(), 0600), 0) << where;
      for (const auto& [name, body] : c.files) std::ofstream(tmp / name) << body;
      for (auto& a : c.argv) {
        a = replace_all(a, "@DATA@", data.string());
        a = replace_all(a, "@MODELS@", (fs::path(MBSGEN_SOURCE_DIR) / "models").string());
        a = replace_all(a, "@TMP@", tmp.string());
      }
      c.stderr_text = replace_all(c.stderr_text, "@TMP@", tmp.string());  // a message may name the path
      const Result r = run(c.argv, tmp, c.timeout_s);
      EXPECT_FALSE(r.timed_out) << where << ": did not return within " << c.timeout_s << " s";
      EXPECT_EQ(r.status, c.exit_code) << where << "\n" << r.err;
      EXPECT_NE(r.err.find(c.stderr_text), std::string::npos)
          << where << ": expected on stderr: " << c.stderr_text << "\ngot: " << r.err;
    }
  fs::remove_all(root);
  RecordProperty("cases", count);
  std::cout << "[ bad_runs ] " << count << " cases\n";
}

}  // namespace
