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
/// use (FK at its centre, the other joints at 0) and kept; the bound at q is the distance
/// at c less Σ w_k·|q_k − c_k|, at most 2E below the distance at q. MapClearance asks here
/// before it measures a pair, and a bound at or above d_high gives the pair's factor, 1, exactly.
///
/// Fine pairs: an arm pair with one or two joints measured as a stand-in (a link mesh as its
/// convex pieces or hull, and no mesh measured exactly: tens of GJK queries a measure, where
/// primitives take one closed form) gets bins of the finer erosion, and MapClearance takes its
/// factor from the bound alone, never from a query: at most 2E_fine nearer than the pair is, never
/// farther. (Its coarse bin is asked first: far there, the pair is far without a fine bin
/// measured.) Such a bound depends on q alone (when the pair's table is full it is measured and not
/// kept), so the maps still do not depend on the order of the cells.
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
  /// Bins kept per fine pair (the KR6 R700's link 4–link 6 at 0.5 mm: ~80 000 on the rings
  /// demo): within 8 MB a pair.
  static constexpr std::size_t kMaxFineBins = std::size_t{1} << 18;
  static constexpr int kMaxJoints = 2;

  /// erosion, fine_erosion: E and E_fine above, m (> 0); fine_erosion 0: no fine pairs.
  SelfPairGrid(const Scene& scene,
               const ChainLevers& levers,
               double erosion,
               double fine_erosion = 0.0);

  /// True when the pair is one of the arm's own with one or two joints (above) between its
  /// bodies.
  bool covers(std::size_t pair) const { return grids_[pair].dims > 0; }
  /// True for a fine pair (above): its factor is the bound's.
  bool fine(std::size_t pair) const { return grids_[pair].fine; }
  /// A lower bound on the pair's distance at joints q (within the joints' limits), m; −∞ when
  /// the bin cannot be kept (q outside the limits, or the pair's bins all used).
  double lower(std::size_t pair, const kinematics::JointVector& q);
  /// Bins measured so far, over every pair.
  std::size_t measured() const { return measured_; }

 private:
  struct Grid {
    int dims = 0;
    bool fine = false;
    std::size_t max_bins = kMaxBins;
    std::array<double, kinematics::kNumJoints> width{};       ///< 2h_k, rad; 0: not a dimension
    std::array<double, kinematics::kNumJoints> per_width{};   ///< 1 / width
    std::array<double, kinematics::kNumJoints> origin{};      ///< the joint's lower limit, rad
    std::array<double, kinematics::kNumJoints> weight{};      ///< w_k, m/rad
    std::array<std::int64_t, kinematics::kNumJoints> bins{};  ///< bins along each joint
    double cap = 0.0;  ///< measured exactly up to d_high + erosion (beyond: far is all)
    double far = 0.0;  ///< a bound at or above this settles the pair (d_high and GJK's tolerance)
    // Open addressing, linear probing: key + 1 (0 = empty), and the distance at the bin's centre
    // (a lower bound, beyond the cap).
    std::vector<std::uint64_t> keys;
    std::vector<double> centre;
    std::size_t used = 0;
  };
  static Grid gridOf(const kinematics::RobotModel& robot,
                     const ChainLevers::Weights& w,
                     double d_high,
                     double erosion);
  /// The bin of q as one number, and Σ w_k·|q_k − c_k| over its centre c (m); false when q is
  /// outside the limits.
  bool keyOf(const Grid& grid,
             const kinematics::JointVector& q,
             std::uint64_t& key,
             double& offset) const;
  /// The pair's distance at the bin's centre (the other joints at 0), exactly below the cap.
  double measure(std::size_t pair, const Grid& grid, std::uint64_t key) const;
  void grow(Grid& grid);
  /// The bound of q's bin of `grid` (the pair's, or its coarse one), measured on first use.
  double binLower(std::size_t pair, Grid& grid, const kinematics::JointVector& q);

  const Scene* scene_;
  std::vector<Grid> grids_;
  /// Fine pairs: bins of the coarse erosion, asked first; a bound at or above d_high there
  /// settles the pair without a fine bin.
  std::vector<Grid> coarse_;
  std::size_t measured_ = 0;
};

}  // namespace scanplan::collision
