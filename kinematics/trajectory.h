#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/kinematics/robot_model.h>

namespace scanplan::kinematics {

/// One sample of a 7-DOF trajectory: the table angle and the six joints at time t, with what the
/// plan knows about it.
struct TrajectorySample {
  double t = 0.0;                                          ///< s
  double theta = 0.0;                                      ///< table angle, rad, unwrapped
  JointVector q = JointVector::Zero();                     ///< rad, continuous along the path
  double f = 0.0;                                          ///< Eq. 6 at this pose (NaN: unknown)
  bool scanning = false;                                   ///< the laser is acquiring
  Eigen::Isometry3d X_PS = Eigen::Isometry3d::Identity();  ///< target scanner pose, part frame, m
  std::string limit;  ///< the lowest factor ("joint 5", "clearance scanner-part"); may be empty
};

/// A timed joint trajectory: strictly increasing times, one sample per planned time step.
struct Trajectory {
  std::vector<TrajectorySample> samples;

  double duration() const { return samples.empty() ? 0.0 : samples.back().t; }
};

/// The largest joint or table angle a trajectory file may hold, degrees: no axis turns through
/// this (the demo's continuous table turns about 30 000° in a 20-minute scan), and far beyond
/// it the collision check between two samples has no end.
inline constexpr double kMaxTrajectoryAngleDeg = 1e6;
/// The largest scanner position coordinate a trajectory file may hold, mm (a kilometre, as for
/// every length in a job).
inline constexpr double kMaxTrajectoryLengthMm = 1e6;

/// The CSV interchange format (header included):
///   t_s,table_deg,j1_deg,…,j6_deg,f,scanning,px_mm,py_mm,pz_mm,qw,qx,qy,qz,limit
/// Angles in degrees, positions in mm, the quaternion of X_PS with qw ≥ 0; 12 significant
/// digits, so a written trajectory reads back equal to 1e-12 relative.
std::string trajectoryToCsv(const Trajectory& trajectory);

/// Reads trajectoryToCsv()'s format, or a hand-written file with the same columns (the `limit`
/// column may be left out; `f` may be empty or "nan" when unknown). Comment lines start with #.
/// Errors (InputError) name `source`, the line, the column and the value: wrong header, wrong
/// column count, non-numbers, NaN or infinite values, angles beyond ±kMaxTrajectoryAngleDeg
/// and positions beyond ±kMaxTrajectoryLengthMm, times not strictly increasing, a
/// quaternion that is not unit length (within 1e-6), scanning not 0 or 1, no samples.
Trajectory parseTrajectoryCsv(const std::string& text, const std::string& source);

}  // namespace scanplan::kinematics
