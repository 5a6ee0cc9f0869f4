#pragma once
// The robustness catalogue's machinery (tests/robustness/README.md): a case is a command line,
// the input files it needs and what it expects; the runner makes the files in a scratch folder,
// runs scanplan there under an address-space limit and a watchdog, and judges the outcome.

#include <sys/types.h>

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace scanplan::robustness {

namespace fs = std::filesystem;

/// What the OUT folder of a case (the argument "out" of its command line) holds before the run.
enum class OutState {
  kNone,      // the command writes no OUT
  kAbsent,    // OUT does not exist: a failing run must not create it
  kExisting,  // OUT holds an earlier run's files: a failing run must leave them byte-identical
};

/// One input of a case: `make` creates `name` (relative to the case folder).
struct InputFile {
  std::string name;
  std::function<void(const fs::path& file)> make;
};

struct Case {
  std::string name;               // unique; letters, digits and '_' (a gtest name)
  std::string group;              // the class it belongs to (README's table of counts)
  std::vector<std::string> args;  // after "scanplan"; @src = the repository, @fix = fixtures
  std::vector<InputFile> files;
  std::vector<int> exits{4};       // the exit codes that pass
  std::vector<std::string> names;  // what stderr must hold when the exit code is not 0
  OutState out = OutState::kNone;
  bool as_nobody = false;         // run as uid 65534 when root (read-only folders bind root not)
  long file_size_limit = 0;       // RLIMIT_FSIZE in bytes (a full disk), 0: none
  bool needs_shared = false;      // skipped without ../shared/data
  std::string xfail;              // non-empty: known to fail today, why (reported, not failed)
  std::vector<std::string> kept;  // files that must be byte-identical after the run
};

/// How a run ended.
struct Outcome {
  int exit_code = -1;  // when it exited
  int signal = 0;      // when a signal ended it
  bool timed_out = false;
  std::string out;
  std::string err;
};

/// Limits of every run (`ulimit -v 4194304` and `timeout 20`).
inline constexpr long kAddressSpaceBytes = 4L << 30;
inline constexpr int kTimeoutS = 20;

/// Runs the scanplan binary with `args` in `cwd` under the limits; stdout and stderr go through
/// files in `cwd`.
Outcome runScanplan(const std::vector<std::string>& args,
                    const fs::path& cwd,
                    const Case& limits = {});

/// Starts scanplan in the background (no limits besides the address space); its pid.
pid_t spawnScanplan(const std::vector<std::string>& args, const fs::path& cwd);

/// Waits for `pid` with the watchdog of runScanplan; reads stdout/stderr from `cwd`.
Outcome waitScanplan(pid_t pid, const fs::path& cwd);

/// A folder's listing (relative paths, folders with a trailing '/') with each file's bytes
/// hashed: two snapshots are equal when nothing was added, removed or changed.
using Snapshot = std::map<std::string, std::string>;
Snapshot snapshot(const fs::path& dir);
std::string describeDifference(const Snapshot& before, const Snapshot& after);

/// The fixtures the cases share, made once under a lock in the build tree (again when the
/// scanplan binary is newer): fix/light.yaml, the demo with two rings at 0.2 s (a plan in a few
/// seconds), robot and mesh by absolute path; fix/full.yaml, demo_rings with an obstacle, a
/// waypoint path and scan.auto; fix/resolved.yaml, `job show` of full.yaml (every key written).
fs::path fixtureDir();
/// fix/NAME/: a complete `plan` of light.yaml with `--set` overrides `sets` (fix/plan: none; its
/// trajectory.csv, programs/scan.v2 are the cases' trajectories).
fs::path planFixture(const std::string& name = "plan", const std::vector<std::string>& sets = {});

std::string readText(const fs::path& file);
void writeText(const fs::path& file, const std::string& text);

}  // namespace scanplan::robustness
