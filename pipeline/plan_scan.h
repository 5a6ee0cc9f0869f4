#pragma once
// planScan(): a whole scan plan from a ScanProblem — scan path, configuration maps, the
// table-angle path (every branch planned, the best executable one chosen), the 7-DOF
// trajectory, its validation and the scanner simulation. Every planning decision lives here;
// front ends only read problems and write what comes back.

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <scanplan/collision/scene.h>
#include <scanplan/kinematics/scan_path.h>
#include <scanplan/pipeline/auto_scan.h>
#include <scanplan/pipeline/cancel.h>
#include <scanplan/pipeline/certificate.h>
#include <scanplan/pipeline/problem.h>
#include <scanplan/pipeline/program_moves.h>
#include <scanplan/pipeline/simulation.h>
#include <scanplan/planner/config_map.h>
#include <scanplan/planner/plan_result.h>
#include <scanplan/planner/refine.h>
#include <scanplan/planner/trajectory_builder.h>
#include <scanplan/planner/validation.h>
#include <scanplan/planner/wrap_sheets.h>
#include <scanplan/scanner/laser_model.h>
#include <scanplan/scanner/path_generators.h>

namespace scanplan::pipeline {

/// Progress of a long stage: its name ("map"), work done and work in all. Called from worker
/// threads; the callee serialises.
using ProgressFn = std::function<void(std::string_view stage, std::size_t done, std::size_t total)>;

/// Per-call choices on top of the problem's settings.
struct PlanOptions {
  std::string method;    ///< empty: problem.planning.method
  bool compare = false;  ///< also run every other planner on the chosen branch
  bool refine = false;   ///< refine even when problem.planning.refine is off
};

/// One planner's run over the map's branches.
struct PlannerOutcome {
  std::string method;                         ///< ray | dp | ompl
  planner::PlanResult result;                 ///< the chosen branch's, or why none was chosen
  std::vector<planner::PlanResult> branches;  ///< per map branch
  double seconds = 0.0;                       ///< all branches
  /// No branch solved, and on some the search's budget ended it (an approximate path or a
  /// timeout of an iterative search): a larger budget may solve it.
  bool budget_ended = false;
};

/// The path search: the chosen planner on every branch, the branch choice, refinement, the DP
/// yardstick and the comparisons.
struct PathChoice {
  PlannerOutcome chosen;
  std::optional<planner::RefineResult> refine;  ///< of the chosen branch, when refinement ran
  std::vector<double> theta;                    ///< the final path (refined when that helped)
  /// rad, the even shift `theta` got after planning to start where the table stood after the
  /// segment before it in the program (0: none; see ProgramTimes::held).
  double table_shift = 0.0;
  planner::ObjectiveTerms terms;          ///< evaluate() of `theta`
  std::optional<planner::PlanResult> dp;  ///< DP on the chosen branch (the yardstick)
  int dp_subdivisions = 1;                ///< DP's angle grid: map step / this
  std::vector<PlannerOutcome> others;     ///< PlanOptions::compare: the other planners
  /// Branches whose path could not be executed, best J first, with the reason.
  std::vector<std::pair<std::size_t, std::string>> rejected;
  /// Why the chosen branch won (e.g. "lowest J of 6 solved branches").
  std::string why_chosen;
  /// The chosen path's joint-wrap sheet (planner::WrapSheets::describe()); empty when it was
  /// planned on the map itself.
  std::string wrap_sheet;
  /// That sheet as a one-branch map (the DP yardstick and the comparisons ran on it); null when
  /// the path was planned on the map itself.
  std::shared_ptr<const planner::ConfigMap> sheet_map;
  /// A path of several segments (kinematics::ScanPath::breaks): each segment's own choice, in
  /// order (empty for one segment). The fields above then join them: `theta` over every time
  /// sample, `terms` and the J of `chosen`, `dp` and `others` summed, `chosen.result.branch`
  /// the branch most samples use; `rejected` and `why_chosen` name the segment.
  std::vector<PathChoice> segments;
  bool solved() const { return chosen.result.solved(); }
  /// (J − J_dp) / J_dp of the final path, when DP solved; negative when the continuous path
  /// beats DP's grid.
  std::optional<double> dpGap() const;
};

/// The stages before planning, shared by every planner setting on the same cell and path (a
/// batch computes them once per map).
struct PreparedScan {
  scanner::LaserWindow window;
  scanner::GeneratedPath path;
  std::unique_ptr<collision::Scene> scene;
  planner::ConfigMap map;
  std::optional<AutoScanReport> auto_scan;  ///< when the problem asks for the automatic scan
  double path_seconds = 0.0;
  double map_seconds = 0.0;
};

/// Wall time of each stage, s. `plan` is the whole path search without the trajectory checks
/// (the chosen planner on every branch, refinement, the DP yardstick and any comparisons); `dp`
/// is the yardstick's share of it (0 when the chosen planner is DP itself or none ran).
struct StageTimes {
  double path = 0, map = 0, plan = 0, dp = 0, trajectory = 0, validation = 0, simulation = 0;
  double total = 0;  ///< planScan(): the whole call; a front end may put its own total here
};

/// How a plan ended.
enum class ScanStatus {
  kPlanned,            ///< a valid trajectory (validated when the problem asks)
  kNoPath,             ///< no planner path on any branch
  kNoExecutablePath,   ///< paths were found but the arm cannot follow any of them
  kInvalidTrajectory,  ///< the chosen trajectory failed validation
};
/// "planned", "no_path", "no_executable_path", "invalid_trajectory".
std::string_view scanStatusName(ScanStatus status);

/// Everything planScan() found. `trajectory` is set when a branch was accepted (also when the
/// validation then failed); `validation` and `simulation` when they ran.
struct ScanPlan {
  ScanStatus status = ScanStatus::kNoPath;
  std::string reason;  ///< not kPlanned: why
  std::shared_ptr<const PreparedScan> prepared;
  PathChoice choice;
  std::optional<planner::TrajectoryBuild> trajectory;
  std::optional<planner::ValidationReport> validation;
  std::optional<SimulationRun> simulation;
  /// With the automatic scan and the simulation: every area sample covered or why not.
  std::optional<Certificate> certificate;
  /// With the certificate: the share of the scannable area covered against program time.
  CoverageCurve coverage_curve;
  /// The program's time: scanning and moving (set with `trajectory`).
  ProgramTimes program;
  /// A path of segments: the order the program runs them in (segment index, run backwards,
  /// program time of its first sample). Empty for one segment.
  struct Run {
    std::size_t segment = 0;
    bool reversed = false;
    double start = 0.0;
  };
  std::vector<Run> order;
  /// Segments (passes) left out of the program, with the reason: no executable path on any
  /// branch, or no move reaches them. Their samples keep the previous segment's last table
  /// angle in `choice.theta` and are not in the trajectory.
  std::vector<std::pair<std::size_t, std::string>> dropped;
  StageTimes times;
  bool planned() const { return status == ScanStatus::kPlanned; }
};

/// The scan path of a problem: its hand-written elements, then (with auto_scan) the automatic
/// passes as one more element, and what the automatic planner did.
struct ScanPathResult {
  scanner::LaserWindow window;
  scanner::GeneratedPath path;
  std::optional<AutoScanReport> auto_scan;
};
/// The path stage alone (checkProblem first); `scene` is the problem's cell (the automatic scan
/// checks its passes for reach on it). Throws InputError for a path that cannot be built.
ScanPathResult scanPath(const ScanProblem& problem,
                        const collision::Scene& scene,
                        const ProgressFn& progress = {});

/// The scan path and the maps of `problem` (checked first with checkProblem()).
std::shared_ptr<const PreparedScan> prepareScan(const ScanProblem& problem,
                                                const ProgressFn& progress = {});

/// The stages after the maps, on `prepared` (made by prepareScan() from a problem with the same
/// cell, part, path, constraints and map settings; only the planning, validation and simulation
/// settings may differ).
ScanPlan planPrepared(const ScanProblem& problem,
                      std::shared_ptr<const PreparedScan> prepared,
                      const PlanOptions& options = {});

/// prepareScan() then planPrepared(): the whole pipeline. Throws InputError for a bad problem;
/// "no plan" is a status, not an exception.
ScanPlan planScan(const ScanProblem& problem,
                  const PlanOptions& options = {},
                  const ProgressFn& progress = {});

/// The path search alone, on a map (exposed for tests and tools): runs `method` on every branch,
/// takes the solved branches in order of J, refines each (when asked) and accepts the first whose
/// path `accept` passes (empty string = accepted, else the reason); then the DP yardstick and the
/// comparisons on the chosen branch.
///
/// Joint wrap: right after `accept` rejects a branch's path (on the map itself), `wrap_sheets`
/// is asked for that branch's joint-wrap sheets (planner::WrapSheets); null or empty: none. The
/// same planner then runs on each sheet and every solved sheet joins the candidates in order of J,
/// so a branch whose best path would take a joint past its limit is planned again with the joint
/// factor of the unwrapped joint values. planScan() asks only when the rejection was a joint that
/// would pass its limit (TrajectoryBuild::wrap_joint).
using PathCheck = std::function<std::string(std::size_t branch, const std::vector<double>& theta)>;
using WrapSheetsFn = std::function<std::shared_ptr<const planner::WrapSheets>(std::size_t branch)>;
PathChoice choosePath(const planner::ConfigMap& map,
                      const PlanSettings& settings,
                      const PlanOptions& options,
                      const PathCheck& accept = {},
                      const WrapSheetsFn& wrap_sheets = {});

/// One planner over the map's branches (or only `branch`), keeping the lowest J.
PlannerOutcome runPlanner(const std::string& method,
                          const planner::ConfigMap& map,
                          const PlanSettings& settings,
                          std::optional<std::size_t> branch = {});

}  // namespace scanplan::pipeline
