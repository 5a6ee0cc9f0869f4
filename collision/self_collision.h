#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <scanplan/kinematics/robot_model.h>

namespace scanplan::collision {

/// One pair of a robot's bodies (base and links) over the survey's configurations.
struct SelfPairSurvey {
  std::string a, b;  ///< body names (the scene's: the link's name, else base, link1 … link6)
  int link_a = 0, link_b = 0;
  bool adjacent = false;      ///< consecutive links: never checked (the default pair set)
  bool allowed = false;       ///< in the robot's allowed_collisions
  std::size_t colliding = 0;  ///< configurations in which they touch or overlap
  double min_distance = 0.0;  ///< m, the least over the configurations (0 when colliding)
};

/// How a robot's bodies meet over random configurations, as MoveIt's setup assistant samples
/// them: pairs that collide always or nearly always overlap by design (allow them: every pose
/// would read as a collision); pairs that never do still need checking (a sample is no proof).
struct SelfSurvey {
  std::size_t samples = 0;
  std::vector<SelfPairSurvey> pairs;  ///< every pair of bodies with geometry
};

/// Pairs are measured exactly up to this distance; beyond it only "farther" is known.
inline constexpr double kSurveyReach = 0.1;  // m

/// Samples `samples` (> 0) joint vectors uniformly within the limits (std::mt19937 seeded with
/// `seed`) and measures every pair of bodies with collision geometry; a pair within 1e-6 m
/// counts as colliding.
SelfSurvey surveySelfCollisions(const kinematics::RobotModel& robot,
                                std::size_t samples,
                                std::uint32_t seed);

}  // namespace scanplan::collision
