// Kills during writes: `plan` into an OUT that holds a complete earlier plan, stopped
// at several moments. The contract: OUT is then the old complete output or the new one, never a
// mix (hidden `.scanplan-*` entries of the killed run aside); SIGINT exits 130 and SIGTERM 143
// leaving OUT as it was and nothing `.scanplan-*` behind; after a SIGKILL the next run cleans up
// (no `.scanplan-staging*` in OUT or in its parent). The cases that today's output code does not
// meet yet are expected failures (kKnownToFail), reported as XFAIL rather than failed.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <iostream>
#include <map>
#include <set>
#include <string>
#include <thread>

#include "tests/robustness/runner.h"

namespace scanplan::robustness {
namespace {

// Moments that break the contract today; remove a name when its test passes (XPASS in the log).
const std::set<std::string> kKnownToFail = {};

// The new run differs from the old one in every file (a ring 5 mm higher: another path, maps,
// trajectory, programs, cloud and report).
const std::vector<std::string> kNewSets = {"scan.paths[0].height_mm=40"};

// A run's hidden entries: `.scanplan-*` inside OUT (older versions), `.NAME.scanplan-*` beside it.
bool hidden(const std::string& relative) {
  return relative.find(".scanplan-") != std::string::npos && relative.front() == '.';
}

// OUT without the hidden entries of a run (its lock, a killed run's staging folder).
Snapshot visible(const fs::path& out) {
  Snapshot snap = snapshot(out);
  std::erase_if(snap, [](const auto& entry) { return hidden(entry.first); });
  return snap;
}

std::vector<std::string> leftovers(const fs::path& dir) {
  std::vector<std::string> found;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (hidden(name)) found.push_back(e.path().string());
  }
  return found;
}

class Publishing : public ::testing::Test {
 protected:
  void SetUp() override {
    name_ = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    dir_ = fs::temp_directory_path() /
           ("scanplan_publishing_" + std::to_string(::getpid()) + "_" + name_);
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    old_ = snapshot(planFixture());
    new_ = snapshot(planFixture("plan_new", kNewSets));
    for (const auto& [file, hash] : old_) {
      if (new_.count(file) && new_.at(file) == hash) same_.insert(file);  // "." and folders too
    }
    fs::copy(planFixture(), out(), fs::copy_options::recursive);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
    fs::remove(dir_.string() + ".stdout", ec);
    fs::remove(dir_.string() + ".stderr", ec);
  }
  fs::path out() const { return dir_ / "out"; }
  std::vector<std::string> newRun() const {
    std::vector<std::string> args{"plan", (fixtureDir() / "light.yaml").string(), "-o", "out",
                                  "-q"};
    for (const std::string& s : kNewSets) args.insert(args.end(), {"--set", s});
    return args;
  }

  // "" when OUT is the old or the new complete output; else what it is.
  std::string oldOrNew() const {
    const Snapshot now = visible(out());
    if (now == old_) return "";
    // The new output's listing with no file of the old one left (report.json holds timings, so
    // the new bytes are not known in advance; files the two runs share count as either).
    bool all_new = now.size() == new_.size();
    for (const auto& [file, hash] : now) {
      const bool old_file = old_.count(file) && old_.at(file) == hash && !same_.count(file);
      all_new = all_new && new_.count(file) && !old_file;
    }
    if (all_new) return "";
    return "OUT is neither the old nor the new output; against the old:\n" +
           describeDifference(old_, now) + "against the new:\n" + describeDifference(new_, now);
  }
  void check(bool ok, const std::string& what) {
    if (ok) return;
    if (kKnownToFail.count(name_)) {
      std::cout << "XFAIL Publishing." << name_ << ": " << what << "\n";
      xfailed_ = true;
      return;
    }
    ADD_FAILURE() << what;
  }
  void reportXpass() const {
    if (kKnownToFail.count(name_) && !xfailed_) std::cout << "XPASS Publishing." << name_ << "\n";
  }

  // Kills the run (SIGKILL) once `ready` holds (or it ended), then checks old-or-new, then that
  // the next run completes and cleans up.
  template <class Ready>
  void killWhen(Ready ready) {
    const pid_t pid = spawnScanplan(newRun(), dir_);
    int status = 0;
    while (::waitpid(pid, &status, WNOHANG) == 0) {
      if (ready()) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        break;
      }
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    const std::string state = oldOrNew();
    check(state.empty(), "after SIGKILL: " + state);
    nextRunCleansUp();
  }

  void nextRunCleansUp() {
    const Outcome next = runScanplan(newRun(), dir_);
    check(next.exit_code == 0,
          "the next run: exit " + std::to_string(next.exit_code) + ": " + next.err);
    check(visible(out()) != old_ && oldOrNew().empty(),
          "the next run did not publish the new output: " + oldOrNew());
    for (const auto& dir : {dir_, out()}) {
      const auto left = leftovers(dir);
      check(left.empty(), "after the next run, left behind: " + (left.empty() ? "" : left.front()));
    }
  }

  // Sends `signal` once the run stages its files; checks the exit code and that nothing changed.
  void signalWhileStaging(int signal, int code) {
    const pid_t pid = spawnScanplan(newRun(), dir_);
    while (!staging() && running(pid)) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    ::kill(pid, signal);
    const Outcome run = waitScanplan(pid, dir_);
    const std::string name = signal == SIGINT ? "SIGINT" : "SIGTERM";
    check(run.signal == 0 && run.exit_code == code, name + ": exit " +
                                                        std::to_string(run.exit_code) +
                                                        ", signal " + std::to_string(run.signal));
    check(visible(out()) == old_,
          name + " changed OUT:\n" + describeDifference(old_, visible(out())));
    for (const auto& dir : {dir_, out()}) {
      const auto left = leftovers(dir);
      check(left.empty(), name + " left behind: " + (left.empty() ? "" : left.front()));
    }
  }

  static bool running(pid_t pid) {
    siginfo_t info{};
    return ::waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOHANG | WNOWAIT) == 0 &&
           info.si_pid == 0;
  }

  // The inode of every file at OUT's top: a rename into place changes one.
  std::map<std::string, ino_t> topInodes() const {
    std::map<std::string, ino_t> inodes;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(out(), ec)) {
      struct stat st {};
      if (!hidden(e.path().filename().string()) && ::lstat(e.path().c_str(), &st) == 0) {
        inodes[e.path().filename().string()] = st.st_ino;
      }
    }
    return inodes;
  }

  bool staging() const {
    for (const auto& dir : {dir_, out()}) {
      for (const std::string& entry : leftovers(dir)) {
        if (entry.find(".scanplan-staging") != std::string::npos) return true;
      }
    }
    return false;
  }

  std::string name_;
  fs::path dir_;
  Snapshot old_, new_;
  std::set<std::string> same_;
  bool xfailed_ = false;
};

TEST(Fixture, Make) {
  EXPECT_TRUE(fs::exists(planFixture() / "report.json"));
  EXPECT_TRUE(fs::exists(planFixture("plan_new", kNewSets) / "report.json"));
}

TEST_F(Publishing, SigkillWhileComputing) {
  for (const double seconds : {0.2, 0.5, 1.0, 2.0}) {
    const auto start = std::chrono::steady_clock::now();
    killWhen([&] {
      return std::chrono::steady_clock::now() - start > std::chrono::duration<double>(seconds);
    });
  }
  reportXpass();
}

TEST_F(Publishing, SigkillWhileStaging) {
  killWhen([this] { return staging(); });
  reportXpass();
}

// Killed as soon as a file of OUT is another file (a rename put a new one there): while the new
// output is being moved into place.
TEST_F(Publishing, SigkillWhilePublishing) {
  const auto inodes = topInodes();
  killWhen([&] { return topInodes() != inodes; });
  reportXpass();
}

// SIGINT / SIGTERM while the run writes: exit 130 / 143, OUT as it was, nothing left behind.
TEST_F(Publishing, Sigint) {
  signalWhileStaging(SIGINT, 130);
  reportXpass();
}

TEST_F(Publishing, Sigterm) {
  signalWhileStaging(SIGTERM, 143);
  reportXpass();
}

}  // namespace
}  // namespace scanplan::robustness
