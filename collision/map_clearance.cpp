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
  for (const detail::BodyGeometry& body : scene.geometry().map_bodies) {
    const auto [c, r] = detail::boundingSphere(body);
    centre_.push_back(c);
    radius_.push_back(r);
  }
  const std::size_t np = scene.pairs().size(), nb = scene.bodies().size();
  memory_.resize(np * (1 + branches));
  state_.resize(np);
  shared_factor_.assign(np, -1.0);
  travel_of_branch_.resize(branches);
  for (std::size_t p = 0; p < np; ++p) {
    if (!levers_.covers(p)) continue;
    table_lever_ = std::max(table_lever_, levers_.tableLever(p));
    for (std::size_t k = 0; k < joint_levers_.size(); ++k) {
      joint_levers_[k] = std::max(joint_levers_[k], levers_.weights(p)[k]);
    }
  }
  X_W_.assign(nb, Eigen::Isometry3d::Identity());
  placed_.assign(nb, false);
  last_.assign(nb, Eigen::Isometry3d::Identity());
  seen_.assign(nb, false);
  travel_.assign(nb, 0.0);
}

void MapClearance::place(std::size_t i, const Eigen::Isometry3d& X_W) {
  X_W_[i] = X_W;
  if (seen_[i]) travel_[i] += motionBound(centre_[i], radius_[i], last_[i], X_W);
  last_[i] = X_W;
  seen_[i] = true;
}

void MapClearance::beginCell(double theta, const Eigen::Isometry3d& X_BF) {
  if (!std::isfinite(theta) || !X_BF.matrix().allFinite()) {
    throw std::invalid_argument("collision::MapClearance: non-finite table angle or target");
  }
  const kinematics::CellModel& cell = scene_->cell();
  theta_ = theta;
  const Eigen::Isometry3d X_WR = cell.table.X_WR(theta);
  const Eigen::Isometry3d X_WS = cell.X_WB * X_BF * cell.scanner.X_FS;
  for (std::size_t i = 0; i < X_W_.size(); ++i) {
    switch (scene_->bodies()[i].motion) {
      case BodyMotion::kWorld:
        place(i, Eigen::Isometry3d::Identity());
        break;
      case BodyMotion::kTable:
        place(i, X_WR);
        break;
      case BodyMotion::kScanner:
        place(i, X_WS);
        break;
      case BodyMotion::kRobotLink:
        break;  // per branch, on first use
    }
  }
  std::fill(shared_factor_.begin(), shared_factor_.end(), -1.0);
}

const std::array<Eigen::Isometry3d, kinematics::kNumJoints + 1>& MapClearance::frames() {
  if (!frames_ready_) {
    frames_ = scene_->cell().robot.linkFrames(*q_, scene_->cell().X_WB);
    frames_ready_ = true;
  }
  return frames_;
}

const Eigen::Isometry3d& MapClearance::pose(std::size_t i) {
  const BodyInfo& body = scene_->bodies()[i];
  if (body.motion != BodyMotion::kRobotLink || placed_[i]) return X_W_[i];
  X_W_[i] = frames()[static_cast<std::size_t>(body.link)];
  placed_[i] = true;
  return X_W_[i];
}

double MapClearance::factor(std::size_t branch, const kinematics::JointVector& q) {
  if (!q.allFinite()) throw std::invalid_argument("collision::MapClearance: non-finite joints");
  q_ = &q;
  frames_ready_ = false;
  std::fill(placed_.begin(), placed_.end(), false);
  Travel& travel = travel_of_branch_.at(branch);
  if (travel.seen) {
    double step = table_lever_ * std::abs(theta_ - travel.theta);
    for (int k = 0; k < kinematics::kNumJoints; ++k) {
      step += joint_levers_[static_cast<std::size_t>(k)] * std::abs(q(k) - travel.q(k));
    }
    travel.sum += step;
  }
  travel.theta = theta_;
  travel.q = q;
  travel.seen = true;
  const std::size_t np = shared_factor_.size();
  double f = 1.0;
  for (std::size_t p = 0; p < np; ++p) {
    double fp = 1.0;
    if (!levers_.covers(p)) {
      if (shared_factor_[p] < 0.0) shared_factor_[p] = sharedFactor(p);
      fp = shared_factor_[p];
    } else {
      fp = linkFactor(p, np * (1 + branch) + p, q, travel.sum);
    }
    if (fp == 1.0) continue;  // as ClearanceEvaluator::factor: no product with a pair beyond
    f *= fp;
    if (f == 0.0) return 0.0;
  }
  return f;
}

double MapClearance::sharedFactor(std::size_t p) {
  const PairInfo& pair = scene_->pairs()[p];
  const PairThresholds& t = pair.thresholds;
  const auto a = static_cast<std::size_t>(pair.a), b = static_cast<std::size_t>(pair.b);
  Memory& memory = memory_[p];
  State& state = state_[p];
  const double travel = travel_[a] + travel_[b];
  if (options_.skip && memory.known && !options_.exact_distances) {
    const double moved = travel - memory.travel;
    if (moved == 0.0 && state.X_a.matrix() == X_W_[a].matrix() &&
        state.X_b.matrix() == X_W_[b].matrix()) {
      return memory.factor;  // the same query again
    }
    if (memory.lower - moved - kMargin >= t.d_high) return 1.0;
    if (memory.upper + moved + kMargin < t.d_low) return 0.0;
  }
  memory.travel = travel;
  state.X_a = X_W_[a];
  state.X_b = X_W_[b];
  return query(p, memory);
}

double MapClearance::linkFactor(std::size_t p,
                                std::size_t slot,
                                const kinematics::JointVector& q,
                                double travel) {
  Memory& memory = memory_[slot];
  if (options_.skip && memory.known && !options_.exact_distances) {
    if (travel <= memory.far_until) return 1.0;
    if (travel < memory.zero_until) return 0.0;
    const PairThresholds& t = scene_->pairs()[p].thresholds;
    const double moved =
        levers_.motion(p, memory.weights, memory.theta, memory.q, theta_, q) + kMargin;
    // Far or deep enough: so until the branch has travelled the slack over the lever more.
    const auto until = [&](double slack) {
      return memory.lever > 0.0 ? travel + slack / memory.lever : kInf;
    };
    if (memory.lower - moved >= t.d_high) {
      memory.far_until = until(memory.lower - moved - t.d_high);
      return 1.0;
    }
    if (memory.upper + moved < t.d_low) {
      memory.zero_until = until(t.d_low - memory.upper - moved);
      return 0.0;
    }
  }
  return requery(p, slot, q);
}

double MapClearance::requery(std::size_t p, std::size_t slot, const kinematics::JointVector& q) {
  Memory& memory = memory_[slot];
  memory.theta = theta_;
  memory.q = q;
  const double f = query(p, memory);
  memory.far_until = memory.zero_until = -kInf;
  if (options_.skip) {
    memory.weights = leversNow(p);
    memory.lever = leverRatio(p, memory.weights);
  }
  return f;
}

double MapClearance::leverRatio(std::size_t p, const ChainLevers::Weights& weights) const {
  double ratio = table_lever_ > 0.0 ? levers_.tableLever(p) / table_lever_ : 0.0;
  for (std::size_t k = 0; k < weights.size(); ++k) {
    if (joint_levers_[k] > 0.0) ratio = std::max(ratio, weights[k] / joint_levers_[k]);
  }
  return ratio;
}

ChainLevers::Weights MapClearance::leversNow(std::size_t p) {
  const std::size_t body = levers_.distal(p);
  return levers_.weightsAt(p, pose(body), frames());
}

double MapClearance::query(std::size_t p, Memory& memory) {
  const PairInfo& pair = scene_->pairs()[p];
  const PairThresholds& t = pair.thresholds;
  const auto a = static_cast<std::size_t>(pair.a), b = static_cast<std::size_t>(pair.b);
  const auto& bodies = scene_->geometry().map_bodies;
  const Eigen::Isometry3d &X_a = pose(a), &X_b = pose(b);
  if (options_.exact_distances) {
    const detail::ShapeDistance d =
        detail::bodyDistance(bodies[a], X_a, bodies[b], X_b, kInf, true, false);
    return d.beyond ? 1.0 : rampFactor(d.distance, t.d_low, t.d_high, t.gamma);
  }
  const detail::ShapeDistance d =
      detail::bodyDistance(bodies[a], X_a, bodies[b], X_b, t.d_high, false, false);
  memory.lower = d.lower;
  memory.upper = d.beyond ? kInf : d.distance;
  memory.factor = d.beyond ? 1.0 : rampFactor(d.distance, t.d_low, t.d_high, t.gamma);
  memory.known = true;
  return memory.factor;
}

}  // namespace scanplan::collision
