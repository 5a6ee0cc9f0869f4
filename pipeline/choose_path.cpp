#include "pipeline/plan_scan.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "kinematics/error.h"
#include "kinematics/units.h"
#include "pipeline/map_checks.h"
#include "planner/dp_planner.h"
#include "scanner/raycaster.h"

namespace scanplan::pipeline {

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

planner::PlanningProblem branchProblem(const planner::ConfigMap& map,
                                       std::size_t branch,
                                       const PlanSettings& settings) {
  planner::PlanningProblem p;
  p.map = &map;
  p.branch = branch;
  p.settings = settings.objective;
  p.continuous = settings.continuous;
  p.start_theta = settings.start_theta;
  return p;
}

// The solved branches, lowest J first (ties: branch order).
std::vector<std::size_t> solvedByCost(const PlannerOutcome& outcome) {
  std::vector<std::size_t> order;
  for (std::size_t b = 0; b < outcome.branches.size(); ++b) {
    if (outcome.branches[b].solved()) order.push_back(b);
  }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return outcome.branches[a].terms.total < outcome.branches[b].terms.total;
  });
  return order;
}

// Refines (when asked) and checks the solved branches in order of J; the first the check
// passes is chosen. False when none passes.
bool acceptBest(const planner::ConfigMap& map,
                const PlanSettings& settings,
                bool refine,
                const PathCheck& accept,
                PathChoice& out) {
  const std::vector<std::size_t> order = solvedByCost(out.chosen);
  for (const std::size_t b : order) {
    const planner::PlanResult& r = out.chosen.branches[b];
    out.theta = r.theta;
    out.terms = r.terms;
    out.refine.reset();
    if (refine) {
      planner::RefineSettings rs = settings.refine_settings;
      rs.keep_start = settings.start_theta.has_value();
      out.refine = planner::refinePath(map, b, out.theta, settings.objective, settings.continuous,
                                       rs);
      out.theta = out.refine->theta;
      out.terms = out.refine->after;
    }
    const std::string why = accept ? accept(b, out.theta) : std::string();
    if (why.empty()) {
      out.chosen.result = r;
      out.why_chosen =
          out.rejected.empty()
              ? fmt::format("lowest J of {} solved branch(es), and the arm can follow it",
                            order.size())
              : fmt::format("lowest J the arm can follow: {} of {} solved branch(es) had a lower "
                            "J but cannot be executed (see rejected)",
                            out.rejected.size(), order.size());
      return true;
    }
    out.rejected.emplace_back(b, why);
  }
  std::string reasons;
  for (const auto& [b, why] : out.rejected) {
    reasons += fmt::format("\n  {}: {}", map.branches[b].words(), why);
  }
  out.chosen.result = planner::PlanResult{};
  out.chosen.result.reason =
      fmt::format("{} found a path on {} branch(es) but none can be executed:{}",
                  out.chosen.method, order.size(), reasons);
  out.theta.clear();
  out.refine.reset();
  return false;
}

// The DP yardstick and, with `compare`, the other planners on the chosen branch.
void yardsticks(const planner::ConfigMap& map,
                const PlanSettings& settings,
                const PlanOptions& options,
                PathChoice& out) {
  const std::size_t branch = out.chosen.result.branch;
  out.dp_subdivisions =
      planner::dpSubdivisions(branchProblem(map, branch, settings), settings.planners);
  const std::string& method = out.chosen.method;
  if (method == "dp") {
    out.dp = out.chosen.result;
  } else if (settings.dp_gap || options.compare) {
    out.dp = runPlanner("dp", map, settings, branch).branches[branch];
  }
  if (!options.compare) return;
  for (const std::string& m : planner::plannerNames()) {
    if (m == method) continue;
    if (m == "dp" && out.dp) {
      PlannerOutcome dp;
      dp.method = "dp";
      dp.result = *out.dp;
      dp.seconds = out.dp->seconds;
      out.others.push_back(dp);
      continue;
    }
    out.others.push_back(runPlanner(m, map, settings, branch));
  }
}

}  // namespace

std::optional<double> PathChoice::dpGap() const {
  if (!solved() || !dp || !dp->solved() || !(dp->terms.total > 0.0)) return std::nullopt;
  return (terms.total - dp->terms.total) / dp->terms.total;
}

std::string_view scanStatusName(ScanStatus status) {
  switch (status) {
    case ScanStatus::kPlanned: return "planned";
    case ScanStatus::kNoPath: return "no_path";
    case ScanStatus::kNoExecutablePath: return "no_executable_path";
    case ScanStatus::kInvalidTrajectory: return "invalid_trajectory";
  }
  return "unknown";
}

PlannerOutcome runPlanner(const std::string& method,
                          const planner::ConfigMap& map,
                          const PlanSettings& settings,
                          std::optional<std::size_t> branch) {
  const auto start = Clock::now();
  const std::unique_ptr<planner::Planner> planner =
      planner::makePlanner(method, settings.planners);
  if (!planner) throw InputError("planner.method: " + method + ": expected ray, dp or ompl");
  PlannerOutcome out;
  out.method = method;
  out.branches.resize(map.branches.size());
  bool any = false;
  std::string reasons;
  for (std::size_t b = 0; b < map.branches.size(); ++b) {
    if (branch && b != *branch) continue;
    planner::PlanResult& r = out.branches[b];
    r.branch = b;
    if (const auto k = blockedColumn(map, b)) {
      r.reason = fmt::format("f = 0 at every table angle at time sample {} (t = {:.2f} s): {}", *k,
                             map.times[*k], columnLimits(map, b, *k));
    } else {
      r = planner->solve(branchProblem(map, b, settings), settings.termination);
    }
    if (r.solved() && (!any || r.terms.total < out.result.terms.total)) {
      out.result = r;
      any = true;
    }
    reasons += fmt::format("\n  {}: {}", map.branches[b].words(),
                           r.solved() ? fmt::format("J = {:.4f} s", r.terms.total) : r.reason);
  }
  if (!any) {
    out.result = planner::PlanResult{};
    out.result.reason = fmt::format("{} found no path on any branch:{}", method, reasons);
  }
  out.seconds = since(start);
  return out;
}

PathChoice choosePath(const planner::ConfigMap& map,
                      const PlanSettings& settings,
                      const PlanOptions& options,
                      const PathCheck& accept) {
  PathChoice out;
  out.chosen = runPlanner(options.method.empty() ? settings.method : options.method, map,
                          settings);
  if (!out.solved()) return out;
  if (!acceptBest(map, settings, options.refine || settings.refine, accept, out)) return out;
  yardsticks(map, settings, options, out);
  return out;
}

}  // namespace scanplan::pipeline
