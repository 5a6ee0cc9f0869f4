// The robustness catalogue: every case of cases.h run through the scanplan binary
// under a 4 GB address-space limit and a 20 s watchdog. A case passes when scanplan was not
// killed by a signal or the watchdog, never printed "internal error", exited with one of the
// case's codes, named the file (and key) in its error, and left OUT as it was when it failed.
// ctest runs the catalogue in shards (GTEST_TOTAL_SHARDS); tests/robustness/README.md.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cstdlib>
#include <iostream>
#include <map>
#include <set>
#include <string>
#include <system_error>
#include <vector>

#include "tests/robustness/builders.h"
#include "tests/robustness/cases.h"
#include "tests/robustness/runner.h"

namespace scanplan::robustness {
namespace {

// An error message that echoes a whole hostile line or file is a finding too.
constexpr std::size_t kMaxErrorBytes = 16 * 1024;

fs::path scratchRootPath() {
  return fs::temp_directory_path() / ("scanplan_robustness_" + std::to_string(::getpid()));
}

fs::path scratchRoot() {
  static const fs::path root = [] {
    const fs::path dir = scratchRootPath();
    fs::create_directories(dir);
    fs::permissions(dir, fs::perms::all & ~fs::perms::group_write & ~fs::perms::others_write);
    return dir;
  }();
  return root;
}

// The scratch root goes when the run ends, once its cases are gone (with
// SCANPLAN_ROBUSTNESS_KEEP they stay, and so does the root).
class ScratchRootRemoval : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ec;
    fs::remove(scratchRootPath(), ec);  // only when empty
  }
};
[[maybe_unused]] const ::testing::Environment* const kScratchRootRemoval =
    ::testing::AddGlobalTestEnvironment(new ScratchRootRemoval);

// An earlier run's OUT: a report, a trajectory, a program and a file of the user's.
void makeExistingOut(const fs::path& out, bool read_only) {
  fs::create_directories(out / "programs");
  writeText(out / "report.json", "{\"status\": \"planned\"}\n");
  writeText(out / "trajectory.csv", "t_s,table_deg\n0,0\n");
  writeText(out / "programs" / "scan.v2", ".PROGRAM scan()\n.END\n");
  writeText(out / "notes of mine.txt", "keep\n");
  if (!read_only) return;
  for (const fs::path& dir : {out / "programs", out}) {
    fs::permissions(dir, fs::perms::owner_write | fs::perms::group_write | fs::perms::others_write,
                    fs::perm_options::remove);
  }
}

// Read-only folders of a case made writable again, so that it can be removed.
void removeCase(const fs::path& dir) {
  std::error_code ec;
  for (const auto& e : fs::recursive_directory_iterator(dir, ec)) {
    if (e.is_directory(ec) && !e.is_symlink(ec))
      fs::permissions(e.path(), fs::perms::owner_all, fs::perm_options::add, ec);
  }
  fs::permissions(dir, fs::perms::owner_all, fs::perm_options::add, ec);
  fs::remove_all(dir, ec);
  fs::remove(dir.string() + ".stdout", ec);
  fs::remove(dir.string() + ".stderr", ec);
}

std::vector<std::string> expandArgs(const std::vector<std::string>& args) {
  std::vector<std::string> expanded;
  for (const std::string& a : args) expanded.push_back(a.rfind("@", 0) == 0 ? expand(a) : a);
  return expanded;
}

std::string joined(const std::vector<std::string>& words) {
  std::string text;
  for (const std::string& w : words) text += (text.empty() ? "" : " ") + w.substr(0, 120);
  return text;
}

bool allowed(const Case& c, int code) {
  for (int e : c.exits)
    if (e == code) return true;
  return false;
}

// What went wrong with a run of `c`; empty when nothing did.
std::vector<std::string> judge(const Case& c,
                               const Outcome& run,
                               const Snapshot& before,
                               const Snapshot& after,
                               bool out_exists) {
  std::vector<std::string> problems;
  if (run.timed_out) problems.push_back("timed out after " + std::to_string(kTimeoutS) + " s");
  if (run.signal != 0) problems.push_back("killed by signal " + std::to_string(run.signal));
  if (!run.timed_out && run.signal == 0 && !allowed(c, run.exit_code)) {
    problems.push_back("exit code " + std::to_string(run.exit_code));
  }
  if ((run.out + run.err).find("internal error") != std::string::npos)
    problems.push_back("internal error");
  if (run.err.size() > kMaxErrorBytes)
    problems.push_back("stderr of " + std::to_string(run.err.size()) + " bytes");
  // 0 and 3 are finished runs (3: no plan, which may replace an earlier run's files).
  if (run.exit_code == 0 || run.exit_code == 3) return problems;
  for (const std::string& name : c.names) {
    if (run.err.find(name) == std::string::npos)
      problems.push_back("stderr does not name '" + name.substr(0, 60) + "'");
  }
  if (c.out == OutState::kExisting && before != after) {
    problems.push_back("OUT changed:\n" + describeDifference(before, after));
  }
  if (c.out == OutState::kAbsent && out_exists) problems.push_back("OUT was created");
  return problems;
}

void report(const Case& c, const Outcome& run, const std::vector<std::string>& problems) {
  std::string text;
  for (const std::string& p : problems) text += "  " + p + "\n";
  const std::string what = "[" + c.name + "] scanplan " + joined(c.args) + "\n" + text + "exit " +
                           std::to_string(run.exit_code) + ", stderr:\n" + run.err.substr(0, 2000);
  if (problems.empty()) {
    if (!c.xfail.empty()) std::cout << "XPASS " << c.name << " (" << c.xfail << ")\n";
    return;
  }
  if (!c.xfail.empty()) {
    std::cout << "XFAIL " << c.name << " (" << c.xfail << "): " << what << "\n";
    return;
  }
  ADD_FAILURE() << what;
}

}  // namespace

// gtest prints a failing case by its name.
void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

namespace {

class Catalogue : public ::testing::TestWithParam<Case> {};

TEST_P(Catalogue, Case) {
  const Case& c = GetParam();
  if (c.needs_shared && !fs::exists(SCANPLAN_SHARED_DATA_DIR)) GTEST_SKIP() << "no ../shared/data";
  const fs::path dir = scratchRoot() / c.name;
  removeCase(dir);
  fs::create_directories(dir);
  fs::permissions(dir, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                           fs::perms::others_read | fs::perms::others_exec);
  for (const InputFile& f : c.files) {
    fs::create_directories((dir / f.name).parent_path());
    f.make(dir / f.name);
  }
  const fs::path out = dir / "out";
  if (c.out == OutState::kExisting) makeExistingOut(out, c.as_nobody);
  const Snapshot before = snapshot(out);
  std::vector<std::string> kept_before;
  for (const std::string& k : c.kept) kept_before.push_back(readText(dir / k));
  const Outcome run = runScanplan(expandArgs(c.args), dir, c);
  std::error_code ec;
  std::vector<std::string> problems =
      judge(c, run, before, snapshot(out), fs::exists(fs::symlink_status(out, ec)));
  for (std::size_t i = 0; i < c.kept.size(); ++i) {
    if (!fs::is_regular_file(dir / c.kept[i]) || readText(dir / c.kept[i]) != kept_before[i])
      problems.push_back("the input " + c.kept[i] + " was changed or removed");
  }
  report(c, run, problems);
  if (!std::getenv("SCANPLAN_ROBUSTNESS_KEEP")) removeCase(dir);
}

// At least 200 cases; names must be unique (they name the scratch folders).
TEST(CatalogueSize, AtLeast200CasesWithUniqueNames) {
  std::map<std::string, int> per_group;
  std::set<std::string> names;
  const std::vector<Case> cases = allCases();
  for (const Case& c : cases) {
    ++per_group[c.group];
    EXPECT_TRUE(names.insert(c.name).second) << "two cases named " << c.name;
  }
  for (const auto& [group, count] : per_group) std::cout << count << "\t" << group << "\n";
  EXPECT_GE(cases.size(), 200u);
}

INSTANTIATE_TEST_SUITE_P(Robustness,
                         Catalogue,
                         ::testing::ValuesIn(allCases()),
                         [](const ::testing::TestParamInfo<Case>& param) {
                           std::string name = param.param.name;
                           for (char& ch : name) {
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           }
                           return name;
                         });

}  // namespace
}  // namespace scanplan::robustness
