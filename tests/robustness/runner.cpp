#include "tests/robustness/runner.h"

#include <fcntl.h>
#include <grp.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace scanplan::robustness {
namespace {

fs::path stdoutFile(const fs::path& cwd) {
  return cwd.parent_path() / (cwd.filename().string() + ".stdout");
}
fs::path stderrFile(const fs::path& cwd) {
  return cwd.parent_path() / (cwd.filename().string() + ".stderr");
}

// In the child between fork and exec: only async-signal-safe calls, then exec or _exit(127).
[[noreturn]] void execChild(const std::vector<char*>& argv,
                            const fs::path& cwd,
                            const fs::path& out_file,
                            const fs::path& err_file,
                            const Case& limits) {
  ::setpgid(0, 0);
  const int in = ::open("/dev/null", O_RDONLY);
  const int out = ::open(out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const int err = ::open(err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (in < 0 || out < 0 || err < 0 || ::chdir(cwd.c_str()) != 0) ::_exit(127);
  ::dup2(in, 0);
  ::dup2(out, 1);
  ::dup2(err, 2);
  const rlimit as{static_cast<rlim_t>(kAddressSpaceBytes), static_cast<rlim_t>(kAddressSpaceBytes)};
  ::setrlimit(RLIMIT_AS, &as);
  if (limits.file_size_limit > 0) {
    const rlimit fsize{static_cast<rlim_t>(limits.file_size_limit),
                       static_cast<rlim_t>(limits.file_size_limit)};
    ::setrlimit(RLIMIT_FSIZE, &fsize);
    ::signal(SIGXFSZ, SIG_IGN);  // a write past the limit fails with EFBIG, as on a full disk
  }
  if (limits.as_nobody && ::geteuid() == 0) {
    if (::setgroups(0, nullptr) != 0 || ::setgid(65534) != 0 || ::setuid(65534) != 0) ::_exit(127);
  }
  ::execve(argv[0], argv.data(), environ);
  ::_exit(127);
}

}  // namespace

// SCANPLAN_ROBUSTNESS_BINARY, when set, runs the catalogue against another build (README.md).
std::string scanplanBinary() {
  const char* other = std::getenv("SCANPLAN_ROBUSTNESS_BINARY");
  return other && *other ? other : SCANPLAN_BINARY;
}

pid_t startScanplan(const std::vector<std::string>& args, const fs::path& cwd, const Case& limits) {
  std::vector<std::string> text{scanplanBinary()};
  text.insert(text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : text) argv.push_back(a.data());
  argv.push_back(nullptr);
  const fs::path out_file = stdoutFile(cwd);
  const fs::path err_file = stderrFile(cwd);
  const pid_t pid = ::fork();
  if (pid == 0) execChild(argv, cwd, out_file, err_file, limits);
  if (pid < 0) throw std::runtime_error("fork failed");
  ::setpgid(pid, pid);
  return pid;
}

pid_t spawnScanplan(const std::vector<std::string>& args, const fs::path& cwd) {
  return startScanplan(args, cwd, Case{});
}

Outcome waitScanplan(pid_t pid, const fs::path& cwd) {
  Outcome outcome;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(kTimeoutS);
  int status = 0;
  while (::waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      outcome.timed_out = true;
      ::kill(-pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (WIFEXITED(status)) outcome.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) outcome.signal = WTERMSIG(status);
  outcome.out = readText(stdoutFile(cwd));
  outcome.err = readText(stderrFile(cwd));
  return outcome;
}

Outcome runScanplan(const std::vector<std::string>& args, const fs::path& cwd, const Case& limits) {
  return waitScanplan(startScanplan(args, cwd, limits), cwd);
}

std::string readText(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void writeText(const fs::path& file, const std::string& text) {
  std::ofstream(file, std::ios::binary | std::ios::trunc) << text;
}

namespace {

std::string hashOf(const fs::path& file) {
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a 64
  std::ifstream in(file, std::ios::binary);
  char buffer[65536];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
    for (std::streamsize i = 0; i < in.gcount(); ++i) {
      h = (h ^ static_cast<unsigned char>(buffer[i])) * 1099511628211ull;
    }
  }
  return std::to_string(h);
}

}  // namespace

Snapshot snapshot(const fs::path& dir) {
  Snapshot snap;
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(dir, ec))) return snap;
  // Only regular files are read: opening a FIFO would wait for a writer.
  const auto content = [](const fs::path& p) {
    std::error_code error;
    return fs::is_regular_file(fs::symlink_status(p, error)) ? hashOf(p) : std::string("special");
  };
  snap["."] = fs::is_directory(dir, ec) ? "folder" : "file " + content(dir);
  if (!fs::is_directory(dir, ec)) return snap;
  for (const auto& e : fs::recursive_directory_iterator(dir, ec)) {
    const std::string rel = fs::relative(e.path(), dir).string();
    snap[e.is_directory() ? rel + "/" : rel] = e.is_directory() ? "" : content(e.path());
  }
  return snap;
}

std::string describeDifference(const Snapshot& before, const Snapshot& after) {
  std::string text;
  for (const auto& [name, hash] : before) {
    const auto it = after.find(name);
    if (it == after.end())
      text += "  removed " + name + "\n";
    else if (it->second != hash)
      text += "  changed " + name + "\n";
  }
  for (const auto& [name, hash] : after) {
    if (!before.count(name)) text += "  added   " + name + "\n";
  }
  return text;
}

namespace {

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::runtime_error("demo_rings.yaml lacks " + from);
  return text.replace(at, from.size(), to);
}

// demo_rings.yaml with its robot and mesh by absolute path, so that copies work from anywhere.
std::string demoRings() {
  const fs::path data = fs::path(SCANPLAN_SOURCE_DIR) / "data";
  std::string job = readText(data / "jobs/demo_rings.yaml");
  job = replaced(job, "../robots/", (data / "robots").string() + "/");
  return replaced(job, "../parts/", (data / "parts").string() + "/");
}

// fix/light.yaml: lightened as tests/test_support.h's kLightDemo does (two rings, 0.2 s).
std::string lightJob() {
  std::string job = replaced(demoRings(), "dt_s: 0.1", "dt_s: 0.2");
  const auto paths = job.find("  paths:");
  const auto map = job.find("\nmap:");
  return job.replace(paths, map - paths,
                     "  paths:\n"
                     "    - {type: ring, height_mm: 35, tilt_deg: 25, speed_deg_s: 20}\n"
                     "    - {type: ring, height_mm: 105, tilt_deg: 60, speed_deg_s: 20}\n");
}

// fix/full.yaml: demo_rings with one of everything that has numeric keys besides its own: an
// obstacle, a waypoint path, scan.auto. Its `job show` is fix/resolved.yaml.
std::string fullJob() {
  std::string job = replaced(demoRings(), "\nmap:",
                             "    - type: waypoints\n"
                             "      points: [{xyz_mm: [0, 0, 300], rpy_deg: [180, 0, 0]},\n"
                             "               {xyz_mm: [50, 0, 300], rpy_deg: [180, 0, 0]}]\n"
                             "  auto: {}\n"
                             "\nmap:");
  return job +
         "obstacles:\n"
         "  - {name: post, type: cylinder, radius_mm: 20, length_mm: 100, carrier: world,\n"
         "     pose: {xyz_mm: [300, 300, 50], rpy_deg: [0, 0, 0]}}\n";
}

void makeFixtures(const fs::path& dir) {
  const fs::path staging = dir.string() + ".making";
  fs::remove_all(staging);
  fs::create_directories(staging);
  writeText(staging / "light.yaml", lightJob());
  writeText(staging / "full.yaml", fullJob());
  const Outcome show = runScanplan({"job", "show", "full.yaml"}, staging);
  if (show.exit_code != 0) throw std::runtime_error("job show full.yaml failed: " + show.err);
  writeText(staging / "resolved.yaml", show.out);
  fs::remove(staging.string() + ".stdout");
  fs::remove(staging.string() + ".stderr");
  fs::rename(staging, dir);
}

void makePlan(const fs::path& dir, const std::string& name, const std::vector<std::string>& sets) {
  const fs::path staging = dir / (name + ".making");
  fs::remove_all(staging);
  fs::create_directories(staging);
  std::vector<std::string> args{"plan", (dir / "light.yaml").string(), "-o", name, "-q"};
  for (const std::string& s : sets) args.insert(args.end(), {"--set", s});
  const Outcome plan = runScanplan(args, staging);
  if (plan.exit_code != 0) throw std::runtime_error("plan light.yaml failed: " + plan.err);
  fs::rename(staging / name, dir / name);
  fs::remove_all(staging);
}

// Runs `make` under fixture.lock unless `done` exists and is newer than the scanplan binary.
template <class Make>
void once(const fs::path& done, const fs::path& lock_file, Make make) {
  const int lock = ::open(lock_file.c_str(), O_RDWR | O_CREAT, 0644);
  ::flock(lock, LOCK_EX);
  std::error_code ec;
  const bool fresh = fs::exists(done, ec) &&
                     fs::last_write_time(done, ec) > fs::last_write_time(scanplanBinary(), ec);
  if (!fresh) make();
  ::close(lock);
}

}  // namespace

fs::path fixtureDir() {
  static const fs::path fixtures = [] {
    const char* other = std::getenv("SCANPLAN_ROBUSTNESS_BINARY");
    const fs::path dir = fs::path(std::string(SCANPLAN_ROBUSTNESS_FIXTURE_DIR) +
                                  (other && *other ? "_other" : ""));
    fs::create_directories(dir.parent_path());
    once(dir / "resolved.yaml", dir.string() + ".lock", [&dir] {
      fs::remove_all(dir);
      makeFixtures(dir);
    });
    return dir;
  }();
  return fixtures;
}

fs::path planFixture(const std::string& name, const std::vector<std::string>& sets) {
  const fs::path dir = fixtureDir();
  once(dir / name / "report.json", dir.string() + ".lock", [&] {
    fs::remove_all(dir / name);
    makePlan(dir, name, sets);
  });
  return dir / name;
}

}  // namespace scanplan::robustness
