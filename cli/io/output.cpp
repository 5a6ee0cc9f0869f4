#include "cli/io/output.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string_view>
#include <system_error>

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

OutputStage::OutputStage(std::filesystem::path out_dir, std::vector<std::string> owned)
    : out_(std::move(out_dir)), owned_(std::move(owned)) {
  std::error_code ec;
  created_out_ = !std::filesystem::exists(out_, ec);
  prepareOutputDir(out_);
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
    throw InputError(
        fmt::format("{}: cannot create a staging folder: {}", out_.string(), ec.message()));
  }
}

OutputStage::~OutputStage() {
  if (committed_) return;
  std::error_code ec;
  std::filesystem::remove_all(stage_, ec);
  if (created_out_ && std::filesystem::is_empty(out_, ec)) std::filesystem::remove(out_, ec);
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
