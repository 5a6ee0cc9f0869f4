#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include <scanplan/collision/map_clearance.h>
#include <scanplan/collision/scene.h>
#include <scanplan/kinematics/robot_model.h>
#include <scanplan/kinematics/scan_path.h>
#include <scanplan/planner/constraints.h>

namespace scanplan::planner {

/// Which constraint limits a map cell (the lowest factor group).
enum class Limit : std::uint8_t {
  kNone = 0,         ///< every factor is 1
  kUnreachable = 1,  ///< no IK solution on this branch
  kJointLimit = 2,   ///< Eq. 7
  kSingularity = 3,  ///< wrist, elbow, shoulder ramps
  kClearance = 4,    ///< Eq. 8 (collision included)
};
inline constexpr int kLimitCount = 5;
const char* limitName(Limit limit);

struct MapRequest {
  double angle_step = 0.017453292519943295;    ///< rad
  std::vector<kinematics::IkBranch> branches;  ///< one map per branch
  std::size_t memory_limit_bytes = std::size_t{8192} << 20;
  /// Plain fcl::distance for every pair instead of the bounded query (the benchmark's
  /// reference); the maps must come out identical.
  bool exact_distances = false;
  /// Motion-bound skipping and per-cell sharing (collision::MapClearance). False: every pair
  /// queried at every branch-cell, the reference the maps must equal.
  bool motion_bounds = true;
};

/// Configuration maps over table angle × time (seed §7.2, Fig. 6), one per IK branch. Each
/// layer is float32 in [branch][angle][time] order; `limit` says which constraint is lowest.
struct ConfigMap {
  std::vector<double> angles;  ///< rad
  std::vector<double> times;   ///< s
  std::vector<kinematics::IkBranch> branches;
  std::vector<float> f;            ///< Eq. 6, the product
  std::vector<float> joint;        ///< Π f_j
  std::vector<float> singularity;  ///< wrist · elbow · shoulder
  std::vector<float> clearance;    ///< Π f_C (1 where not evaluated because f was already 0)
  std::vector<std::uint8_t> limit;

  std::size_t index(std::size_t branch, std::size_t angle, std::size_t time) const {
    return (branch * angles.size() + angle) * times.size() + time;
  }
  std::size_t cellsPerBranch() const { return angles.size() * times.size(); }
};

/// The distance checks a map takes on at most (branches × angles × times × body pairs): about
/// hours of work on a workstation. buildConfigMaps refuses a larger map before it starts, as it
/// refuses one over memory_limit_bytes or over the memory this process can still allocate.
inline constexpr double kMaxMapPairChecks = 2e10;

/// Bytes a map of this size needs (all layers).
std::size_t mapBytes(std::size_t branches, std::size_t angles, std::size_t times);

/// The table angles of the grid: a full turn [0, 360°) in n = round(360° / step) equal steps
/// for a continuous table (so the grid closes on itself), [min, max] every `step` for a limited
/// one.
std::vector<double> mapAngles(const kinematics::RotaryTableModel& table, double step);

/// Called now and then from worker threads (serialise inside): cells done, cells in all.
using ProgressFn = std::function<void(std::size_t, std::size_t)>;

/// Builds the maps in parallel (TBB); the result does not depend on the thread count. Throws
/// InputError when the map would exceed the memory limit, before computing anything.
ConfigMap buildConfigMap(const collision::Scene& scene,
                         const ConstraintSettings& settings,
                         const kinematics::ScanPath& path,
                         const MapRequest& request,
                         const ProgressFn& progress = {});

/// Scores one cell the way the map does (exposed for tests and `check --time`).
struct CellScore {
  float f = 0.0f, joint = 0.0f, singularity = 0.0f, clearance = 1.0f;
  Limit limit = Limit::kUnreachable;
  kinematics::JointVector q = kinematics::JointVector::Zero();
};
/// `clearance` has begun the cell (MapClearance::beginCell); `branch_index` is the branch's
/// index in it.
CellScore scoreCell(const collision::Scene& scene,
                    const ConstraintSettings& settings,
                    collision::MapClearance& clearance,
                    std::size_t branch_index,
                    const std::vector<kinematics::IkSolution>& solutions,
                    const kinematics::IkBranch& branch);

namespace detail {
/// The map as scanplan first built it: FCL alone (no closed forms), every pair at
/// every branch-cell, the scanner placed by FK per branch, Eq. 7 with a pow per joint on every
/// solution. Kept for the benchmark's old-path comparison; values differ from buildConfigMap's
/// only by FCL's GJK tolerance (1e-6 m) against the closed forms.
ConfigMap buildConfigMapReference(const collision::Scene& scene,
                                  const ConstraintSettings& settings,
                                  const kinematics::ScanPath& path,
                                  const MapRequest& request);
}  // namespace detail

}  // namespace scanplan::planner
