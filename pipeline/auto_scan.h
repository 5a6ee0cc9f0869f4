#pragma once
// The automatic scan (job keys scan.auto, docs/design.md §11): candidate passes over the part
// placed on the table, each evaluated on area samples with the scanner model, a greedy set cover of
// the scannable area by new area per second, every chosen pass checked for reach on the cell (some
// table angle where the arm follows it on one IK branch), the passes ordered to keep the
// connecting moves short. Each pass becomes a segment of the scan path: the planners plan the
// table per pass, and the program joins the passes with point-to-point moves (plan_scan.h).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <scanplan/collision/scene.h>
#include <scanplan/pipeline/problem.h>
#include <scanplan/scanner/area_coverage.h>
#include <scanplan/scanner/path_generators.h>
#include <scanplan/scanner/scannability.h>

namespace scanplan::pipeline {

/// One chosen pass as it runs in the program.
struct AutoPass {
  std::string kind;         ///< spin | strip
  std::string label;        ///< what it is ("spin elevation 25 deg, line at 40 mm")
  double start_time = 0.0;  ///< s of scanning before it (its place on the map's time axis)
  double duration = 0.0;    ///< s of scanning
  double gain = 0.0;        ///< share of the counted area it newly covers, as measured
};

/// What the automatic planner did.
struct AutoScanReport {
  std::size_t candidates = 0;   ///< passes generated and evaluated
  std::size_t samples = 0;      ///< evaluation area samples
  double sample_spacing = 0.0;  ///< m between evaluation samples
  std::size_t counted = 0;      ///< samples that count toward the target (scannable)
  std::vector<AutoPass> passes;
  std::vector<std::string> unreachable;  ///< candidates the reach check refused
  double planned_fraction = 0.0;  ///< counted samples the chosen passes cover (the prediction)
  double given_fraction = 0.0;    ///< of them, covered by the hand-written paths already
  std::string stop;               ///< why the selection stopped
  double scan_time = 0.0;         ///< s of scanning in the automatic passes
  /// s of moves between passes as the tour estimated them (the program's own moves are
  /// point-to-point moves timed by the pipeline: ScanPlan::program).
  double transfer_time = 0.0;
  double seconds = 0.0;  ///< planning time
  /// The set cover's estimated program time (scanning + a move per pass), s: the greedy cover's,
  /// the integer programme's (scanner::solveCover, the passes used) and its proven lower bound
  /// (0: none proven); its status. All 0 / empty when the programme did not run (a time limit,
  /// or the greedy cover missed the target).
  double greedy_cost = 0.0;
  double cover_cost = 0.0;
  double cover_bound = 0.0;
  std::string cover_status;
  double cover_seconds = 0.0;
  /// The chosen passes, as the scanner will measure them (scanner::measurePass), cut to what the
  /// others do not cover (scanner::cutToCover): the scanning time left out, s; the passes left
  /// out whole; the extra pieces of passes split in two.
  double cut_time = 0.0;
  std::size_t cut_dropped = 0;
  std::size_t cut_split = 0;
  /// Covers chosen again with a larger margin because the passes measured less than the target
  /// (0: the first cover measured it), and whether the last of them, measuring the target,
  /// replaced the first (else the first stands).
  std::size_t rechosen = 0;
  bool rechosen_kept = false;
  /// Then pieces left out while the measured coverage stays at the target (scanner::pruneToGoal):
  /// how many, and their scanning time, s.
  std::size_t pruned = 0;
  double pruned_time = 0.0;
  /// Of the counting area (the simulation's area samples), the share the passes kept measure:
  /// the coverage the simulated cloud is expected to have.
  double measured_fraction = 0.0;
  std::size_t aimed = 0;  ///< of the candidates, aimed at surfaces the others miss
  /// The certificate before simulation: the evaluation samples (part frame P) and why each can
  /// or cannot be scanned (kOutOfReach: every pass that sees it was refused by the reach check).
  scanner::AreaSampling sampling;
  std::vector<scanner::SampleClass> classes;
};

/// The automatic passes and their report.
struct AutoScanPlan {
  /// The passes in tour order, each as timed keys of the scanner in the part frame (times from
  /// 0, all scanning). They are not joined: the pipeline plans each as a path segment and joins
  /// them with point-to-point moves.
  std::vector<scanner::FileSpec> passes;
  AutoScanReport report;
};

/// The point spacing the automatic scan works to: settings.point_spacing, or the line's point
/// pitch at the middle of the depth window for `rays_per_profile` rays.
double autoPointSpacing(const AutoScanSettings& settings,
                        const scanner::LaserOptics& optics,
                        int rays_per_profile);

/// Plans the automatic passes of `problem` (problem.auto_scan must be set). `given` is the
/// hand-written part of the path (may be empty): its coverage counts first and the passes start
/// where it ends. Throws InputError when no candidate pass sees the part.
AutoScanPlan planAutoScan(const ScanProblem& problem,
                          const collision::Scene& scene,
                          const kinematics::ScanPath& given,
                          const std::function<void(std::size_t, std::size_t)>& progress = {});

}  // namespace scanplan::pipeline
