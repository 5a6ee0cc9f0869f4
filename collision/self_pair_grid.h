#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <scanplan/collision/chain_levers.h>
#include <scanplan/collision/scene.h>

namespace scanplan::collision {

/// Lower bounds on the distance of the arm's own pairs (base, links, scanner: the pairs whose
/// bodies both ride on the arm), kept per bin of the joints between them.
///
/// Such a pair's distance depends only on the joints whose ChainLevers weight is not zero
/// (those between its links, less the ones its bodies turn about as solids of revolution), and
/// the configuration maps come back to the same few of those values again and again: along the
/// next table angle's row, and on the other branches. A bin of those joints is the box
/// |q_k − c_k| ≤ h_k about its centre c; at any q in it the distance is at least the distance at
/// c minus Σ w_k·h_k (ChainLevers' bound, which holds over every configuration). The widths
/// share the erosion E equally: h_k = E / (n·w_k) for the n joints. A bin is measured on first
/// use (FK at its centre, the other joints as asked) and kept; MapClearance asks here before it
/// measures a pair, and a bound at or above d_high gives the pair's factor, 1, exactly.
///
/// Only pairs with one or two such joints are kept: on the demo map their bins came back 10–500
/// times each, those of pairs with three to five joints 1.5–8 times, which did not pay for the
/// bins' measuring and looking up (callgrind: the same instruction count).
///
/// One per thread (not thread-safe). Memory: at most kMaxBins bins per pair.
class SelfPairGrid {
 public:
  /// Bins kept per pair (the demo map visits up to ~4 000 per pair and thread): the table
  /// stays within 2 MB a pair.
  static constexpr std::size_t kMaxBins = std::size_t{1} << 16;
  static constexpr int kMaxJoints = 2;

  /// erosion: E above, m (> 0).
  SelfPairGrid(const Scene& scene, const ChainLevers& levers, double erosion);

  /// True when the pair is one of the arm's own with one or two joints (above) between its
  /// bodies.
  bool covers(std::size_t pair) const { return grids_[pair].dims > 0; }
  /// A lower bound on the pair's distance at joints q (within the joints' limits), m; −∞ when
  /// the bin cannot be kept (q outside the limits, or the pair's bins all used).
  double lower(std::size_t pair, const kinematics::JointVector& q);
  /// Bins measured so far, over every pair.
  std::size_t measured() const { return measured_; }

 private:
  struct Grid {
    int dims = 0;
    std::array<double, kinematics::kNumJoints> width{};       ///< 2h_k, rad; 0: not a dimension
    std::array<double, kinematics::kNumJoints> per_width{};   ///< 1 / width
    std::array<double, kinematics::kNumJoints> origin{};      ///< the joint's lower limit, rad
    std::array<std::int64_t, kinematics::kNumJoints> bins{};  ///< bins along each joint
    double erosion = 0.0;                                     ///< Σ w_k·h_k, m
    double cap = 0.0;  ///< measured exactly up to d_high + erosion (beyond: far is all)
    // Open addressing, linear probing: key + 1 (0 = empty), and the bin's bound.
    std::vector<std::uint64_t> keys;
    std::vector<double> bounds;
    std::size_t used = 0;
  };
  static Grid gridOf(const kinematics::RobotModel& robot,
                     const ChainLevers::Weights& w,
                     double d_high,
                     double erosion);
  /// The bin of q as one number, or false when q is outside the limits.
  bool keyOf(const Grid& grid, const kinematics::JointVector& q, std::uint64_t& key) const;
  double measure(std::size_t pair,
                 const Grid& grid,
                 std::uint64_t key,
                 kinematics::JointVector q) const;
  void grow(Grid& grid);

  const Scene* scene_;
  std::vector<Grid> grids_;
  std::size_t measured_ = 0;
};

}  // namespace scanplan::collision
