// The map and planner sections of a job file: their YAML keys (describe) and the planner's
// settings in SI (plannerSettings, startAngle, parseBranch).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <regex>
#include <set>
#include <sstream>
#include <type_traits>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <scanplan/config/detail/job_sections.h>
#include <scanplan/config/robot_urdf.h>
#include <scanplan/config/text.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/placement.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/planner/registry.h>
#include <scanplan/programs/programs.h>

namespace scanplan::config {
namespace {

template <class A>
void describeMap(A& a, MapSpec& s) {
  a.field("angle_step_deg", s.angle_step_deg, Expect{0.01, 90.0, false, false, {}});
  a.field("branch", s.branch);
  a.field("memory_limit_mb", s.memory_limit_mb, Expect::positive());
  if constexpr (A::kReading) {
    if (s.branch != "auto" && !parseBranch(s.branch)) {
      a.fail("branch", "'" + s.branch + "'",
             "auto or three V+ words, e.g. 'RIGHTY ABOVE NOFLIP' (LEFTY/RIGHTY, ABOVE/BELOW, "
             "FLIP/NOFLIP)");
    }
  }
}

const std::vector<std::string>& kPlannerMethods = planner::plannerNames();

template <class A>
void describeRay(A& a, RaySpec& s) {
  a.field("rays", s.rays, Expect::range(1, 401));
  a.field("horizon", s.horizon, Expect::range(1, 1000));
  a.field("starts", s.starts, Expect::range(1, 100000));
  a.field("blocked_penalty_s", s.blocked_penalty_s, Expect::nonNegative());
  a.field("cost_to_go", s.cost_to_go);
  a.field("dp_fallback", s.dp_fallback);
}

template <class A>
void describeDp(A& a, DpSpec& s) {
  a.field("angle_subdivisions", s.angle_subdivisions, Expect::range(0, 64));
}

template <class A>
void describeOmpl(A& a, OmplSpec& s) {
  a.field("max_iterations", s.max_iterations, Expect::range(1, 100000000));
  a.field("time_limit_s", s.time_limit_s, Expect{0.01, 3600.0, false, false, {}});
  a.field("seed", s.seed, Expect::range(0, 2147483647));
}

template <class A>
void describeRefine(A& a, RefineSpec& s) {
  a.field("enabled", s.enabled);
  a.field("time_limit_s", s.time_limit_s, Expect{0.01, 3600.0, false, false, {}});
}

template <class A>
void describePlanner(A& a, PlannerSpec& s) {
  a.field("method", s.method, Expect::oneOf(kPlannerMethods));
  a.field("k_omega", s.k_omega, Expect::nonNegative());
  a.field("k_alpha", s.k_alpha, Expect::nonNegative());
  a.field("start_deg", s.start_deg);
  a.field("dp_gap", s.dp_gap);
  a.section("ray", s.ray);
  a.section("dp", s.dp);
  a.section("ompl", s.ompl);
  a.section("refine", s.refine);
  if constexpr (A::kReading) {
    if (s.start_deg != "auto" && !parseFiniteNumber(s.start_deg)) {
      a.fail("start_deg", "'" + s.start_deg + "'", "auto or a table angle in degrees");
    }
  }
}

}  // namespace

void describe(YamlIn& a, MapSpec& s) { describeMap(a, s); }
void describe(YamlOut& a, MapSpec& s) { describeMap(a, s); }
void describe(SchemaOut& a, MapSpec& s) { describeMap(a, s); }
void describe(YamlIn& a, RaySpec& s) { describeRay(a, s); }
void describe(YamlOut& a, RaySpec& s) { describeRay(a, s); }
void describe(SchemaOut& a, RaySpec& s) { describeRay(a, s); }
void describe(YamlIn& a, DpSpec& s) { describeDp(a, s); }
void describe(YamlOut& a, DpSpec& s) { describeDp(a, s); }
void describe(SchemaOut& a, DpSpec& s) { describeDp(a, s); }
void describe(YamlIn& a, OmplSpec& s) { describeOmpl(a, s); }
void describe(YamlOut& a, OmplSpec& s) { describeOmpl(a, s); }
void describe(SchemaOut& a, OmplSpec& s) { describeOmpl(a, s); }
void describe(YamlIn& a, RefineSpec& s) { describeRefine(a, s); }
void describe(YamlOut& a, RefineSpec& s) { describeRefine(a, s); }
void describe(SchemaOut& a, RefineSpec& s) { describeRefine(a, s); }
void describe(YamlIn& a, PlannerSpec& s) { describePlanner(a, s); }
void describe(YamlOut& a, PlannerSpec& s) { describePlanner(a, s); }
void describe(SchemaOut& a, PlannerSpec& s) { describePlanner(a, s); }

std::optional<kinematics::IkBranch> parseBranch(const std::string& words) {
  std::istringstream in(words);
  std::string w;
  kinematics::IkBranch b;
  int seen = 0;
  while (in >> w) {
    int bit = 0;
    if (w == "LEFTY" || w == "RIGHTY") {
      b.lefty = w == "LEFTY";
      bit = 1;
    } else if (w == "ABOVE" || w == "BELOW") {
      b.below = w == "BELOW";
      bit = 2;
    } else if (w == "FLIP" || w == "NOFLIP") {
      b.flip = w == "FLIP";
      bit = 4;
    } else {
      return std::nullopt;
    }
    if (seen & bit) return std::nullopt;  // two words of one pair
    seen |= bit;
  }
  if (seen != 7) return std::nullopt;
  return b;
}

planner::PlannerSettings plannerSettings(const JobSpec& job) {
  planner::PlannerSettings p;
  p.k_omega = job.planner.k_omega;
  p.k_alpha = job.planner.k_alpha;
  p.omega_max = deg(job.table.max_speed_deg_s);
  p.alpha_max = deg(job.table.max_accel_deg_s2);
  return p;
}

std::optional<double> startAngle(const JobSpec& job) {
  if (job.planner.start_deg == "auto") return std::nullopt;
  return deg(*parseFiniteNumber(job.planner.start_deg));
}

pipeline::MapSettings mapSettings(const JobSpec& job) {
  pipeline::MapSettings s;
  s.angle_step = deg(job.map.angle_step_deg);
  if (job.map.branch != "auto") s.branches = {*parseBranch(job.map.branch)};
  s.memory_limit_bytes = static_cast<std::size_t>(job.map.memory_limit_mb * 1024.0 * 1024.0);
  return s;
}

pipeline::PlanSettings planSettings(const JobSpec& job) {
  pipeline::PlanSettings s;
  s.method = job.planner.method;
  s.objective = plannerSettings(job);
  s.continuous = job.table.continuous;
  s.start_theta = startAngle(job);
  s.planners.ray.rays = job.planner.ray.rays;
  s.planners.ray.horizon = job.planner.ray.horizon;
  s.planners.ray.starts = job.planner.ray.starts;
  s.planners.ray.blocked_penalty = job.planner.ray.blocked_penalty_s;
  s.planners.ray.cost_to_go = job.planner.ray.cost_to_go;
  s.planners.ray.dp_fallback = job.planner.ray.dp_fallback;
  s.planners.dp_subdivisions = job.planner.dp.angle_subdivisions;
  s.planners.ompl.seed = static_cast<std::uint32_t>(job.planner.ompl.seed);
  s.termination.time_limit_s = job.planner.ompl.time_limit_s;
  s.termination.max_iterations = static_cast<std::size_t>(job.planner.ompl.max_iterations);
  s.refine = job.planner.refine.enabled;
  s.refine_settings.time_limit_s = job.planner.refine.time_limit_s;
  s.dp_gap = job.planner.dp_gap;
  return s;
}

}  // namespace scanplan::config
