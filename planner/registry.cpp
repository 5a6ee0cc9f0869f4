#include <scanplan/planner/registry.h>

#include <scanplan/planner/dp_planner.h>

namespace scanplan::planner {

namespace {

class RayShootingPlanner final : public Planner {
 public:
  explicit RayShootingPlanner(const RayShootingSettings& settings) : settings_(settings) {}
  std::string name() const override { return "ray"; }

 private:
  PlanResult solveChecked(const PlanningProblem& p, const Termination&) const override {
    return planRayShooting(*p.map, p.branch, p.settings, p.continuous, settings_, p.start_theta);
  }
  RayShootingSettings settings_;
};

class DpPlanner final : public Planner {
 public:
  explicit DpPlanner(const PlannerConfig& config) : config_(config) {}
  std::string name() const override { return "dp"; }

 private:
  PlanResult solveChecked(const PlanningProblem& p, const Termination&) const override {
    return planDpRefined(*p.map, p.branch, p.settings, p.continuous, dpSubdivisions(p, config_),
                         p.start_theta);
  }
  PlannerConfig config_;
};

class OmplSearch final : public Planner {
 public:
  explicit OmplSearch(const OmplSettings& settings) : settings_(settings) {}
  std::string name() const override { return "ompl"; }

 private:
  PlanResult solveChecked(const PlanningProblem& p, const Termination& t) const override {
    OmplSettings os = settings_;
    os.time_limit_s = t.time_limit_s > 0.0 ? t.time_limit_s : 1e9;
    os.max_iterations = t.max_iterations;
    os.cancel = t.cancel;
    return planOmpl(*p.map, p.branch, p.settings, p.continuous, os, p.start_theta);
  }
  OmplSettings settings_;
};

}  // namespace

const std::vector<std::string>& plannerNames() {
  static const std::vector<std::string> names{"ray", "dp", "ompl"};
  return names;
}

std::unique_ptr<Planner> makePlanner(std::string_view name, const PlannerConfig& config) {
  if (name == "ray") return std::make_unique<RayShootingPlanner>(config.ray);
  if (name == "dp") return std::make_unique<DpPlanner>(config);
  if (name == "ompl") return std::make_unique<OmplSearch>(config.ompl);
  return nullptr;
}

int dpSubdivisions(const PlanningProblem& problem, const PlannerConfig& config) {
  if (config.dp_subdivisions > 0) return config.dp_subdivisions;
  return autoAngleSubdivisions(*problem.map, problem.branch, problem.settings, problem.continuous);
}

}  // namespace scanplan::planner
