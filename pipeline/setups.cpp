#include <scanplan/pipeline/setups.h>

#include <stdexcept>
#include <utility>
#include <vector>

#include <scanplan/kinematics/placement.h>
#include <scanplan/scanner/area_coverage.h>
#include <scanplan/scanner/laser_model.h>

namespace scanplan::pipeline {

namespace {

struct Turn {
  const char* name;
  Eigen::Matrix3d R;
};

std::vector<Turn> turns() {
  const auto about = [](double angle, const Eigen::Vector3d& axis) {
    return Eigen::AngleAxisd(angle, axis).toRotationMatrix();
  };
  const double half = 3.141592653589793, quarter = 0.5 * half;
  return {{"turned over (180 deg about x)", about(half, Eigen::Vector3d::UnitX())},
          {"tipped onto a side (+90 deg about x)", about(quarter, Eigen::Vector3d::UnitX())},
          {"tipped onto a side (-90 deg about x)", about(-quarter, Eigen::Vector3d::UnitX())},
          {"tipped onto a side (+90 deg about y)", about(quarter, Eigen::Vector3d::UnitY())},
          {"tipped onto a side (-90 deg about y)", about(-quarter, Eigen::Vector3d::UnitY())}};
}

}  // namespace

std::optional<SecondSetup> chooseSecondSetup(const ScanProblem& problem, const ScanPlan& first) {
  if (!first.simulation || !first.certificate) {
    throw std::invalid_argument("chooseSecondSetup: the first plan has no certificate");
  }
  const scanner::AreaSampling& sampling = first.simulation->sampling;
  const auto& classes = first.certificate->classes;
  const double z_max = scanner::laserWindow(problem.optics).z_max;
  const double limit = problem.simulation ? problem.simulation->max_incidence : 1.0471975511965976;
  std::optional<SecondSetup> best;
  for (const Turn& t : turns()) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = t.R * problem.cell.part.X_RP.linear();
    const Eigen::Isometry3d X_RP = kinematics::placedOnTable(problem.part, pose);
    if (!kinematics::restsStably(problem.part, X_RP)) continue;
    const std::vector<std::uint8_t> faces = scanner::facesTable(sampling, X_RP, limit, z_max);
    std::size_t gained = 0;
    for (std::size_t i = 0; i < classes.size(); ++i)
      gained += (classes[i] == CoverageClass::kFacesTable && !faces[i]) ? 1u : 0u;
    const double gain = static_cast<double>(gained) / std::max<double>(1.0, double(classes.size()));
    if (gain >= 0.005 && (!best || gain > best->gain + 1e-12))
      best = SecondSetup{X_RP, t.name, gain};
  }
  return best;
}

ScanProblem secondSetupProblem(const ScanProblem& problem, const SecondSetup& setup) {
  ScanProblem second = problem;
  second.cell.part.X_RP = setup.X_RP;
  second.path.elements.clear();
  if (!second.auto_scan) second.auto_scan = AutoScanSettings{};
  return second;
}

CombinedCoverage combineSetups(const ScanPlan& first, const ScanPlan& second) {
  if (!first.certificate || !second.certificate ||
      first.certificate->classes.size() != second.certificate->classes.size()) {
    throw std::invalid_argument("combineSetups: both plans need certificates on the same samples");
  }
  const auto& a = first.certificate->classes;
  const auto& b = second.certificate->classes;
  const auto scannable = [](CoverageClass c) {
    return c == CoverageClass::kCovered || c == CoverageClass::kMissed;
  };
  std::size_t covered = 0, can = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    covered += (a[i] == CoverageClass::kCovered || b[i] == CoverageClass::kCovered) ? 1u : 0u;
    can += (scannable(a[i]) || scannable(b[i])) ? 1u : 0u;
  }
  CombinedCoverage c;
  const double n = std::max<double>(1.0, static_cast<double>(a.size()));
  c.area_fraction = static_cast<double>(covered) / n;
  c.scannable_fraction = static_cast<double>(can) / n;
  c.covered_of_scannable = can ? static_cast<double>(covered) / static_cast<double>(can) : 0.0;
  return c;
}

SecondSetupPlan planSecondSetup(const ScanProblem& problem,
                                const ScanPlan& first,
                                const PlanOptions& options,
                                const ProgressFn& progress) {
  SecondSetupPlan out;
  if (!first.certificate) {
    out.why_not = "it needs scan.auto and the simulation";
    return out;
  }
  out.setup = chooseSecondSetup(problem, first);
  if (!out.setup) {
    out.why_not = "no other face the part rests on shows more of it";
    return out;
  }
  out.problem = secondSetupProblem(problem, *out.setup);
  out.plan = planScan(*out.problem, options, progress);
  if (out.plan.planned()) out.combined = combineSetups(first, out.plan);
  return out;
}

}  // namespace scanplan::pipeline
