#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <utility>

#include <scanplan/collision/scene.h>

namespace scanplan::collision {

namespace detail {
struct BodyGeometry;
/// |a − b| modulo a whole turn.
inline double turn(double a, double b) {
  constexpr double kTurn = 2.0 * std::numbers::pi;
  const double d = std::abs(a - b);
  if (d <= std::numbers::pi) return d;  // the usual step: no remainder to take
  const double t = std::fmod(d, kTurn);
  return std::min(t, kTurn - t);
}
/// A body's bounding sphere in its frame: the mean of its shapes' sphere centres, and the radius
/// reaching around them all.
std::pair<Eigen::Vector3d, double> boundingSphere(const BodyGeometry& body);
/// The axis link k (1–6) turns about, joint k's (z_{k−1}), in the link's own DH frame: a point
/// on it and its unit direction.
std::pair<Eigen::Vector3d, Eigen::Vector3d> ownJointAxis(const kinematics::RobotModel& robot,
                                                         int k);
}  // namespace detail

/// Joint-difference motion bounds for the pairs with a robot link: how much
/// their distance can change between two (table angle, joints) states, without placing them.
///
/// When joint k turns by Δ, a point at distance ρ from its axis moves by 2ρ·sin(|Δ|/2) ≤ ρ·|Δ|.
/// Relative to a body before joint k, a body after it turns about that axis; relative to the
/// body after it, the body before turns the other way: either way the distance between the two
/// changes by at most min(ρ_before, ρ_after)·|Δ|. Turning the table first (a body on it moves
/// by at most its reach from the table axis times |Δθ|), then the joints between the two bodies
/// one after another, the distance changes by at most L_θ·|Δθ| + Σ_k w_k·|Δq_k|, where w_k
/// bounds that minimum over every configuration:
/// - a body on link j after joint k (j ≥ k): exact about its own joint's axis (j = k: the
///   farthest shape point, 0 for shapes turning about their own axis, as a cylinder on it);
///   else |a_k| + Σ_{m=k+1..j} √(a_m² + d_m²) + the body's reach from its frame origin;
/// - a body on link j before joint k (j < k; the world and table bodies count as link 0):
///   exact about the next joint's axis (j = k − 1; a table body over every table angle), else
///   its reach from its frame origin + Σ_{m=j+1..k−1} √(a_m² + d_m²).
/// The base is link 0, the scanner is on link 6. Angle differences are taken modulo a turn.
class ChainLevers {
 public:
  using Weights = std::array<double, 6>;  ///< m per rad, joints 1..6

  explicit ChainLevers(const Scene& scene);

  /// True when the pair has a robot link: its motion is bounded here.
  bool covers(std::size_t pair) const { return covers_[pair]; }
  /// The pair's weights (zero outside the joints between its bodies).
  const Weights& weights(std::size_t pair) const { return weights_[pair].w; }
  /// L_θ: the reach from the table axis of the pair's body on the table (0 without one), m.
  double tableLever(std::size_t pair) const { return weights_[pair].table; }
  /// The pair's body after the joints between them (the one on the later link).
  std::size_t distal(std::size_t pair) const { return weights_[pair].distal; }
  /// How much the distance between the pair's bodies can change from (θ0, q0) to (θ1, q1), m,
  /// with `weights` (the pair's).
  /// Inline: the maps ask it for every pair at every branch-cell.
  double motion(std::size_t pair,
                const Weights& weights,
                double theta0,
                const kinematics::JointVector& q0,
                double theta1,
                const kinematics::JointVector& q1) const {
    const double table = weights_[pair].table;
    double motion = table == 0.0 ? 0.0 : table * detail::turn(theta1, theta0);
    double widest = 0.0;
    for (int k = 0; k < kinematics::kNumJoints; ++k) {
      const double d = std::abs(q1(k) - q0(k));
      widest = std::max(widest, d);
      motion += weights[static_cast<std::size_t>(k)] * d;
    }
    // The usual steps (every joint within half a turn) need no remainder.
    if (widest <= std::numbers::pi) return motion;
    return wideMotion(table == 0.0 ? 0.0 : table * detail::turn(theta1, theta0), weights, q0, q1);
  }

 private:
  /// motion() with a joint more than half a turn away, from the table's share: every joint's
  /// difference modulo a turn.
  static double wideMotion(double table_motion,
                           const Weights& weights,
                           const kinematics::JointVector& q0,
                           const kinematics::JointVector& q1);

  struct PairWeights {
    Weights w{};
    double table = 0.0;
    std::size_t distal = 0;
  };
  std::vector<bool> covers_;
  std::vector<PairWeights> weights_;
};

}  // namespace scanplan::collision
