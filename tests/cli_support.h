#pragma once
// Running the `scanplan` executable from tests: a scratch folder per test, stdout, stderr and
// the exit code captured.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

extern char** environ;

namespace scanplan::test {

namespace fs = std::filesystem;

struct Result {
  int exit_code = -1;
  std::string out;
  std::string err;
};

inline std::string readFile(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void writeFile(const fs::path& file, const std::string& text) {
  std::ofstream(file, std::ios::binary | std::ios::trunc) << text;
}

// A scratch folder per test; ctest runs tests as separate processes, possibly in parallel.
class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("scanplan_test_cli_" + std::to_string(::getpid()) + "_" +
                                        info->test_suite_name() + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  /// Starts scanplan with `args` in the background, stdout and stderr going to the two files:
  /// its process id, or -1 (a test failure) when it cannot start.
  static pid_t spawnScanplan(const std::vector<std::string>& args,
                             const fs::path& out_file,
                             const fs::path& err_file) {
    std::vector<std::string> argv_text{SCANPLAN_BINARY};
    argv_text.insert(argv_text.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : argv_text) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
    posix_spawn_file_actions_addopen(&actions, 2, err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
    pid_t pid = 0;
    const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (spawned != 0) {
      ADD_FAILURE() << "cannot start " << argv[0] << ": error " << spawned;
      return -1;
    }
    return pid;
  }

  /// Runs scanplan with `args`, stdout and stderr captured through files in the scratch folder.
  Result scanplan(const std::vector<std::string>& args) const {
    const fs::path out_file = dir_ / "stdout.txt";
    const fs::path err_file = dir_ / "stderr.txt";
    Result run;
    const pid_t pid = spawnScanplan(args, out_file, err_file);
    if (pid < 0) return run;
    int status = 0;
    if (::waitpid(pid, &status, 0) == pid && WIFEXITED(status)) run.exit_code = WEXITSTATUS(status);
    run.out = readFile(out_file);
    run.err = readFile(err_file);
    return run;
  }

  fs::path dir_;
};

inline std::string describe(const Result& run) {
  return "exit " + std::to_string(run.exit_code) + "\n--- stdout\n" + run.out + "--- stderr\n" +
         run.err;
}

inline bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

inline std::vector<fs::path> tmpFiles(const fs::path& dir) {
  std::vector<fs::path> found;
  if (!fs::exists(dir)) return found;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.path().extension() == ".tmp") found.push_back(e.path());
  }
  return found;
}

}  // namespace scanplan::test
