#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <initializer_list>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <scanplan/config/robot_file.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/robot_model.h>

namespace scanplan::test {

/// Passes when `run` throws InputError whose message holds every one of `parts`; prints the
/// actual message (or what happened instead) otherwise.
template <class F>
::testing::AssertionResult throwsInputError(F&& run, std::initializer_list<std::string> parts) {
  try {
    run();
  } catch (const InputError& e) {
    const std::string message = e.what();
    for (const std::string& p : parts) {
      if (message.find(p) == std::string::npos) {
        return ::testing::AssertionFailure() << "'" << p << "' not in: " << message;
      }
    }
    return ::testing::AssertionSuccess() << message;
  } catch (const std::exception& e) {
    return ::testing::AssertionFailure() << "threw a non-InputError: " << e.what();
  }
  return ::testing::AssertionFailure() << "no exception";
}

/// Passes when two poses agree within `tol` (m between positions, rad between rotations); with
/// `max_error`, also keeps the largest difference seen.
inline ::testing::AssertionResult samePose(const Eigen::Isometry3d& a,
                                           const Eigen::Isometry3d& b,
                                           double tol,
                                           double* max_error = nullptr) {
  const double dp = (a.translation() - b.translation()).norm();
  const double dr = kinematics::rotationDistance(a.linear(), b.linear());
  if (max_error) *max_error = std::max({*max_error, dp, dr});
  if (dp <= tol && dr <= tol) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "positions " << dp << " m apart, rotations " << dr << " rad\n"
         << a.matrix() << "\nvs\n"
         << b.matrix();
}

inline std::filesystem::path sourceDir() { return SCANPLAN_SOURCE_DIR; }

/// `--set` overrides that lighten the bundled demo for tests: two of its rings (the body and
/// the hub from above) sampled every 0.2 s, so a plan takes about a second.
inline const std::vector<std::string> kLightDemo = {
    "scan.dt_s=0.2",
    "scan.paths=[{type: ring, height_mm: 35, tilt_deg: 25}, {type: ring, height_mm: 105, "
    "tilt_deg: 60}]"};
inline std::filesystem::path sharedDataDir() { return SCANPLAN_SHARED_DATA_DIR; }

/// A shell command's standard output (popen); empty when it cannot start.
inline std::string runCommand(const std::string& command) {
  std::array<char, 4096> buffer{};
  std::string out;
  const std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), pclose);
  if (!pipe) return out;
  while (std::fgets(buffer.data(), buffer.size(), pipe.get()) != nullptr) out += buffer.data();
  return out;
}

/// A bundled robot file, e.g. "viper_s650".
inline kinematics::RobotModel bundledRobot(const std::string& name) {
  const auto file = sourceDir() / "data" / "robots" / (name + ".yaml");
  return config::buildRobotModel(config::loadRobotFile(file), file.string());
}

inline kinematics::JointVector randomJoints(const kinematics::RobotModel& robot,
                                            std::mt19937& rng) {
  kinematics::JointVector q;
  for (int i = 0; i < kinematics::kNumJoints; ++i) {
    q(i) = std::uniform_real_distribution<double>(robot.joint(i).min, robot.joint(i).max)(rng);
  }
  return q;
}

}  // namespace scanplan::test
