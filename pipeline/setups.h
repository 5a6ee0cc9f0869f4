#pragma once
// A second setup (docs/design.md §11, `plan --setups 2`): what faces the table in the first setup
// cannot be scanned there; turned onto another face it rests on stably, the part shows it. The
// turn is chosen for the area it brings out of the table's shadow; the second program is planned
// like the first (automatic scan only), and the coverage of both is combined on the same area
// samples.

#include <optional>
#include <string>

#include <Eigen/Geometry>

#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/pipeline/problem.h>

namespace scanplan::pipeline {

struct SecondSetup {
  Eigen::Isometry3d X_RP = Eigen::Isometry3d::Identity();  ///< the part on the table, m
  std::string turn;                                        ///< e.g. "turned over (180 deg about x)"
  double gain = 0.0;  ///< share of the area facing the table in the first setup but not here
};

/// Tries the part turned over and tipped onto each side (180° about x, ±90° about x and y, all
/// about the table-top frame, then placed on the table) and keeps the one that rests stably
/// (kinematics::restsStably) with the largest gain. nullopt when none rests stably or gains at
/// least 0.5 % of the area. Precondition: `first` was simulated with a certificate.
std::optional<SecondSetup> chooseSecondSetup(const ScanProblem& problem, const ScanPlan& first);

/// The second setup's problem: the part placed by `setup`, the automatic scan alone (the
/// hand-written paths belong to the first setup).
ScanProblem secondSetupProblem(const ScanProblem& problem, const SecondSetup& setup);

/// Both setups together on the area samples they share.
struct CombinedCoverage {
  double area_fraction = 0.0;       ///< covered by either setup
  double scannable_fraction = 0.0;  ///< scannable in either setup
  double covered_of_scannable = 0.0;
};

/// Precondition: both plans simulated with certificates on the same part, point spacing and
/// sample cap (so the area samples are the same); throws std::invalid_argument otherwise.
CombinedCoverage combineSetups(const ScanPlan& first, const ScanPlan& second);

/// A second setup, planned.
struct SecondSetupPlan {
  std::optional<SecondSetup> setup;  ///< none: no second setup, `why_not` says why
  std::string why_not;
  std::optional<ScanProblem> problem;        ///< the second setup's problem (with `setup`)
  ScanPlan plan;                             ///< its plan (with `setup`)
  std::optional<CombinedCoverage> combined;  ///< both setups together, when it is planned
};

/// The second setup as one call (`plan --setups 2`): chooseSecondSetup() after `first`, the plan
/// of `problem` (it needs the automatic scan and the simulation, for the certificate), then
/// planScan() of secondSetupProblem() with `options`, and combineSetups() when it is planned.
SecondSetupPlan planSecondSetup(const ScanProblem& problem,
                                const ScanPlan& first,
                                const PlanOptions& options = {},
                                const ProgressFn& progress = {});

}  // namespace scanplan::pipeline
