#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/collision/chain_levers.h>
#include <scanplan/collision/scene.h>
#include <scanplan/collision/self_pair_grid.h>

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
/// - Every branch reaches the cell's flange target, so link 6 is placed there (X_WB · X_BF) and
///   the scanner on it, like the base, the table and the world once per cell: the pairs between
///   those bodies (link 6 or the scanner against the part, the table or the base, …) are
///   measured once per cell for all branches, bounded by how far their bodies moved. Below, "a
///   pair with a link" is one with a body on links 1–5, placed per branch by FK; the others
///   are "shared".
/// - Motion-bound skipping: each pair remembers its last query (per branch for pairs with a
///   link): a lower bound on the distance then and, when it was below d_high, the distance.
///   For a pair with a link, ChainLevers bounds how much the distance can have changed since
///   from the differences of the table angle and the joints; for a shared pair, a body's points
///   have moved at most the sum of |Δc| + r·‖ΔR‖_F over the steps since (c, r: its bounding
///   sphere). While the lower bound minus that stays at or above d_high the pair's factor is 1
///   without a query; while the distance plus that stays below d_low it is 0; for a shared
///   pair, with nothing moved, the last factor holds. Links 1–5 are placed (FK) only for the
///   pairs that query.
/// - Travel marks: a pair with a link that the bound showed far (or deep) enough is not even
///   bounded again until its branch has travelled (Travel, below) its slack over its lever ratio.
/// - Nearest points: a pair with a link keeps a point of each body from its last query that
///   found them apart. While the pair was below d_low then, those two points, placed at this
///   cell, bound its distance from above: below d_low still, the factor is 0 without a query.
/// - The arm's own pairs with one or two joints between them: before a query, SelfPairGrid's
///   bound for the bin of those joints; at or above d_high the pair is 1, and its memory is
///   anchored there. A fine pair of them (measured as a stand-in: a link mesh as its convex
///   pieces or hull) takes its factor from that bound alone, never from a query: its
///   factor is then at most that of a distance 1 mm nearer (SelfPairGrid), never more.
/// - Branches share: a pair's factor depends only on the joints up to its last link placed per
///   branch, so a branch takes it from one scored before at the same cell with the same values
///   of those joints (FLIP and NOFLIP share J1–J3), and the DH frames the same way. Links are
///   placed by FK up to the frame asked for.
/// - The zero pair first: each branch asks first the pair that zeroed its last factor; a zero
///   again ends the call before the pairs ahead of it are measured (on the demo with hull links,
///   where most cells are zero, this takes 40 % off the map).
/// Every factor but a fine pair's equals the plain query's (a 1e-6 m margin covers GJK's
/// tolerance), and a fine pair's depends on its joints alone, so the maps do not depend on which
/// cells a thread saw before. One per thread.
class MapClearance {
 public:
  MapClearance(const Scene& scene, std::size_t branches, MapClearanceOptions options = {});

  /// Starts a cell: the table angle θ (rad) and the flange target X_BF (robot base frame).
  void beginCell(double theta, const Eigen::Isometry3d& X_BF);
  /// The clearance factor at this cell of branch `branch` (< branches) with joints q (rad): an
  /// IK solution of the cell's flange target (link 6 and the scanner are placed at the target).
  double factor(std::size_t branch, const kinematics::JointVector& q);

 private:
  /// A pair's last query: what the bound checks read on every call, together in one place.
  struct Memory {
    double travel = 0.0;  ///< shared pairs: the two bodies' travel then, summed
    double lower = 0.0;   ///< m, a lower bound on the distance then
    double upper = 0.0;   ///< m, the distance then when below d_high, else +∞
    double factor = 1.0;
    bool known = false;
    // Pairs with a link: the table angle and joints then.
    double theta = 0.0;
    kinematics::JointVector q = kinematics::JointVector::Zero();
    /// Pairs with a link: the factor is 0 while the branch's travel stays below zero_until
    /// (−∞: not known); far_until_ below says when it is 1.
    double zero_until = -std::numeric_limits<double>::infinity();
    /// Pairs with a link: a point of each body (body frames) from the last query that found
    /// them apart and near, if any: any two points of the bodies bound their distance above.
    Eigen::Vector3d w_a = Eigen::Vector3d::Zero(), w_b = Eigen::Vector3d::Zero();
    bool witness = false;
  };
  /// Per branch: three sums over the steps between its factor() calls of the terms of
  /// L_θ·|Δθ| + Σ_k L_k·|Δq_k| (m; L: the largest lever of any pair, the table's and each
  /// joint's): all of them; the table's and J1–J3's; J4–J6's. And the last call's table angle
  /// and joints. A pair's distance changes by at most its lever ratio times the travel since, in
  /// the sum it reads (travel_class_: the one side it depends on, else all), so a pair that the
  /// exact bound showed far (or deep) enough stays so without a bound evaluated until that sum
  /// reaches the pair's mark.
  struct Travel {
    std::array<double, 3> sum{};
    double theta = 0.0;
    kinematics::JointVector q = kinematics::JointVector::Zero();
    bool seen = false;
  };
  /// Shared pairs: the bodies' poses at the last query (the same poses, the same query).
  struct State {
    Eigen::Isometry3d X_a = Eigen::Isometry3d::Identity(), X_b = Eigen::Isometry3d::Identity();
  };
  /// Finds the branch scored earlier at this cell whose joints agree with q from J1 on for the
  /// most joints (twin_, agree_; none: twin_ = branches, agree_ = −1); records q as this branch's.
  void findTwin(std::size_t branch, const kinematics::JointVector& q);
  /// Pair p's factor at this cell and branch (travel: the branch's), recorded in cell_factor_.
  [[gnu::always_inline]] inline double pairFactor(std::size_t p, double travel);
  /// Adds the step from the branch's last call to (θ, q) to each of its travel sums.
  void addTravel(Travel& travel, const kinematics::JointVector& q) const;
  double sharedFactor(std::size_t pair);
  /// A fine pair's factor (SelfPairGrid::fine): its bin's bound's, q outside the limits
  /// measured.
  double fineFactor(std::size_t pair, std::size_t slot);
  double linkFactor(std::size_t pair,
                    std::size_t slot,
                    const kinematics::JointVector& q,
                    double travel);
  /// Whether a pair with a link, below d_low at its last query, is so still by the nearest
  /// points kept then (Memory::w_a, w_b).
  bool stillBelowLow(std::size_t pair, const Memory& memory);
  /// A pair with a link that SelfPairGrid showed far: its memory anchored at q with that bound.
  double anchorFar(std::size_t pair,
                   std::size_t slot,
                   const kinematics::JointVector& q,
                   double travel,
                   double lower);
  /// linkFactor's query, out of line: the bound checks before it stay small.
  [[gnu::noinline]] double requery(std::size_t pair,
                                   std::size_t slot,
                                   const kinematics::JointVector& q);
  double query(std::size_t pair, Memory& memory);
  /// The largest ratio of the pair's weights (and its table lever) to the scene's.
  double leverRatio(std::size_t pair) const;
  /// DH frame k in the world (X_WB · X_Bk) at this branch's joints: by FK on first use, up to k
  /// only, and taken from the twin as far as their joints agree.
  const Eigen::Isometry3d& frame(int k);
  /// Body i's pose at this cell and branch: links 1–5 by FK on first use.
  const Eigen::Isometry3d& pose(std::size_t i);
  /// Moves a body placed once per cell to X_W, adding the most any of its points moved to its
  /// travel.
  void place(std::size_t i, const Eigen::Isometry3d& X_W);

  const Scene* scene_;
  MapClearanceOptions options_;
  ChainLevers levers_;                   ///< bounds for the pairs with a link
  SelfPairGrid grid_;                    ///< the arm's own pairs: bounds per bin of joints
  std::vector<Eigen::Vector3d> centre_;  ///< per body: bounding-sphere centre, body frame
  std::vector<double> radius_;           ///< per body: bounding-sphere radius, m
  std::size_t np_ = 0;                   ///< pairs
  /// Per body: placed once per cell for every branch (beginCell), not per branch by FK.
  std::vector<char> per_cell_;
  /// Per pair: a body placed per branch on one side and ChainLevers' bounds, so memories per
  /// branch; else one memory for all branches and the bodies' travel (sharedFactor).
  std::vector<char> link_pair_;
  std::vector<Memory> memory_;  ///< per pair (for all branches), then [branch][pair]
  /// [branch][pair]: a pair with a link is 1 while its branch's travel stays at or below this
  /// (−∞: not known; shared pairs stay −∞). Apart from Memory: factor() reads it for
  /// every pair at every call.
  std::vector<double> far_until_;
  /// Work shared between branches: a pair's factor depends on the table angle, the cell's
  /// flange target and the joints up to its last link placed per branch (depth_), so a branch takes
  /// it from another scored at this cell with the same values of those joints (IK's FLIP and
  /// NOFLIP solutions share J1–J3).
  std::vector<int> depth_;  ///< per pair: that last joint (1-based; > 6: a shared pair, not so)
  std::vector<double> cell_factor_;  ///< [branch][pair] at this cell, kUnknown if not scored
  std::vector<kinematics::JointVector> cell_q_;  ///< per branch: its joints at this cell
  std::vector<char> cell_seen_;                  ///< per branch: scored at this cell
  std::vector<State> state_;                     ///< per shared pair
  std::vector<double> shared_factor_;            ///< this cell's factor of each shared pair, or < 0
  std::vector<Travel> travel_of_branch_;
  /// Per branch: the pair that made its last zero factor (np_: none yet), asked first next time.
  std::vector<std::size_t> zero_pair_;
  double table_lever_ = 0.0;  ///< L_θ: the largest table lever of any pair, m/rad
  /// Per pair with a link: the largest ratio of its weights (and table lever) to the L's: its
  /// distance changes by at most that times its branch's travel.
  std::vector<double> lever_;
  std::vector<std::uint8_t> travel_class_;  ///< per pair: the Travel sum it reads
  ChainLevers::Weights joint_levers_{};     ///< L_k: the largest weight of joint k of any pair
  // This cell: θ, the table top's pose then, the branch's joints and link frames (when computed).
  double theta_ = 0.0;
  Eigen::Isometry3d X_WR_ = Eigen::Isometry3d::Identity();
  bool table_seen_ = false;
  const kinematics::JointVector* q_ = nullptr;
  std::size_t branch_ = 0;
  struct Frames {
    std::array<Eigen::Isometry3d, kinematics::kNumJoints + 1> X;
    int upto = -1;  ///< X[0..upto] computed at this cell
  };
  std::vector<Frames> frames_;  ///< per branch, this cell
  std::size_t twin_ = 0;        ///< findTwin's
  int agree_ = 0;
  std::vector<Eigen::Isometry3d> X_W_;  ///< body poses at this cell and branch
  std::vector<bool> placed_;            ///< robot links placed at this branch
  /// Per body placed per cell: its last pose, whether it has one, and the sum of the most any of
  /// its points moved at each step (|Δc| + r·‖ΔR‖_F), m: a bound on how far it moved since any
  /// earlier time by the difference of two sums.
  std::vector<Eigen::Isometry3d> last_;
  std::vector<bool> seen_;
  std::vector<double> travel_;
};

}  // namespace scanplan::collision
