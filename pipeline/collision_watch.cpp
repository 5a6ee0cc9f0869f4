#include <scanplan/pipeline/collision_watch.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <scanplan/kinematics/joint_wrap.h>

namespace scanplan::pipeline {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
/// A pair counts as getting closer when its least predicted distance is this much below now (m):
/// measurement noise and the distance queries' own tolerance stay below it.
constexpr double kCloser = 1e-4;
/// Bisection rounds for the time of first contact between two predicted poses.
constexpr int kContactRounds = 6;

}  // namespace

struct CollisionWatch::Prediction {
  std::vector<double> closest;  ///< per pair, m; kInf where never within the bound
  std::vector<double> at;       ///< per pair, s to the least distance
  std::vector<char> stop;       ///< per pair: below the stop distance within stop_time
  std::vector<char> touching;   ///< per pair: in contact at `contact`
  std::optional<double> contact;
  double predicted = 0.0;
};

CollisionWatch::CollisionWatch(const collision::Scene& scene,
                               const Eigen::Isometry3d& X_FT,
                               const WatchOptions& options)
    : scene_(&scene),
      options_(options),
      model_(scene.cell().robot, X_FT, options.model),
      evaluator_(scene) {
  if (options.window < 3) throw std::invalid_argument("CollisionWatch: window below 3 samples");
  if (!(options.horizon > 0.0) || !(options.step > 0.0) || !std::isfinite(options.horizon)) {
    throw std::invalid_argument("CollisionWatch: horizon and step must be positive");
  }
  if (!(options.warn_distance > 0.0) || !std::isfinite(options.warn_distance)) {
    throw std::invalid_argument("CollisionWatch: warning distance must be positive");
  }
  window_.reserve(options.window + 1);
}

double CollisionWatch::contactTime(const kinematics::MotionFit& fit, double before, double at) {
  collision::ClearanceRequest request;
  request.bound = options_.warn_distance;
  for (int round = 0; round < kContactRounds; ++round) {
    const double mid = 0.5 * (before + at);
    const auto pose = model_.predict(fit, window_.back(), mid);
    if (!pose) return before;
    const bool touching = evaluator_.evaluate(pose->theta, pose->q, request).collision;
    (touching ? at : before) = mid;
  }
  return before;  // the last time seen free: contact comes after it
}

CollisionWatch::Prediction CollisionWatch::predictAhead(const kinematics::MotionFit& fit) {
  const std::size_t pairs = scene_->pairs().size();
  Prediction p{std::vector<double>(pairs, kInf),
               std::vector<double>(pairs, 0.0),
               std::vector<char>(pairs, 0),
               std::vector<char>(pairs, 0),
               std::nullopt,
               0.0};
  collision::ClearanceRequest request;
  request.bounded = options_.bounded;
  request.bound = std::max(options_.warn_distance, options_.stop_distance);
  const auto steps = static_cast<int>(std::ceil(options_.horizon / options_.step - 1e-9));
  double before = 0.0;
  for (int i = 1; i <= steps; ++i) {
    const double tau = std::min(i * options_.step, options_.horizon);
    const auto pose = model_.predict(fit, window_.back(), tau);
    if (!pose) break;  // out of reach or limits: the controller stops the motion there
    p.predicted = tau;
    const collision::ClearanceResult r = evaluator_.evaluate(pose->theta, pose->q, request);
    for (std::size_t k = 0; k < pairs; ++k) {
      const collision::PairClearance& c = r.pairs[k];
      if (c.beyond_bound || c.distance >= request.bound) continue;
      if (c.distance < p.closest[k]) {
        p.closest[k] = c.distance;
        p.at[k] = tau;
      }
      const bool soon = tau <= options_.stop_time + 1e-12;
      if (soon && c.distance < options_.stop_distance) p.stop[k] = 1;
      if (c.penetrating) p.touching[k] = 1;
    }
    if (r.collision) {
      p.contact = contactTime(fit, before, tau);
      for (std::size_t k = 0; k < pairs; ++k) {
        if (!p.touching[k]) continue;
        p.at[k] = *p.contact;
        if (options_.stop_distance >= 0.0 && *p.contact <= options_.stop_time) p.stop[k] = 1;
      }
      break;  // the motion cannot go on through a contact
    }
    before = tau;
  }
  return p;
}

WatchStep CollisionWatch::push(const kinematics::AxisSample& sample) {
  if (!std::isfinite(sample.t) || !std::isfinite(sample.theta) || !sample.q.allFinite()) {
    throw std::invalid_argument("CollisionWatch: non-finite sample");
  }
  if (!window_.empty() && !(sample.t > window_.back().t)) {
    throw std::invalid_argument("CollisionWatch: sample times must increase strictly");
  }
  // A controller may report an endless axis (or a joint) wrapped to ±180°: each axis is taken at
  // the turn nearest the previous sample, which is the same pose, so the motion stays continuous.
  kinematics::AxisSample s = sample;
  if (!window_.empty()) {
    s.theta = kinematics::nearestTurn(s.theta, window_.back().theta);
    s.q = kinematics::unwrapNear(s.q, window_.back().q);
  }
  window_.push_back(s);
  if (window_.size() > options_.window) window_.erase(window_.begin());

  WatchStep step;
  step.t = sample.t;
  step.fit = model_.fit(window_);
  if (step.fit.kind == kinematics::MotionKind::kStill) return step;

  collision::ClearanceRequest request;
  request.bounded = options_.bounded;
  request.bound = std::max(options_.warn_distance, options_.stop_distance);
  const collision::ClearanceResult now = evaluator_.evaluate(s.theta, s.q, request);
  const Prediction p = predictAhead(step.fit);
  step.predicted = p.predicted;
  for (std::size_t k = 0; k < p.closest.size(); ++k) {
    const collision::PairClearance& c = now.pairs[k];
    const bool far = c.beyond_bound || c.distance >= request.bound;
    const double d_now = far ? request.bound : c.distance;
    const bool within = p.closest[k] < options_.warn_distance || p.stop[k];
    // In contact now and still at the next predicted pose: not moving out of it.
    const bool stuck = c.penetrating && p.touching[k];
    if (!within || !(p.closest[k] < d_now - kCloser || stuck)) continue;  // not getting closer
    WatchWarning w;
    w.pair = static_cast<int>(k);
    w.distance_now = d_now;
    w.far_now = far;
    w.closest = p.touching[k] ? 0.0 : p.closest[k];
    w.time_to_closest = p.at[k];
    if (p.touching[k]) w.time_to_contact = p.contact;
    w.stop = p.stop[k] != 0;
    step.stop = step.stop || w.stop;
    step.warnings.push_back(w);
  }
  return step;
}

}  // namespace scanplan::pipeline
