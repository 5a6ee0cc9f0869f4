// FK and full IK solve rates, single thread, for the bundled robots.
// Usage: build/tests/bench/bench_kinematics [repeats]   (run from the repository root)
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "cli/config/robot_file.h"
#include "kinematics/robot_model.h"

using namespace scanplan;
using Clock = std::chrono::steady_clock;

namespace {

constexpr double kTargetIkUs = 2.0;  // issue 2: ≤ 2 µs per full IK solve (Viper)

template <class F>
double microsecondsPerCall(std::size_t calls, F&& f) {
  const auto start = Clock::now();
  f();
  return std::chrono::duration<double, std::micro>(Clock::now() - start).count() /
         static_cast<double>(calls);
}

void bench(const char* file, int repeats) {
  const auto robot = cli::buildRobotModel(cli::loadRobotFile(file), file);
  std::mt19937 rng(1);
  std::vector<kinematics::JointVector> qs(10000);
  for (auto& q : qs) {
    for (int i = 0; i < 6; ++i) {
      q(i) = std::uniform_real_distribution<double>(robot.joint(i).min, robot.joint(i).max)(rng);
    }
  }
  std::vector<Eigen::Isometry3d> poses;
  for (const auto& q : qs) poses.push_back(robot.fk(q));
  const std::size_t calls = qs.size() * static_cast<std::size_t>(repeats);

  double sink = 0.0;
  std::size_t solutions = 0;
  const double fk_us = microsecondsPerCall(calls, [&] {
    for (int r = 0; r < repeats; ++r)
      for (const auto& q : qs) sink += robot.fk(q).translation().x();
  });
  const double ik_us = microsecondsPerCall(calls, [&] {
    for (int r = 0; r < repeats; ++r)
      for (const auto& X : poses) solutions += robot.ik(X).size();
  });
  const double ik_limits_us = microsecondsPerCall(calls, [&] {
    for (int r = 0; r < repeats; ++r)
      for (const auto& X : poses) solutions += robot.ik(X, {.within_limits_only = true}).size();
  });
  std::printf(
      "%-22s  FK %6.3f us (%5.2f M/s)   IK all %6.3f us (%4.2f M/s)   IK in-limits %6.3f us"
      "   IK/FK %4.1fx   IK vs %.0f us target: %4.2fx %s\n",
      robot.name().c_str(), fk_us, 1.0 / fk_us, ik_us, 1.0 / ik_us, ik_limits_us, ik_us / fk_us,
      kTargetIkUs, ik_us / kTargetIkUs, ik_us <= kTargetIkUs ? "OK" : "MISSED");
  std::printf("%-22s  (%.1f solutions per pose on average; checksum %.3f)\n", "",
              static_cast<double>(solutions) / (2.0 * static_cast<double>(calls)), sink);
}

}  // namespace

int main(int argc, char** argv) {
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 20;
  std::printf("bench_kinematics: %d x 10000 random in-limit poses, one thread\n", repeats);
  bench("data/robots/viper_s650.yaml", repeats);
  bench("data/robots/kuka_kr6_r900_sixx.yaml", repeats);
  return 0;
}
