#include "cli/io/output.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string_view>
#include <system_error>

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <fmt/format.h>

#include "kinematics/error.h"

namespace scanplan::cli {
void writeFileAtomically(const std::filesystem::path& file, const std::string& content) {
  std::error_code ec;
  if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path(), ec);
  const std::filesystem::path tmp = file.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << content;
    out.flush();
    if (!out) {
      std::filesystem::remove(tmp, ec);
      throw InputError(fmt::format("{}: cannot write the file", file.string()));
    }
  }
  std::filesystem::rename(tmp, file, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw InputError(fmt::format("{}: cannot move the finished file into place", file.string()));
  }
}

void prepareOutputDir(const std::filesystem::path& dir) {
  std::error_code ec;
  if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec)) {
    throw InputError(
        fmt::format("{}: output folder is an existing file: expected a folder path", dir.string()));
  }
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    throw InputError(
        fmt::format("{}: cannot create the output folder: {}", dir.string(), ec.message()));
  }
}

namespace {

constexpr const char* kLockName = ".scanplan-lock";

bool alive(long pid) {
  return pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH);
}

// The pid a lock file names, or 0 when it names none.
long lockHolder(const std::filesystem::path& lock) {
  std::ifstream in(lock);
  long pid = 0;
  in >> pid;
  return in ? pid : 0;
}

}  // namespace

// Takes OUT's lock: O_EXCL creation of OUT/.scanplan-lock holding our pid. A lock whose process
// is gone is stale: removed and taken. A live holder (another run, or this process) is an
// InputError naming it.
void OutputStage::lock() {
  const std::filesystem::path lock = out_ / kLockName;
  for (int attempt = 0; attempt < 2; ++attempt) {
    const int fd = ::open(lock.c_str(), O_CREAT | O_EXCL | O_WRONLY, 0644);
    if (fd >= 0) {
      const std::string pid = std::to_string(static_cast<long>(::getpid())) + "\n";
      const bool written = ::write(fd, pid.data(), pid.size()) == static_cast<ssize_t>(pid.size());
      ::close(fd);
      if (!written) break;
      locked_ = true;
      return;
    }
    if (errno != EEXIST) break;
    const long holder = lockHolder(lock);
    if (holder > 0 && alive(holder)) {
      throw InputError(fmt::format(
          "{} is in use by pid {} (another scanplan run writing there): wait for it, or choose "
          "another output folder",
          out_.string(), holder));
    }
    std::error_code ignored;
    std::filesystem::remove(lock, ignored);  // stale: its run was killed
  }
  throw InputError(fmt::format("{}: cannot create the lock file {}: {}", out_.string(), kLockName,
                               std::strerror(errno)));
}

OutputStage::OutputStage(std::filesystem::path out_dir, std::vector<std::string> owned)
    : out_(std::move(out_dir)), owned_(std::move(owned)) {
  std::error_code ec;
  created_out_ = !std::filesystem::exists(out_, ec);
  prepareOutputDir(out_);
  lock();
  stage_ = out_ / fmt::format(".scanplan-staging-{}", static_cast<long>(::getpid()));
  // Staging folders of runs that were killed (their process is gone, or it was an earlier run
  // with our pid): removed, so they do not pile up. A live run's folder is left alone.
  constexpr std::string_view kPrefix = ".scanplan-staging-";
  for (const auto& entry : std::filesystem::directory_iterator(out_, ec)) {
    const std::string name = entry.path().filename().string();
    if (!name.starts_with(kPrefix)) continue;
    char* end = nullptr;
    const long pid = std::strtol(name.c_str() + kPrefix.size(), &end, 10);
    const bool dead = pid <= 0 || *end != '\0' || pid == static_cast<long>(::getpid()) ||
                      (::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH);
    std::error_code ignored;
    if (dead) std::filesystem::remove_all(entry.path(), ignored);
  }
  std::filesystem::create_directory(stage_, ec);
  if (ec) {
    unlock();
    throw InputError(
        fmt::format("{}: cannot create a staging folder: {}", out_.string(), ec.message()));
  }
}

void OutputStage::unlock() {
  if (!locked_) return;
  std::error_code ec;
  std::filesystem::remove(out_ / kLockName, ec);
  locked_ = false;
}

OutputStage::~OutputStage() {
  std::error_code ec;
  if (!committed_) std::filesystem::remove_all(stage_, ec);
  unlock();
  if (!committed_ && created_out_ && std::filesystem::is_empty(out_, ec))
    std::filesystem::remove(out_, ec);
}

bool OutputStage::owned(const std::string& name) const {
  for (const std::string& o : owned_) {
    if (!o.empty() && o.back() == '*' ? name.starts_with(o.substr(0, o.size() - 1)) : name == o)
      return true;
  }
  return false;
}

void OutputStage::commit() {
  namespace fs = std::filesystem;
  std::error_code ec;
  std::vector<fs::path> earlier, staged;  // listed first: the loops below change the folders
  for (const fs::directory_entry& e : fs::directory_iterator(out_)) earlier.push_back(e.path());
  for (const fs::directory_entry& e : fs::directory_iterator(stage_)) staged.push_back(e.path());
  for (const fs::path& p : earlier) {
    const std::string name = p.filename().string();
    if (owned(name) && !fs::exists(stage_ / name)) fs::remove_all(p, ec);
  }
  for (const fs::path& p : staged) {
    const fs::path target = out_ / p.filename();
    if (fs::is_directory(p)) fs::remove_all(target, ec);  // a folder is replaced as a whole
    fs::rename(p, target, ec);
    if (ec) {
      throw InputError(fmt::format("{}: cannot move the finished output into place: {}",
                                   target.string(), ec.message()));
    }
  }
  fs::remove(stage_, ec);
  committed_ = true;
}

Eigen::Vector4d quaternionWxyz(const Eigen::Matrix3d& R) {
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1.0;
  return {q.w(), q.x(), q.y(), q.z()};
}

}  // namespace scanplan::cli
