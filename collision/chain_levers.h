#pragma once

#include <array>
#include <cstddef>

#include "collision/scene.h"

namespace scanplan::collision {

/// Joint-difference motion bounds for two bodies the arm carries (the base as link 0, links
/// 1–6, the scanner on link 6; issue 20 item 2).
///
/// When joint k turns by Δ, a point at distance ρ from its axis moves by 2ρ·sin(|Δ|/2) ≤ ρ·|Δ|.
/// Relative to a body before joint k, a body after it turns about that axis; relative to the
/// body after it, the body before turns the other way: either way the distance between the two
/// changes by at most min(ρ_before, ρ_after)·|Δ|. Turning the joints between two bodies one
/// after another, the distance changes by at most Σ_k w_k·|Δq_k|, where w_k bounds that
/// minimum over every configuration:
/// - a body on link j after joint k (j ≥ k): exact about its own joint's axis (j = k: the
///   farthest shape point, 0 for shapes turning about their own axis, as a cylinder on it);
///   else |a_k| + Σ_{m=k+1..j} √(a_m² + d_m²) + the body's reach from its frame origin;
/// - a body on link j before joint k (j < k): exact about the next joint's axis (j = k − 1),
///   else its reach from its origin + Σ_{m=j+1..k−1} √(a_m² + d_m²).
/// Δq is taken modulo a whole turn (the same pose).
class ChainLevers {
 public:
  using Weights = std::array<double, 6>;  ///< m per rad, joints 1..6

  explicit ChainLevers(const Scene& scene);

  /// True when both bodies of the pair are carried by the arm.
  bool together(std::size_t pair) const { return together_[pair]; }
  /// The pair's weights (zero outside the joints between its bodies).
  const Weights& weights(std::size_t pair) const { return weights_[pair]; }
  /// How much the distance between the pair's bodies can change from joints q0 to q1, m.
  double relativeMotion(std::size_t pair,
                        const kinematics::JointVector& q0,
                        const kinematics::JointVector& q1) const;

 private:
  std::vector<bool> together_;
  std::vector<Weights> weights_;
};

}  // namespace scanplan::collision
