#include <scanplan/kinematics/scan_path.h>

namespace scanplan::kinematics {

std::vector<std::pair<std::size_t, std::size_t>> segmentRanges(const ScanPath& path) {
  std::vector<std::pair<std::size_t, std::size_t>> out;
  std::size_t begin = 0;
  for (const std::size_t b : path.breaks) {
    if (b <= begin || b >= path.samples.size()) continue;
    out.emplace_back(begin, b);
    begin = b;
  }
  if (begin < path.samples.size()) out.emplace_back(begin, path.samples.size());
  return out;
}

ScanPath slicePath(const ScanPath& path, std::size_t begin, std::size_t end) {
  ScanPath out;
  out.dt = path.dt;
  out.samples.assign(path.samples.begin() + static_cast<std::ptrdiff_t>(begin),
                     path.samples.begin() + static_cast<std::ptrdiff_t>(end));
  return out;
}

Eigen::Isometry3d interpolatePose(const Eigen::Isometry3d& a,
                                  const Eigen::Isometry3d& b,
                                  double s) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = (1.0 - s) * a.translation() + s * b.translation();
  X.linear() =
      Eigen::Quaterniond(a.linear()).slerp(s, Eigen::Quaterniond(b.linear())).toRotationMatrix();
  return X;
}

}  // namespace scanplan::kinematics
