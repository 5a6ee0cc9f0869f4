#include "collision/map_clearance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "collision/fcl_geometry.h"
#include "kinematics/ramp.h"

namespace scanplan::collision {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// FCL's GJK stops within its distance tolerance (1e-6 m) above the true distance, so a bound
// carried from one of its numbers keeps this much in hand.
constexpr double kMargin = 1e-6;  // m

bool moves(BodyMotion motion) { return motion == BodyMotion::kRobotLink; }

// The most any point within r of c (a body's frame) moves from pose `from` to pose `to`.
double motionBound(const Eigen::Vector3d& c,
                   double r,
                   const Eigen::Isometry3d& from,
                   const Eigen::Isometry3d& to) {
  return (from * c - to * c).norm() + r * (from.linear() - to.linear()).norm();
}

}  // namespace

MapClearance::MapClearance(const Scene& scene, std::size_t branches, MapClearanceOptions options)
    : scene_(&scene), options_(options), levers_(scene) {
  const std::size_t np = scene.pairs().size();
  for (const PairInfo& pair : scene.pairs()) {
    const BodyMotion a = scene.bodies()[static_cast<std::size_t>(pair.a)].motion;
    const BodyMotion b = scene.bodies()[static_cast<std::size_t>(pair.b)].motion;
    shared_.push_back(!moves(a) && !moves(b));
  }
  for (const detail::BodyGeometry& body : scene.geometry().bodies) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const detail::CollisionShape& s : body.shapes) c += s.X_BG * s.centre_G;
    if (!body.shapes.empty()) c /= static_cast<double>(body.shapes.size());
    double r = 0.0;
    for (const detail::CollisionShape& s : body.shapes) {
      r = std::max(r, (s.X_BG * s.centre_G - c).norm() + s.radius);
    }
    centre_.push_back(c);
    radius_.push_back(r);
  }
  memory_.resize(np * (1 + branches));
  poses_.resize(memory_.size());
  shared_factor_.assign(np, -1.0);
  const std::size_t nb = scene.bodies().size();
  X_W_.assign(nb, Eigen::Isometry3d::Identity());
  last_.assign(nb * (1 + branches), Eigen::Isometry3d::Identity());
  placed_.assign(nb * (1 + branches), false);
  travel_.assign(nb * (1 + branches), 0.0);
}

std::size_t MapClearance::chainOf(std::size_t body, std::size_t branch) const {
  return moves(scene_->bodies()[body].motion) ? 1 + branch : 0;
}

void MapClearance::place(std::size_t chain, std::size_t i, const Eigen::Isometry3d& X_W) {
  X_W_[i] = X_W;
  const std::size_t k = chain * X_W_.size() + i;
  if (placed_[k]) {
    travel_[k] += motionBound(centre_[i], radius_[i], last_[k], X_W);
  }
  last_[k] = X_W;
  placed_[k] = true;
}

void MapClearance::beginCell(double theta, const Eigen::Isometry3d& X_BF) {
  if (!std::isfinite(theta) || !X_BF.matrix().allFinite()) {
    throw std::invalid_argument("collision::MapClearance: non-finite table angle or target");
  }
  const kinematics::CellModel& cell = scene_->cell();
  const Eigen::Isometry3d X_WR = cell.table.X_WR(theta);
  const Eigen::Isometry3d X_WS = cell.X_WB * X_BF * cell.scanner.X_FS;
  for (std::size_t i = 0; i < X_W_.size(); ++i) {
    switch (scene_->bodies()[i].motion) {
      case BodyMotion::kWorld:
        place(0, i, Eigen::Isometry3d::Identity());
        break;
      case BodyMotion::kTable:
        place(0, i, X_WR);
        break;
      case BodyMotion::kScanner:
        place(0, i, X_WS);
        break;
      case BodyMotion::kRobotLink:
        break;  // per branch
    }
  }
  std::fill(shared_factor_.begin(), shared_factor_.end(), -1.0);
}

double MapClearance::factor(std::size_t branch, const kinematics::JointVector& q) {
  if (!q.allFinite()) throw std::invalid_argument("collision::MapClearance: non-finite joints");
  const kinematics::CellModel& cell = scene_->cell();
  const auto frames = cell.robot.linkFrames(q);
  for (std::size_t i = 0; i < X_W_.size(); ++i) {
    const BodyInfo& body = scene_->bodies()[i];
    if (moves(body.motion)) {
      place(1 + branch, i, cell.X_WB * frames[static_cast<std::size_t>(body.link)]);
    }
  }
  const std::size_t np = shared_.size();
  double f = 1.0;
  for (std::size_t p = 0; p < np; ++p) {
    double fp = 1.0;
    if (shared_[p]) {
      if (shared_factor_[p] < 0.0) shared_factor_[p] = pairFactor(p, branch, p, q);
      fp = shared_factor_[p];
    } else {
      fp = pairFactor(p, branch, np * (1 + branch) + p, q);
    }
    if (fp == 1.0) continue;  // as ClearanceEvaluator::factor: no product with a pair beyond
    f *= fp;
    if (f == 0.0) return 0.0;
  }
  return f;
}

double MapClearance::pairFactor(std::size_t p,
                                std::size_t branch,
                                std::size_t slot,
                                const kinematics::JointVector& q) {
  const PairInfo& pair = scene_->pairs()[p];
  const PairThresholds& t = pair.thresholds;
  const auto a = static_cast<std::size_t>(pair.a), b = static_cast<std::size_t>(pair.b);
  const auto& bodies = scene_->geometry().bodies;
  const std::vector<Eigen::Isometry3d>& X_W = X_W_;
  if (options_.exact_distances) {
    const detail::ShapeDistance d =
        detail::bodyDistance(bodies[a], X_W[a], bodies[b], X_W[b], kInf, true, false);
    return d.beyond ? 1.0 : rampFactor(d.distance, t.d_low, t.d_high, t.gamma);
  }
  Memory& memory = memory_[slot];
  Poses& poses = poses_[slot];
  const double travel =
      travel_[chainOf(a, branch) * X_W.size() + a] + travel_[chainOf(b, branch) * X_W.size() + b];
  if (options_.skip && memory.known) {
    const double moved = travel - memory.travel;
    if (moved == 0.0 && poses.X_a.matrix() == X_W[a].matrix() &&
        poses.X_b.matrix() == X_W[b].matrix()) {
      return memory.factor;  // the same query again
    }
    if (memory.lower - moved - kMargin >= t.d_high) return 1.0;
    if (memory.upper + moved + kMargin < t.d_low) return 0.0;
    if (levers_.together(p)) {
      const double relative = levers_.relativeMotion(p, poses.q, q) + kMargin;
      if (memory.lower - relative >= t.d_high) return 1.0;
      if (memory.upper + relative < t.d_low) return 0.0;
    }
  }
  const detail::ShapeDistance d =
      detail::bodyDistance(bodies[a], X_W[a], bodies[b], X_W[b], t.d_high, false, false);
  poses.X_a = X_W[a];
  poses.X_b = X_W[b];
  poses.q = q;
  memory.travel = travel;
  memory.lower = d.lower;
  memory.upper = d.beyond ? kInf : d.distance;
  memory.factor = d.beyond ? 1.0 : rampFactor(d.distance, t.d_low, t.d_high, t.gamma);
  memory.known = true;
  return memory.factor;
}

}  // namespace scanplan::collision
