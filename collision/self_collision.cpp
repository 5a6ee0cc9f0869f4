#include <scanplan/collision/self_collision.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include <scanplan/collision/fcl_geometry.h>

namespace scanplan::collision {
namespace {

std::string bodyName(const kinematics::RobotDefinition& def, std::size_t k) {
  if (!def.links[k].name.empty()) return def.links[k].name;
  return k == 0 ? std::string("base") : "link" + std::to_string(k);
}

bool allowedPair(const kinematics::RobotDefinition& def,
                 const std::string& a,
                 const std::string& b) {
  return std::any_of(
      def.allowed_collisions.begin(), def.allowed_collisions.end(),
      [&](const auto& p) { return (p[0] == a && p[1] == b) || (p[0] == b && p[1] == a); });
}

// Uniform within the limits from mt19937's own numbers (its sequence is fixed by the standard;
// std::uniform_real_distribution's is not, so the survey reads the same on every library).
kinematics::JointVector randomInLimits(const kinematics::RobotModel& robot, std::mt19937& rng) {
  kinematics::JointVector q;
  for (int j = 0; j < kinematics::kNumJoints; ++j) {
    const double u = static_cast<double>(rng()) / 4294967296.0;  // [0, 1)
    q(j) = robot.joint(j).min + (robot.joint(j).max - robot.joint(j).min) * u;
  }
  return q;
}

// Touching pairs read within GJK's tolerance of 0 (1e-6 m) on FCL's shapes: count them.
constexpr double kContact = 1e-6;  // m

}  // namespace

SelfSurvey surveySelfCollisions(const kinematics::RobotModel& robot,
                                std::size_t samples,
                                std::uint32_t seed) {
  if (samples == 0) throw std::invalid_argument("surveySelfCollisions: no samples");
  const kinematics::RobotDefinition& def = robot.definition();
  std::vector<detail::BodyGeometry> bodies(def.links.size());
  for (std::size_t k = 0; k < def.links.size(); ++k) {
    for (const kinematics::Shape& s : def.links[k].shapes) {
      bodies[k].shapes.push_back(detail::makeCollisionShape(s));
    }
  }
  SelfSurvey survey;
  survey.samples = samples;
  for (std::size_t a = 0; a < bodies.size(); ++a) {
    for (std::size_t b = a + 1; b < bodies.size(); ++b) {
      if (bodies[a].shapes.empty() || bodies[b].shapes.empty()) continue;
      SelfPairSurvey p;
      p.a = bodyName(def, a);
      p.b = bodyName(def, b);
      p.link_a = static_cast<int>(a);
      p.link_b = static_cast<int>(b);
      p.adjacent = b - a == 1;
      p.allowed = allowedPair(def, p.a, p.b);
      p.min_distance = std::numeric_limits<double>::infinity();
      survey.pairs.push_back(p);
    }
  }
  std::mt19937 rng(seed);
  for (std::size_t n = 0; n < samples; ++n) {
    const auto frames = robot.linkFrames(randomInLimits(robot, rng));
    for (SelfPairSurvey& p : survey.pairs) {
      const auto a = static_cast<std::size_t>(p.link_a), b = static_cast<std::size_t>(p.link_b);
      const detail::ShapeDistance d = detail::bodyDistance(bodies[a], frames[a], bodies[b],
                                                           frames[b], kSurveyReach, false, false);
      const double distance = d.penetrating ? 0.0 : d.beyond ? kSurveyReach : d.distance;
      if (d.penetrating || distance <= kContact) ++p.colliding;
      p.min_distance = std::min(p.min_distance, distance);
    }
  }
  return survey;
}

}  // namespace scanplan::collision
