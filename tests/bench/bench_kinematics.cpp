// FK and IK per pose, one thread, CPU time (best of N runs over 10 000 random poses), for the
// bundled robots. The raw OPW inverse (all 8 solutions) is timed side by side with a
// straightforward implementation of the OPW equations written here from the paper
// (Brandstötter et al. 2014: each angle's own sin/cos, full rotation matrices, ZYZ wrist), and
// both solution sets are compared. Target: the raw inverse ≤ 400 ns per pose.
// Usage: build/tests/bench/bench_kinematics [runs]   (run from the repository root)
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <random>
#include <vector>

#include <scanplan/config/robot_file.h>
#include <scanplan/kinematics/opw.h>
#include <scanplan/kinematics/robot_model.h>
#include "tests/bench/bench_timing.h"

using namespace scanplan;
using kinematics::JointVector;
using kinematics::OpwParameters;
using kinematics::detail::OpwSolution;

namespace {

constexpr double kTargetOpwNs = 400.0;  // the target for the raw inverse
constexpr double kPi = std::numbers::pi;

// The reference: the OPW equations as the paper writes them, nothing shared or reused.
std::size_t referenceOpwInverse(const OpwParameters& p,
                                const Eigen::Isometry3d& X,
                                std::array<JointVector, 8>& out) {
  const Eigen::Matrix3d R = X.linear();
  const Eigen::Vector3d c = X.translation() - p.c4 * R * Eigen::Vector3d::UnitZ();
  const double nx1 = std::sqrt(c.x() * c.x() + c.y() * c.y() - p.b * p.b) - p.a1;
  const double s1_sq = nx1 * nx1 + (c.z() - p.c1) * (c.z() - p.c1);
  const double s2_sq = (nx1 + 2 * p.a1) * (nx1 + 2 * p.a1) + (c.z() - p.c1) * (c.z() - p.c1);
  const double k_sq = p.a2 * p.a2 + p.c3 * p.c3;
  const double s1 = std::sqrt(s1_sq), s2 = std::sqrt(s2_sq), k = std::sqrt(k_sq);
  const double t1_i = std::atan2(c.y(), c.x()) - std::atan2(p.b, nx1 + p.a1);
  const double t1_ii = std::atan2(c.y(), c.x()) + std::atan2(p.b, nx1 + p.a1) - kPi;
  const double a2f = std::acos((s1_sq + p.c2 * p.c2 - k_sq) / (2 * s1 * p.c2));
  const double a2b = std::acos((s2_sq + p.c2 * p.c2 - k_sq) / (2 * s2 * p.c2));
  const double a3f = std::acos((s1_sq - p.c2 * p.c2 - k_sq) / (2 * p.c2 * k));
  const double a3b = std::acos((s2_sq - p.c2 * p.c2 - k_sq) / (2 * p.c2 * k));
  const double pf = std::atan2(nx1, c.z() - p.c1);
  const double pb = std::atan2(nx1 + 2 * p.a1, c.z() - p.c1);
  const double psi3 = std::atan2(p.a2, p.c3);
  const std::array<std::array<double, 3>, 4> arm{{{t1_i, -a2f + pf, a3f - psi3},
                                                  {t1_i, a2f + pf, -a3f - psi3},
                                                  {t1_ii, -a2b - pb, a3b - psi3},
                                                  {t1_ii, a2b - pb, -a3b - psi3}}};
  std::size_t n = 0;
  for (const auto& [t1, t2, t3] : arm) {
    const Eigen::Matrix3d R0c = (Eigen::AngleAxisd(t1, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(t2 + t3, Eigen::Vector3d::UnitY()))
                                    .toRotationMatrix();
    const Eigen::Matrix3d e = R0c.transpose() * R;
    const double t4 = std::atan2(e(1, 2), e(0, 2));
    const double t5 = std::atan2(std::sqrt(std::max(0.0, 1 - e(2, 2) * e(2, 2))), e(2, 2));
    const double t6 = std::atan2(e(2, 1), -e(2, 0));
    JointVector a, b;
    a << t1, t2, t3, t4, t5, t6;
    b << t1, t2, t3, t4 + kPi, -t5, t6 - kPi;
    if (a.allFinite() && b.allFinite()) {
      out[n++] = a;
      out[n++] = b;
    }
  }
  return n;
}

double wrapped(double a) { return std::abs(std::remainder(a, 2 * kPi)); }

// The largest joint difference between a reference solution and its nearest raw one, over
// poses whose wrist is not near its singularity (there q4 and q6 trade off freely).
double largestDifference(const OpwParameters& p, const std::vector<Eigen::Isometry3d>& poses) {
  double worst = 0.0;
  std::array<OpwSolution, 8> ours;
  std::array<JointVector, 8> ref;
  for (const auto& X : poses) {
    const std::size_t n = kinematics::detail::opwInverse(p, X, ours);
    const std::size_t m = referenceOpwInverse(p, X, ref);
    for (std::size_t i = 0; i < m; ++i) {
      if (std::abs(std::sin(ref[i](4))) < 1e-3) continue;
      double nearest = 1e9;
      for (std::size_t j = 0; j < n; ++j) {
        double d = 0.0;
        for (int k = 0; k < 6; ++k) d = std::max(d, wrapped(ref[i](k) - ours[j].q(k)));
        nearest = std::min(nearest, d);
      }
      worst = std::max(worst, nearest);
    }
  }
  return worst;
}

void benchRobot(const char* file, int runs) {
  const auto robot = config::buildRobotModel(config::loadRobotFile(file), file);
  const OpwParameters& p = robot.definition().opw;
  std::mt19937 rng(1);
  std::vector<JointVector> qs(10000);
  for (auto& q : qs) {
    for (int i = 0; i < 6; ++i) {
      q(i) = std::uniform_real_distribution<double>(robot.joint(i).min, robot.joint(i).max)(rng);
    }
  }
  std::vector<Eigen::Isometry3d> poses, opw_poses;
  for (const auto& q : qs) {
    poses.push_back(robot.fk(q));
    opw_poses.push_back(kinematics::detail::opwForward(p, q));  // OPW coordinates
  }
  const double per_pose = 1e9 / static_cast<double>(qs.size());  // s per loop → ns per pose
  double sink = 0.0;
  std::size_t ours_n = 0, ref_n = 0;
  const double fk = per_pose * bench::bestThreadCpuSeconds(runs, [&] {
                      for (const auto& q : qs) sink += robot.fk(q).translation().x();
                    });
  std::array<OpwSolution, 8> raw;
  const double opw = per_pose * bench::bestThreadCpuSeconds(runs, [&] {
                       for (const auto& X : opw_poses)
                         ours_n += kinematics::detail::opwInverse(p, X, raw);
                     });
  std::array<JointVector, 8> ref;
  const double reference = per_pose * bench::bestThreadCpuSeconds(runs, [&] {
                             for (const auto& X : opw_poses)
                               ref_n += referenceOpwInverse(p, X, ref);
                           });
  const double ik = per_pose * bench::bestThreadCpuSeconds(runs, [&] {
                      for (const auto& X : poses) ours_n += robot.ik(X).size();
                    });
  const double ik_limits = per_pose * bench::bestThreadCpuSeconds(runs, [&] {
                             for (const auto& X : poses)
                               ours_n += robot.ik(X, {.within_limits_only = true}).size();
                           });
  std::printf("%s\n", robot.name().c_str());
  std::printf("  FK                          %7.1f ns\n", fk);
  std::printf("  OPW inverse, 8 solutions     %7.1f ns   target %.0f ns: %s\n", opw, kTargetOpwNs,
              opw <= kTargetOpwNs ? "met" : "MISSED");
  std::printf("  reference OPW (paper form)   %7.1f ns   ours / reference %.2f\n", reference,
              opw / reference);
  std::printf("  ik(), all turns             %7.1f ns\n", ik);
  std::printf("  ik(), within limits          %7.1f ns\n", ik_limits);
  std::printf("  largest joint difference to the reference %.1e rad (wrist |sin q5| >= 1e-3)\n",
              largestDifference(p, opw_poses));
  std::printf("  (checksums %.3f %zu %zu)\n", sink, ours_n, ref_n);
}

}  // namespace

int main(int argc, char** argv) {
  const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 15;
  std::printf(
      "bench_kinematics: 10000 random in-limit poses, one thread, CPU time per pose, best of %d "
      "runs\n",
      runs);
  benchRobot("data/robots/viper_s650.yaml", runs);
  benchRobot("data/robots/kuka_kr6_r900_sixx.yaml", runs);
  return 0;
}
