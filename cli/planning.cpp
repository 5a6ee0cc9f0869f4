#include "cli/planning.h"

#include <algorithm>
#include <array>
#include <chrono>

#include <fmt/format.h>

#include "planner/ompl_planner.h"
#include "planner/ray_shooting.h"

namespace scanplan::cli {

namespace {

using Status = planner::PlanResult::Status;

const std::vector<std::string> kMethods = {"ray", "dp", "ompl"};

int dpSubdivisions(const planner::ConfigMap& map,
                   std::size_t branch,
                   const JobSpec& job,
                   const planner::PlannerSettings& settings) {
  if (job.planner.dp.angle_subdivisions > 0) return job.planner.dp.angle_subdivisions;
  return planner::autoAngleSubdivisions(map, branch, settings, continuousTable(job));
}

planner::PlanResult planOne(const std::string& method,
                            const planner::ConfigMap& map,
                            std::size_t branch,
                            const JobSpec& job) {
  const planner::PlannerSettings settings = plannerSettings(job);
  const bool continuous = continuousTable(job);
  const std::optional<double> start = startAngle(job);
  if (method == "ray") {
    planner::RayShootingSettings rs;
    rs.rays = job.planner.ray.rays;
    rs.horizon = job.planner.ray.horizon;
    rs.starts = job.planner.ray.starts;
    rs.blocked_penalty = job.planner.ray.blocked_penalty_s;
    return planner::planRayShooting(map, branch, settings, continuous, rs, start);
  }
  if (method == "dp") {
    return planner::planDpRefined(map, branch, settings, continuous,
                                  dpSubdivisions(map, branch, job, settings), start);
  }
  if (method == "ompl") {
    planner::OmplSettings os;
    os.time_limit_s = job.planner.ompl.time_limit_s;
    os.max_iterations = static_cast<std::size_t>(job.planner.ompl.max_iterations);
    os.seed = static_cast<std::uint32_t>(job.planner.ompl.seed);
    return planner::planOmpl(map, branch, settings, continuous, os, start);
  }
  throw std::logic_error("planOne: unknown planner " + method);
}

// A time column with f = 0 everywhere on a branch: no planner can cross it.
std::optional<std::size_t> blockedColumn(const planner::ConfigMap& map, std::size_t branch) {
  for (std::size_t k = 0; k < map.times.size(); ++k) {
    bool open = false;
    for (std::size_t a = 0; a < map.angles.size() && !open; ++a) {
      open = map.f[map.index(branch, a, k)] > 0.0f;
    }
    if (!open) return k;
  }
  return std::nullopt;
}

// What limits a time column, e.g. "clearance at 60% of the angles, unreachable at 40%".
std::string columnLimits(const planner::ConfigMap& map, std::size_t branch, std::size_t k) {
  std::array<std::size_t, planner::kLimitCount> count{};
  for (std::size_t a = 0; a < map.angles.size(); ++a) ++count[map.limit[map.index(branch, a, k)]];
  std::vector<int> order(planner::kLimitCount);
  for (int i = 0; i < planner::kLimitCount; ++i) order[static_cast<std::size_t>(i)] = i;
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) {
    return count[static_cast<std::size_t>(x)] > count[static_cast<std::size_t>(y)];
  });
  std::string text;
  for (const int i : order) {
    const std::size_t n = count[static_cast<std::size_t>(i)];
    if (n == 0) continue;
    text += fmt::format("{}{} at {:.0f}% of the angles", text.empty() ? "" : ", ",
                        planner::limitName(static_cast<planner::Limit>(i)),
                        100.0 * static_cast<double>(n) / static_cast<double>(map.angles.size()));
  }
  return text;
}

}  // namespace

bool continuousTable(const JobSpec& job) { return job.table.continuous; }

std::optional<double> PlanningOutcome::dpGap() const {
  if (!solved() || !dp || dp->status != Status::kExact || !(dp->terms.total > 0.0)) {
    return std::nullopt;
  }
  return (terms.total - dp->terms.total) / dp->terms.total;
}

PlannerOutcome runPlanner(const std::string& method,
                          const planner::ConfigMap& map,
                          const JobSpec& job,
                          std::optional<std::size_t> branch) {
  const auto start = std::chrono::steady_clock::now();
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
      r = planOne(method, map, b, job);
    }
    if (r.status == Status::kExact && (!any || r.terms.total < out.result.terms.total)) {
      out.result = r;
      any = true;
    }
    reasons += fmt::format(
        "\n  {}: {}", map.branches[b].words(),
        r.status == Status::kExact ? fmt::format("J = {:.4f} s", r.terms.total) : r.reason);
  }
  if (!any) {
    out.result = planner::PlanResult{};
    out.result.reason = fmt::format("{} found no path on any branch:{}", method, reasons);
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

PlanningOutcome planJob(const planner::ConfigMap& map,
                        const JobSpec& job,
                        std::string method,
                        bool compare,
                        bool refine,
                        const PathCheck& check) {
  if (method.empty()) method = job.planner.method;
  PlanningOutcome out;
  out.chosen = runPlanner(method, map, job);
  if (!out.solved()) return out;
  const planner::PlannerSettings settings = plannerSettings(job);
  const bool continuous = continuousTable(job);

  std::vector<std::size_t> order;
  for (std::size_t b = 0; b < out.chosen.branches.size(); ++b) {
    if (out.chosen.branches[b].status == Status::kExact) order.push_back(b);
  }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return out.chosen.branches[a].terms.total < out.chosen.branches[b].terms.total;
  });
  bool accepted = false;
  for (const std::size_t b : order) {
    const planner::PlanResult& r = out.chosen.branches[b];
    out.theta = r.theta;
    out.terms = r.terms;
    out.refine.reset();
    if (refine || job.planner.refine.enabled) {
      planner::RefineSettings rs;
      rs.time_limit_s = job.planner.refine.time_limit_s;
      rs.keep_start = startAngle(job).has_value();
      out.refine = planner::refinePath(map, b, out.theta, settings, continuous, rs);
      out.theta = out.refine->theta;
      out.terms = out.refine->after;
    }
    const std::string why = check ? check(b, out.theta) : std::string();
    if (why.empty()) {
      out.chosen.result = r;
      accepted = true;
      break;
    }
    out.rejected.emplace_back(b, why);
  }
  if (!accepted) {
    std::string reasons;
    for (const auto& [b, why] : out.rejected) {
      reasons += fmt::format("\n  {}: {}", map.branches[b].words(), why);
    }
    out.chosen.result = planner::PlanResult{};
    out.chosen.result.reason =
        fmt::format("{} found a path on {} branch(es) but none can be executed:{}", method,
                    order.size(), reasons);
    out.theta.clear();
    out.refine.reset();
    return out;
  }
  const std::size_t branch = out.chosen.result.branch;
  out.dp_subdivisions = dpSubdivisions(map, branch, job, settings);
  if (method == "dp") {
    out.dp = out.chosen.result;
  } else if (job.planner.dp_gap || compare) {
    out.dp = runPlanner("dp", map, job, branch).branches[branch];
  }
  if (compare) {
    for (const std::string& m : kMethods) {
      if (m == method) continue;
      if (m == "dp" && out.dp) {
        PlannerOutcome dp;
        dp.method = "dp";
        dp.result = *out.dp;
        dp.seconds = out.dp->seconds;
        out.others.push_back(dp);
        continue;
      }
      out.others.push_back(runPlanner(m, map, job, branch));
    }
  }
  return out;
}

}  // namespace scanplan::cli
