#include <scanplan/pipeline/plan_scan.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <tuple>

#include <fmt/format.h>

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/pipeline/map_checks.h>
#include <scanplan/planner/dp_planner.h>
#include <scanplan/scanner/raycaster.h>

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

// A path to check: a branch's on the map, or on one of the branch's joint-wrap sheets.
struct Candidate {
  double cost = 0.0;  // J
  std::size_t branch = 0;
  std::shared_ptr<const planner::WrapSheets> sheets;  // null: the map itself
  std::size_t sheet = 0;
  planner::PlanResult result;
};

// The candidates of `branch`'s sheets the planner solves, its result's branch the map's.
void planSheets(std::shared_ptr<const planner::WrapSheets> sheets,
                std::size_t branch,
                const std::string& method,
                const PlanSettings& settings,
                std::vector<Candidate>& out) {
  for (std::size_t i = 0; i < sheets->size(); ++i) {
    const planner::ConfigMap sheet = sheets->map(i);
    planner::PlanResult r = runPlanner(method, sheet, settings).branches[0];
    if (!r.solved()) continue;
    r.branch = branch;
    out.push_back({r.terms.total, branch, sheets, i, std::move(r)});
  }
}

// Why the accepted path was chosen: `rejected` paths of lower J came first, out of `solved`
// branches, or of `tried` paths once joint-wrap sheets were planned too.
std::string whyChosen(std::size_t rejected,
                      std::size_t solved,
                      bool sheets_planned,
                      std::size_t tried) {
  if (rejected == 0)
    return fmt::format("lowest J of {} solved branch(es), and the arm can follow it", solved);
  if (!sheets_planned)
    return fmt::format(
        "lowest J the arm can follow: {} of {} solved branch(es) had a lower J but cannot be "
        "executed (see rejected)",
        rejected, solved);
  return fmt::format(
      "lowest J the arm can follow: {} of {} solved path(s) (branches and joint-wrap sheets) had "
      "a lower J but cannot be executed (see rejected)",
      rejected, tried);
}

// Refines (when asked) and checks the solved branches in order of J; the first the check
// passes is chosen. A branch rejected because a joint would pass its limit (joint wrap) gets its
// sheets planned as further candidates, in the same order of J. False when none passes.
bool acceptBest(const planner::ConfigMap& map,
                const PlanSettings& settings,
                bool refine,
                const PathCheck& accept,
                const WrapSheetsFn& wrap_sheets,
                PathChoice& out) {
  const std::vector<std::size_t> order = solvedByCost(out.chosen);
  std::vector<Candidate> pending;
  for (const std::size_t b : order)
    pending.push_back({out.chosen.branches[b].terms.total, b, nullptr, 0, out.chosen.branches[b]});
  const auto later = [](const Candidate& x, const Candidate& y) {
    // Ties: branch order, the map before its sheets, sheets in order (never pointer values).
    return std::make_tuple(x.cost, x.branch, x.sheets != nullptr, x.sheet) >
           std::make_tuple(y.cost, y.branch, y.sheets != nullptr, y.sheet);
  };
  std::size_t tried = 0;
  bool sheets_planned = false;
  while (!pending.empty()) {
    std::stable_sort(pending.begin(), pending.end(), later);
    const Candidate c = std::move(pending.back());
    pending.pop_back();
    ++tried;
    const planner::ConfigMap sheet_map = c.sheets ? c.sheets->map(c.sheet) : planner::ConfigMap{};
    const planner::ConfigMap& m = c.sheets ? sheet_map : map;
    const std::size_t mb = c.sheets ? 0 : c.branch;
    out.theta = c.result.theta;
    out.terms = c.result.terms;
    out.refine.reset();
    if (refine) {
      planner::RefineSettings rs = settings.refine_settings;
      rs.keep_start = settings.start_theta.has_value();
      out.refine =
          planner::refinePath(m, mb, out.theta, settings.objective, settings.continuous, rs);
      out.theta = out.refine->theta;
      out.terms = out.refine->after;
    }
    const std::string why = accept ? accept(c.branch, out.theta) : std::string();
    const std::string on_sheet =
        c.sheets ? fmt::format("on its joint-wrap sheet ({})", c.sheets->describe(c.sheet))
                 : std::string();
    if (why.empty()) {
      out.chosen.result = c.result;
      out.wrap_sheet = c.sheets ? c.sheets->describe(c.sheet) : std::string();
      if (c.sheets) out.sheet_map = std::make_shared<const planner::ConfigMap>(sheet_map);
      out.why_chosen = whyChosen(out.rejected.size(), order.size(), sheets_planned, tried);
      if (c.sheets) out.why_chosen += "; " + on_sheet;
      return true;
    }
    out.rejected.emplace_back(c.branch, c.sheets ? on_sheet + ": " + why : why);
    if (!c.sheets && wrap_sheets) {
      if (auto sheets = wrap_sheets(c.branch)) {
        planSheets(std::move(sheets), c.branch, out.chosen.method, settings, pending);
        sheets_planned = true;
      }
    }
  }
  std::string reasons;
  for (const auto& [b, why] : out.rejected) {
    reasons += fmt::format("\n  {}: {}", map.branches[b].words(), why);
  }
  out.chosen.result = planner::PlanResult{};
  out.chosen.result.reason =
      fmt::format("{} found a path on {} branch(es) but none can be executed:{}", out.chosen.method,
                  order.size(), reasons);
  out.theta.clear();
  out.refine.reset();
  return false;
}

// The DP yardstick and, with `compare`, the other planners on the chosen branch.
void yardsticks(const planner::ConfigMap& map,
                const PlanSettings& settings,
                const PlanOptions& options,
                PathChoice& out) {
  // A path chosen on a joint-wrap sheet is measured on that sheet (its only branch).
  const planner::ConfigMap& on = out.sheet_map ? *out.sheet_map : map;
  const std::size_t chosen = out.chosen.result.branch;
  const std::size_t branch = out.sheet_map ? 0 : chosen;
  const auto run = [&](const std::string& method) {
    PlannerOutcome o = runPlanner(method, on, settings, branch);
    o.result.branch = chosen;
    return o;
  };
  out.dp_subdivisions =
      planner::dpSubdivisions(branchProblem(on, branch, settings), settings.planners);
  const std::string& method = out.chosen.method;
  if (method == "dp") {
    out.dp = out.chosen.result;
  } else if (settings.dp_gap || options.compare) {
    const PlannerOutcome dp = run("dp");
    out.dp = dp.branches[branch];
    out.dp->branch = chosen;
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
    out.others.push_back(run(m));
  }
}

}  // namespace

std::optional<double> PathChoice::dpGap() const {
  if (!solved() || !dp || !dp->solved() || !(dp->terms.total > 0.0)) return std::nullopt;
  return (terms.total - dp->terms.total) / dp->terms.total;
}

std::string_view scanStatusName(ScanStatus status) {
  switch (status) {
    case ScanStatus::kPlanned:
      return "planned";
    case ScanStatus::kNoPath:
      return "no_path";
    case ScanStatus::kNoExecutablePath:
      return "no_executable_path";
    case ScanStatus::kInvalidTrajectory:
      return "invalid_trajectory";
  }
  return "unknown";
}

PlannerOutcome runPlanner(const std::string& method,
                          const planner::ConfigMap& map,
                          const PlanSettings& settings,
                          std::optional<std::size_t> branch) {
  const auto start = Clock::now();
  const std::unique_ptr<planner::Planner> planner = planner::makePlanner(method, settings.planners);
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
    out.budget_ended = std::any_of(out.branches.begin(), out.branches.end(), [](const auto& r) {
      return r.status == planner::PlannerStatus::kApproximate ||
             r.status == planner::PlannerStatus::kTimeout;
    });
    out.result.reason =
        out.budget_ended ? fmt::format(
                               "{} reached the end on no branch within its budget (a larger budget "
                               "may; see each branch):{}",
                               method, reasons)
                         : fmt::format("{} found no path on any branch:{}", method, reasons);
  }
  out.seconds = since(start);
  return out;
}

PathChoice choosePath(const planner::ConfigMap& map,
                      const PlanSettings& settings,
                      const PlanOptions& options,
                      const PathCheck& accept,
                      const WrapSheetsFn& wrap_sheets) {
  PathChoice out;
  out.chosen = runPlanner(options.method.empty() ? settings.method : options.method, map, settings);
  if (!out.solved()) return out;
  if (!acceptBest(map, settings, options.refine || settings.refine, accept, wrap_sheets, out))
    return out;
  yardsticks(map, settings, options, out);
  return out;
}

}  // namespace scanplan::pipeline
