#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include <scanplan/kinematics/cell.h>
#include <scanplan/kinematics/robot_model.h>
#include <scanplan/kinematics/scan_path.h>
#include <scanplan/planner/config_map.h>
#include <scanplan/planner/constraints.h>

namespace scanplan::planner {

/// Joint wrap on the configuration maps.
///
/// A map cell keeps, per branch, the whole-turn variant of the IK solution farthest from the
/// limits (Eq. 7). For a joint whose range exceeds 2π (ABB J4 ±200°, J6 ±400°, the Viper's J4
/// ±190° and J6 ±360°) that is a relaxation: the joint's value along a motion is continuous, so
/// which equivalent a cell really needs depends on where the path came from, and a path good on
/// the map may need the joint past its limit (buildTrajectory() finds that and names the joint).
/// The value cannot be lifted once for the whole map: with the table turning freely the joint
/// usually winds a whole turn per table turn (J4 ≈ table angle − path angle + c), so any lifting
/// over the cylinder meets itself a turn apart.
///
/// The sheets of a branch for one such joint j are maps on which j's value is taken in a window
/// [lo, lo + 360°): each cell uses the equivalent of its solution inside the window, Eq. 7 is
/// scored on it (0 outside the limits), and the cells whose value lies within kWrapMargin of
/// either window edge are closed, so that no path between open cells can pass the edge, where the
/// value would jump a whole turn. On a sheet the joint factor is therefore the one of the joint's
/// continuous value along any path whose steps move j by less than the margin, and such a path
/// keeps j within its limits. The windows start at min − margin and step by at most 90° until
/// one ends at max + margin, so a path whose j spans up to 360° − 2·margin − 90° (230°) always
/// fits one, a wider one (up to 360° − 2·margin, 320°) only where a window happens to hold it,
/// and a wider still none. The other
/// joints keep the map's choice; the planners run on a sheet unchanged (it is a one-branch
/// ConfigMap, f' = f · J'/J, J the map's joint factor, J' the sheet's: singularity and clearance
/// do not change with whole turns), and buildTrajectory() still checks the chosen path.
///
/// Sheets are computed on demand (one IK per open cell of the branch): the pipeline asks for them
/// only for a branch whose best path was rejected because joint j would pass its limit.
class WrapSheets {
 public:
  /// rad: the band closed inside each window edge.
  static constexpr double kWrapMargin = 0.3490658503988659;  // 20°

  /// The sheets of `map`'s branch `branch` for joint `joint` (0-based); `path` is the path the
  /// map was built on, `cell` its cell. None when the joint does not turn more than once or no
  /// sheet is open at every time.
  WrapSheets(const kinematics::CellModel& cell,
             const ConstraintSettings& settings,
             const kinematics::ScanPath& path,
             const ConfigMap& map,
             std::size_t branch,
             int joint);

  /// Sheets open at every time sample (some table angle with f' > 0), lowest window first.
  std::size_t size() const { return windows_.size(); }
  /// Sheet i's window start, rad (the window is [lo, lo + 2π)).
  double window(std::size_t i) const { return windows_[i]; }
  /// "joint 4 in [-130, 230) deg".
  std::string describe(std::size_t i) const;
  /// Sheet i as a one-branch map (branches = {the branch}), same angles and times.
  ConfigMap map(std::size_t i) const;

 private:
  double sheetJoint(std::size_t cell, double lo) const;

  const ConfigMap* map_;
  std::size_t branch_;
  const kinematics::RobotModel* robot_;
  ConstraintSettings settings_;
  int joint_;
  std::vector<double> value_;  ///< [cell] the joint's value in (−π, π], rad; NaN where closed
  std::vector<double> rest_;   ///< [cell] Eq. 7's product over the other joints (map's choice)
  std::vector<double> windows_;
};

}  // namespace scanplan::planner
