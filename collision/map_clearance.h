#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Geometry>

#include "collision/chain_levers.h"
#include "collision/scene.h"

namespace scanplan::collision {

/// How MapClearance measures.
struct MapClearanceOptions {
  /// Motion-bound skipping (below). False: every pair is queried, the reference the skipping
  /// is tested against.
  bool skip = true;
  /// Plain fcl::distance on every pair (ClearanceEvaluator::evaluate unbounded) instead.
  bool exact_distances = false;
};

/// The configuration maps' clearance factor (ClearanceEvaluator::factor), cell after cell and
/// branch after branch, with the work that repeats between them left out:
/// - The scanner is placed at the cell's flange target, the pose every branch reaches, so the
///   pairs without an arm link (scanner, table, part, world) are measured once per cell for all
///   branches.
/// - Motion-bound skipping: each pair remembers its last query (per branch for pairs with an
///   arm link): the bodies' poses then, a lower bound on the distance and, when it was below
///   d_high, the distance. A body's points have moved at most the sum of |Δc| + r·‖ΔR‖_F over
///   the steps since (c, r: its bounding sphere). While the lower bound minus both motions stays
///   at or above d_high the pair's factor is 1 without a query; while the distance plus both
///   motions stays below d_low it is 0; with neither body moved, the last factor holds. For two
///   bodies that both move with the arm, the motion of one in the other's frame is bounded the
///   by the joints between them (ChainLevers: the distance does not change when both move
///   together): the wrist's links move little relative to each other while the arm swings.
/// Every factor equals the plain query's (a 1e-6 m margin covers GJK's tolerance), so the
/// maps do not depend on the skipping, nor on which cells a thread saw before. One per thread.
class MapClearance {
 public:
  MapClearance(const Scene& scene, std::size_t branches, MapClearanceOptions options = {});

  /// Starts a cell: the table angle θ (rad) and the flange target X_BF (robot base frame).
  void beginCell(double theta, const Eigen::Isometry3d& X_BF);
  /// The clearance factor at this cell of branch `branch` (< branches) with joints q (rad).
  double factor(std::size_t branch, const kinematics::JointVector& q);

 private:
  /// A pair's last query: what the bound checks read on every call.
  struct Memory {
    double travel = 0.0;  ///< the two bodies' travel then, summed
    double lower = 0.0;   ///< m, a lower bound on the distance then
    double upper = 0.0;   ///< m, the distance then when below d_high, else +∞
    double factor = 1.0;
    bool known = false;
  };
  /// The rest of it, read when a bound does not decide.
  struct Poses {
    Eigen::Isometry3d X_a = Eigen::Isometry3d::Identity(), X_b = Eigen::Isometry3d::Identity();
    kinematics::JointVector q = kinematics::JointVector::Zero();  ///< the branch's joints then
  };
  /// The factor of `pair` at branch `branch` with joints q, its memory at `slot`.
  double pairFactor(std::size_t pair,
                    std::size_t branch,
                    std::size_t slot,
                    const kinematics::JointVector& q);
  /// Moves body i to X_W in chain `chain` (0: the bodies without an arm link, per cell; 1 + b:
  /// branch b's arm links), adding the most any of its points moved to its travel.
  void place(std::size_t chain, std::size_t i, const Eigen::Isometry3d& X_W);
  std::size_t chainOf(std::size_t body, std::size_t branch) const;

  const Scene* scene_;
  MapClearanceOptions options_;
  std::vector<bool> shared_;             ///< per pair: no arm link in it
  ChainLevers levers_;                   ///< joint-difference bounds for pairs on the arm
  std::vector<Eigen::Vector3d> centre_;  ///< per body: bounding-sphere centre, body frame
  std::vector<double> radius_;           ///< per body: bounding-sphere radius, m
  std::vector<Memory> memory_;           ///< shared pairs, then [branch][pair] for the others
  std::vector<Poses> poses_;             ///< the same slots
  std::vector<double> shared_factor_;    ///< this cell's factor of each shared pair, or < 0
  std::vector<Eigen::Isometry3d> X_W_;   ///< body poses at this cell (arm links per branch)
  /// Per chain and body: its last pose, whether it has one, and the sum of the most any of its
  /// points moved at each step (|Δc| + r·‖ΔR‖_F), m: a bound on how far it moved since any
  /// earlier time by the difference of two sums.
  std::vector<Eigen::Isometry3d> last_;
  std::vector<bool> placed_;
  std::vector<double> travel_;
};

}  // namespace scanplan::collision
