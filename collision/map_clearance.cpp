#include <scanplan/collision/map_clearance.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <scanplan/collision/fcl_geometry.h>
#include <scanplan/kinematics/ramp.h>

namespace scanplan::collision {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// FCL's GJK stops within its distance tolerance (1e-6 m) above the true distance, so a bound
// carried from one of its numbers keeps this much in hand.
constexpr double kMargin = 1e-6;  // m
// A pair's factor not known at this cell for a branch (factors are within [0, 1]).
constexpr double kUnknown = -1.0;

// Whether a body is placed once per cell for every branch: the world's and the table's bodies,
// and on the arm the base (fixed), link 6 and the scanner on it. Every branch reaches the
// cell's flange target X_BF, so link 6 is at X_WB · X_BF (Scene::bodyPoses places it at
// X_WB · X_B6(q), and X_B6(q) is the flange pose) and the scanner at X_WB · X_BF · X_FS.
bool placedPerCell(const BodyInfo& body) {
  return body.motion != BodyMotion::kRobotLink || body.link == 0 ||
         body.link == kinematics::kNumJoints;
}

// The last joint a pair with a link depends on at a cell (its bodies' farthest link placed per
// branch), beyond the joints for the others.
int depthOf(const Scene& scene, std::size_t p, bool with_link) {
  if (!with_link) return kinematics::kNumJoints + 1;
  int depth = 0;
  for (const int i : {scene.pairs()[p].a, scene.pairs()[p].b}) {
    const BodyInfo& body = scene.bodies()[static_cast<std::size_t>(i)];
    if (!placedPerCell(body)) depth = std::max(depth, body.link);
  }
  return depth;
}
// SelfPairGrid's erosion: its bins' bounds lie at most this far below the distance (2, 4 and
// 8 mm measured on the demo map: 4 and 8 the same, 2 a little worse).
constexpr double kGridErosion = 0.004;  // m
// Its erosion for the fine pairs, whose factor is their bins' bound: at most twice this nearer
// than the pair is (0.5 mm: on the KR6 R700's pieces, the same feasible share as exactly).
constexpr double kFineErosion = 0.0005;  // m

// The most any point within r of c (a body's frame) moves from pose `from` to pose `to`.
double motionBound(const Eigen::Vector3d& c,
                   double r,
                   const Eigen::Isometry3d& from,
                   const Eigen::Isometry3d& to) {
  return (from * c - to * c).norm() + r * (from.linear() - to.linear()).norm();
}

// MapClearance::Travel's sums: over every joint and the table (kAll), the table and J1–J3
// (kArm), J4–J6 (kWristOnly); kWrist: the first wrist joint, 0-based.
constexpr std::uint8_t kAll = 0, kArm = 1, kWristOnly = 2;
constexpr int kWrist = 3;

// The travel sum a pair with a link reads: kArm when its weights on J4–J6 are all zero,
// kWristOnly when those on J1–J3 and its table lever are, else kAll. (A sum per pair's own span
// of joints was measured too: its upkeep cost more than it saved.)
std::uint8_t travelClass(const ChainLevers& levers, std::size_t p) {
  const ChainLevers::Weights& w = levers.weights(p);
  const auto zero = [&](int from, int to) {
    return std::all_of(w.begin() + from, w.begin() + to, [](double x) { return x == 0.0; });
  };
  if (zero(kWrist, kinematics::kNumJoints)) return kArm;
  if (levers.tableLever(p) == 0.0 && zero(0, kWrist)) return kWristOnly;
  return kAll;
}

}  // namespace

MapClearance::MapClearance(const Scene& scene, std::size_t branches, MapClearanceOptions options)
    : scene_(&scene),
      options_(options),
      levers_(scene),
      grid_(scene,
            levers_,
            kGridErosion,
            options.skip && !options.exact_distances ? kFineErosion : 0.0) {
  for (const detail::BodyGeometry& body : scene.geometry().map_bodies) {
    const auto [c, r] = detail::boundingSphere(body);
    centre_.push_back(c);
    radius_.push_back(r);
  }
  const std::size_t np = scene.pairs().size(), nb = scene.bodies().size();
  np_ = np;
  for (const BodyInfo& body : scene.bodies()) per_cell_.push_back(placedPerCell(body) ? 1 : 0);
  for (std::size_t p = 0; p < np; ++p) {
    const PairInfo& pair = scene.pairs()[p];
    const bool shared = per_cell_[static_cast<std::size_t>(pair.a)] != 0 &&
                        per_cell_[static_cast<std::size_t>(pair.b)] != 0;
    link_pair_.push_back(levers_.covers(p) && !shared ? 1 : 0);
  }
  memory_.resize(np * (1 + branches));
  far_until_.assign(np * branches, -kInf);
  cell_factor_.assign(np * branches, kUnknown);
  cell_q_.assign(branches, kinematics::JointVector::Zero());
  cell_seen_.assign(branches, 0);
  frames_.resize(branches);
  for (std::size_t p = 0; p < np; ++p) depth_.push_back(depthOf(scene, p, link_pair_[p] != 0));
  state_.resize(np);
  shared_factor_.assign(np, -1.0);
  travel_of_branch_.resize(branches);
  zero_pair_.assign(branches, np_);
  for (std::size_t p = 0; p < np; ++p) {
    if (!link_pair_[p]) continue;
    table_lever_ = std::max(table_lever_, levers_.tableLever(p));
    for (std::size_t k = 0; k < joint_levers_.size(); ++k) {
      joint_levers_[k] = std::max(joint_levers_[k], levers_.weights(p)[k]);
    }
  }
  for (std::size_t p = 0; p < np; ++p) {
    lever_.push_back(link_pair_[p] ? leverRatio(p) : 0.0);
    travel_class_.push_back(link_pair_[p] ? travelClass(levers_, p) : kAll);
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
  if (!table_seen_ || theta != theta_) X_WR_ = cell.table.X_WR(theta);  // one per θ row
  table_seen_ = true;
  theta_ = theta;
  const Eigen::Isometry3d& X_WR = X_WR_;
  const Eigen::Isometry3d X_W6 = cell.X_WB * X_BF;
  const Eigen::Isometry3d X_WS = X_W6 * cell.scanner.X_FS;
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
      case BodyMotion::kRobotLink:  // the base and link 6 here, the others per branch on use
        if (per_cell_[i]) place(i, scene_->bodies()[i].link == 0 ? cell.X_WB : X_W6);
        break;
    }
  }
  std::fill(shared_factor_.begin(), shared_factor_.end(), -1.0);
  std::fill(cell_seen_.begin(), cell_seen_.end(), 0);
}

const Eigen::Isometry3d& MapClearance::frame(int k) {
  Frames& own = frames_[branch_];
  while (own.upto < k) {
    const int next = own.upto + 1;
    const auto i = static_cast<std::size_t>(next);
    if (next <= agree_ && frames_[twin_].upto >= next) {
      own.X[i] = frames_[twin_].X[i];  // the same joints up to there: the same frame
    } else if (next == 0) {
      own.X[0] = scene_->cell().X_WB;
    } else {  // as RobotModel::linkFrames, product for product
      own.X[i] = own.X[i - 1] * scene_->cell().robot.dh(i - 1, (*q_)(next - 1));
    }
    own.upto = next;
  }
  return own.X[static_cast<std::size_t>(k)];
}

const Eigen::Isometry3d& MapClearance::pose(std::size_t i) {
  const BodyInfo& body = scene_->bodies()[i];
  if (per_cell_[i] || placed_[i]) return X_W_[i];
  X_W_[i] = frame(body.link);
  placed_[i] = true;
  return X_W_[i];
}

double MapClearance::factor(std::size_t branch, const kinematics::JointVector& q) {
  if (!q.allFinite()) throw std::invalid_argument("collision::MapClearance: non-finite joints");
  Travel& travel = travel_of_branch_.at(branch);
  q_ = &q;
  branch_ = branch;
  frames_[branch].upto = -1;
  std::fill(placed_.begin(), placed_.end(), false);
  if (travel.seen) addTravel(travel, q);
  travel.theta = theta_;
  travel.q = q;
  travel.seen = true;
  findTwin(branch, q);
  double* seen = cell_factor_.data() + np_ * branch;
  std::fill(seen, seen + np_, kUnknown);
  // The pair that zeroed this branch's last factor is likely to zero this one: asked first, a
  // zero ends the call before the pairs ahead of it in order are measured. The product is the
  // same either way (a zero anywhere makes it zero; otherwise the same factors in order).
  std::size_t& first = zero_pair_[branch];
  const double* sum = travel.sum.data();
  const std::uint8_t* travel_class = travel_class_.data();
  if (options_.skip && first < np_ && pairFactor(first, sum[travel_class[first]]) == 0.0) {
    return 0.0;
  }
  const double* far_until = far_until_.data() + np_ * branch;
  double f = 1.0;
  for (std::size_t p = 0; p < np_; ++p) {
    if (seen[p] == kUnknown && sum[travel_class[p]] <= far_until[p]) {  // most pairs: one test
      seen[p] = 1.0;
      continue;
    }
    const double fp = seen[p] != kUnknown ? seen[p] : pairFactor(p, sum[travel_class[p]]);
    if (fp == 1.0) continue;  // as ClearanceEvaluator::factor: no product with a pair beyond
    f *= fp;
    if (f == 0.0) {
      first = p;
      return 0.0;
    }
  }
  return f;
}

void MapClearance::addTravel(Travel& travel, const kinematics::JointVector& q) const {
  double arm = table_lever_ * std::abs(theta_ - travel.theta), wrist = 0.0;
  for (int k = 0; k < kinematics::kNumJoints; ++k) {
    const double step = joint_levers_[static_cast<std::size_t>(k)] * std::abs(q(k) - travel.q(k));
    (k < kWrist ? arm : wrist) += step;
  }
  travel.sum[kAll] += arm + wrist;
  travel.sum[kArm] += arm;
  travel.sum[kWristOnly] += wrist;
}

double MapClearance::pairFactor(std::size_t p, double travel) {
  const std::size_t slot = np_ * (1 + branch_) + p;
  double& seen = cell_factor_[np_ * branch_ + p];
  if (travel <= far_until_[slot - np_]) return seen = 1.0;  // a pair with a link that stays far
  const double* twin = twin_ < cell_q_.size() ? cell_factor_.data() + np_ * twin_ : nullptr;
  if (twin && depth_[p] <= agree_ && twin[p] != kUnknown) return seen = twin[p];
  if (!link_pair_[p]) {
    if (shared_factor_[p] < 0.0) shared_factor_[p] = sharedFactor(p);
    return seen = shared_factor_[p];
  }
  if (grid_.fine(p)) return seen = fineFactor(p, slot);
  return seen = linkFactor(p, slot, *q_, travel);
}

double MapClearance::fineFactor(std::size_t p, std::size_t slot) {
  const double lower = grid_.lower(p, *q_) - kMargin;
  if (lower == -kInf) return requery(p, slot, *q_);  // a joint outside its limits
  const PairThresholds& t = scene_->pairs()[p].thresholds;
  return lower >= t.d_high ? 1.0 : rampFactor(lower, t.d_low, t.d_high, t.gamma);
}

void MapClearance::findTwin(std::size_t branch, const kinematics::JointVector& q) {
  twin_ = cell_q_.size();
  agree_ = -1;  // no frame to share
  for (std::size_t b = 0; b < cell_q_.size(); ++b) {
    if (!cell_seen_[b] || b == branch) continue;
    int k = 0;
    while (k < kinematics::kNumJoints && cell_q_[b](k) == q(k)) ++k;
    if (k > std::max(agree_, 0)) {
      agree_ = k;
      twin_ = b;
    }
  }
  cell_q_[branch] = q;
  cell_seen_[branch] = 1;
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
    if (travel < memory.zero_until) return 0.0;
    const PairThresholds& t = scene_->pairs()[p].thresholds;
    const double moved =
        levers_.motion(p, levers_.weights(p), memory.theta, memory.q, theta_, q) + kMargin;
    // Far or deep enough: so until the branch has travelled the slack over the lever more.
    const auto until = [&](double slack) {
      return lever_[p] > 0.0 ? travel + slack / lever_[p] : kInf;
    };
    if (memory.lower - moved >= t.d_high) {
      far_until_[slot - np_] = until(memory.lower - moved - t.d_high);
      return 1.0;
    }
    if (memory.upper + moved < t.d_low) {
      memory.zero_until = until(t.d_low - memory.upper - moved);
      return 0.0;
    }
  }
  if (options_.skip && !options_.exact_distances && stillBelowLow(p, memory)) return 0.0;
  if (options_.skip && !options_.exact_distances && grid_.covers(p)) {
    const double lower = grid_.lower(p, q);
    const PairThresholds& t = scene_->pairs()[p].thresholds;
    if (lower - kMargin >= t.d_high) return anchorFar(p, slot, q, travel, lower);
  }
  return requery(p, slot, q);
}

bool MapClearance::stillBelowLow(std::size_t p, const Memory& memory) {
  const PairInfo& pair = scene_->pairs()[p];
  if (!memory.witness || !(memory.upper < pair.thresholds.d_low)) return false;
  // Below d_low at the last query. A point of each body from a query that found them apart:
  // their distance now bounds the pair's from above, far tighter than the lever bound.
  const double upper = (pose(static_cast<std::size_t>(pair.a)) * memory.w_a -
                        pose(static_cast<std::size_t>(pair.b)) * memory.w_b)
                           .norm();
  return upper + kMargin < pair.thresholds.d_low;
}

double MapClearance::anchorFar(std::size_t p,
                               std::size_t slot,
                               const kinematics::JointVector& q,
                               double travel,
                               double lower) {
  Memory& memory = memory_[slot];
  memory.theta = theta_;
  memory.q = q;
  memory.lower = lower;
  memory.upper = kInf;
  memory.factor = 1.0;
  memory.known = true;
  const double slack = lower - kMargin - scene_->pairs()[p].thresholds.d_high;
  far_until_[slot - np_] = lever_[p] > 0.0 ? travel + slack / lever_[p] : kInf;
  memory.zero_until = -kInf;
  return 1.0;
}

double MapClearance::requery(std::size_t p, std::size_t slot, const kinematics::JointVector& q) {
  Memory& memory = memory_[slot];
  memory.theta = theta_;
  memory.q = q;
  const double f = query(p, memory);
  far_until_[slot - np_] = memory.zero_until = -kInf;
  return f;
}

double MapClearance::leverRatio(std::size_t p) const {
  const ChainLevers::Weights& weights = levers_.weights(p);
  double ratio = table_lever_ > 0.0 ? levers_.tableLever(p) / table_lever_ : 0.0;
  for (std::size_t k = 0; k < weights.size(); ++k) {
    if (joint_levers_[k] > 0.0) ratio = std::max(ratio, weights[k] / joint_levers_[k]);
  }
  return ratio;
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
  const bool link = link_pair_[p] != 0;
  const detail::ShapeDistance d =
      detail::bodyDistance(bodies[a], X_a, bodies[b], X_b, t.d_high, false, link);
  if (link && !d.beyond && !d.penetrating) {  // the nearest points, in the bodies' frames
    memory.w_a = X_a.inverse() * d.p_a;
    memory.w_b = X_b.inverse() * d.p_b;
    memory.witness = true;
  }
  memory.lower = d.lower;
  memory.upper = d.beyond ? kInf : d.distance;
  memory.factor = d.beyond ? 1.0 : rampFactor(d.distance, t.d_low, t.d_high, t.gamma);
  memory.known = true;
  return memory.factor;
}

}  // namespace scanplan::collision
