#include <scanplan/planner/planner.h>

#include <chrono>
#include <cmath>

#include <fmt/format.h>

namespace scanplan::planner {

namespace {

PlanResult refused(const PlanningProblem& p, PlannerStatus status, std::string reason) {
  PlanResult r;
  r.status = status;
  r.branch = p.branch;
  r.reason = std::move(reason);
  return r;
}

}  // namespace

std::string_view statusName(PlannerStatus status) {
  switch (status) {
    case PlannerStatus::kExact:
      return "exact";
    case PlannerStatus::kApproximate:
      return "approximate";
    case PlannerStatus::kNoPath:
      return "no_path";
    case PlannerStatus::kTimeout:
      return "timeout";
    case PlannerStatus::kInvalidInput:
      return "invalid_input";
  }
  return "unknown";
}

std::string problemError(const PlanningProblem& p) {
  if (p.map == nullptr) return "no configuration map";
  const ConfigMap& map = *p.map;
  if (p.branch >= map.branches.size()) {
    return fmt::format("branch {} of a map with {} branch(es)", p.branch, map.branches.size());
  }
  if (map.times.size() < 2 || map.angles.size() < 2) {
    return fmt::format("a map of {} angle(s) x {} time sample(s): need at least 2 x 2",
                       map.angles.size(), map.times.size());
  }
  if (map.f.size() != map.branches.size() * map.cellsPerBranch()) return "map layer size";
  const PlannerSettings& s = p.settings;
  if (!(s.omega_max > 0.0) || !(s.alpha_max > 0.0) || !std::isfinite(s.omega_max) ||
      !std::isfinite(s.alpha_max)) {
    return fmt::format(
        "speed and acceleration bounds must be positive and finite (omega_max {}, "
        "alpha_max {})",
        s.omega_max, s.alpha_max);
  }
  if (!(s.k_omega >= 0.0) || !(s.k_alpha >= 0.0) || !std::isfinite(s.k_omega) ||
      !std::isfinite(s.k_alpha)) {
    return fmt::format("weights must be finite and >= 0 (k_omega {}, k_alpha {})", s.k_omega,
                       s.k_alpha);
  }
  if (p.start_theta && !std::isfinite(*p.start_theta)) return "start angle not finite";
  return {};
}

PlanResult Planner::solve(const PlanningProblem& problem, const Termination& termination) const {
  if (std::string why = problemError(problem); !why.empty()) {
    return refused(problem, PlannerStatus::kInvalidInput, name() + ": " + why);
  }
  if (termination.cancelled()) {
    return refused(problem, PlannerStatus::kTimeout, name() + ": cancelled");
  }
  if (termination.time_limit_s < 0.0 || !std::isfinite(termination.time_limit_s)) {
    return refused(problem, PlannerStatus::kTimeout,
                   fmt::format("{}: no time left ({} s)", name(), termination.time_limit_s));
  }
  const auto start = std::chrono::steady_clock::now();
  PlanResult result = solveChecked(problem, termination);
  result.branch = problem.branch;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace scanplan::planner
