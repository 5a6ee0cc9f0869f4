#include <scanplan/planner/ompl_planner.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <ompl/base/Goal.h>
#include <ompl/base/OptimizationObjective.h>
#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/goals/GoalSampleableRegion.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/base/spaces/SO2StateSpace.h>
#include <ompl/control/ControlSampler.h>
#include <ompl/control/PathControl.h>
#include <ompl/control/SpaceInformation.h>
#include <ompl/control/planners/rrt/RRT.h>
#include <ompl/control/planners/sst/SST.h>
#include <ompl/control/spaces/RealVectorControlSpace.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

namespace scanplan::planner {

namespace {

namespace ob = ompl::base;
namespace oc = ompl::control;

// The components of the compound state, in this order.
constexpr unsigned kTheta = 0, kOmega = 1, kTime = 2, kCost = 3;

// Everything a step, a validity check and the goal need; outlives the OMPL objects using it.
struct Problem {
  const ConfigMap* map = nullptr;
  detail::Grid grid;
  std::size_t branch = 0;
  PlannerSettings settings;
  bool continuous = true;

  double f(double theta, std::size_t k) const noexcept {
    return detail::mapValue(*map, grid, branch, theta, k, continuous);
  }
  // One sample of the dynamics (header): the speed after a step with control u (target speed
  // u·ω_max) from speed `omega` at sample k. The first step reaches the target: evaluate() bounds
  // no acceleration into sample 1.
  double nextOmega(double omega, std::size_t k, double u) const noexcept {
    const double w_max = settings.omega_max, target = u * w_max;
    if (k == 0) return target;
    const double dw = settings.alpha_max * grid.dt;
    return std::clamp(omega + std::clamp(target - omega, -dw, dw), -w_max, w_max);
  }
  // The J terms a step adds (evaluate()'s, Eq. in objective.h), the start sample's own −ln f
  // included on the first step. Infinite when f = 0 at the new sample.
  double stepCost(
      double theta0, double omega0, std::size_t k, double theta1, double omega1) const noexcept {
    const double dt = grid.dt;
    const double f1 = f(theta1, k + 1);
    if (!(f1 > 0.0)) return std::numeric_limits<double>::infinity();
    double c = (-std::log(f1) + settings.k_omega * omega1 * omega1) * dt;
    if (k + 1 >= 2) {
      const double alpha = (omega1 - omega0) / dt;
      c += settings.k_alpha * alpha * alpha * dt;
    }
    if (k == 0) {
      const double f0 = f(theta0, 0);
      c += f0 > 0.0 ? -std::log(f0) * dt : std::numeric_limits<double>::infinity();
    }
    return c;
  }
};

// Typed access to the compound state.
struct StateView {
  bool so2 = true;

  double& theta(ob::State* s) const {
    auto* c = s->as<ob::CompoundState>();
    return so2 ? c->as<ob::SO2StateSpace::StateType>(kTheta)->value
               : c->as<ob::RealVectorStateSpace::StateType>(kTheta)->values[0];
  }
  double theta(const ob::State* s) const {
    const auto* c = s->as<ob::CompoundState>();
    return so2 ? c->as<ob::SO2StateSpace::StateType>(kTheta)->value
               : c->as<ob::RealVectorStateSpace::StateType>(kTheta)->values[0];
  }
  static double& real(ob::State* s, unsigned i) {
    return s->as<ob::CompoundState>()->as<ob::RealVectorStateSpace::StateType>(i)->values[0];
  }
  static double real(const ob::State* s, unsigned i) {
    return s->as<ob::CompoundState>()->as<ob::RealVectorStateSpace::StateType>(i)->values[0];
  }
  static std::size_t sample(const ob::State* s) {
    return static_cast<std::size_t>(std::llround(real(s, kTime)));
  }
};

// SO(2)'s wrap into [−π, π) (as ompl::base::SO2StateSpace::enforceBounds).
double wrapPi(double v) {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  v = std::fmod(v, kTwoPi);
  if (v < -kTwoPi / 2.0) {
    v += kTwoPi;
  } else if (v >= kTwoPi / 2.0) {
    v -= kTwoPi;
  }
  return v;
}

// J as the difference of the accumulated-cost component: exact for a control held any number of
// samples, which a cost from the two end states alone could not be.
class AccumulatedCost : public ob::OptimizationObjective {
 public:
  explicit AccumulatedCost(const ob::SpaceInformationPtr& si) : ob::OptimizationObjective(si) {}
  ob::Cost stateCost(const ob::State*) const override { return identityCost(); }
  ob::Cost motionCost(const ob::State* s1, const ob::State* s2) const override {
    return ob::Cost(StateView::real(s2, kCost) - StateView::real(s1, kCost));
  }
};

// Reached the last time sample. Goal samples (for goal bias) are uniform states moved there.
class LastSample : public ob::GoalSampleableRegion {
 public:
  LastSample(const ob::SpaceInformationPtr& si, double last)
      : ob::GoalSampleableRegion(si), last_(last), sampler_(si->allocStateSampler()) {
    setThreshold(0.5);  // k is a whole number: "less than" half a sample means k = last
  }
  double distanceGoal(const ob::State* s) const override {
    return std::max(0.0, last_ - StateView::real(s, kTime));
  }
  void sampleGoal(ob::State* s) const override {
    sampler_->sampleUniform(s);
    StateView::real(s, kTime) = last_;
    StateView::real(s, kCost) = 0.0;
  }
  unsigned int maxSampleCount() const override { return std::numeric_limits<unsigned>::max(); }

 private:
  double last_;
  ob::StateSamplerPtr sampler_;
};

// OMPL seeds every RNG from one process-wide generator and logs through one global handler.
std::mutex& omplMutex() {
  static std::mutex m;
  return m;
}

class LogLevelGuard {
 public:
  LogLevelGuard() : previous_(ompl::msg::getLogLevel()) {
    ompl::msg::setLogLevel(ompl::msg::LOG_NONE);
  }
  ~LogLevelGuard() { ompl::msg::setLogLevel(previous_); }
  LogLevelGuard(const LogLevelGuard&) = delete;
  LogLevelGuard& operator=(const LogLevelGuard&) = delete;

 private:
  ompl::msg::LogLevel previous_;
};

// Uniform target speeds, and with probability `p_stop` exactly 0: standing still is often the
// cheapest motion and the only one that fits a corridor one grid step wide, and a uniform sample
// never hits it.
class StopBiasedSampler : public oc::ControlSampler {
 public:
  StopBiasedSampler(const oc::ControlSpace* space, double p_stop)
      : oc::ControlSampler(space), p_stop_(p_stop) {}
  void sample(oc::Control* control) override {
    double& u = control->as<oc::RealVectorControlSpace::ControlType>()->values[0];
    u = rng_.uniform01() < p_stop_ ? 0.0 : rng_.uniformReal(-1.0, 1.0);
  }

 private:
  double p_stop_;
};

const char* plannerName(OmplPlanner p) { return p == OmplPlanner::kSst ? "SST" : "RRT"; }

void checkSettings(const PlannerSettings& settings, const OmplSettings& os) {
  if (!(settings.omega_max >= 0.0) || !(settings.alpha_max >= 0.0) || !(os.time_limit_s > 0.0) ||
      os.max_steps < 1 || !(os.goal_bias >= 0.0) || !(os.goal_bias <= 1.0) ||
      !(os.stop_probability >= 0.0) || !(os.stop_probability <= 1.0) ||
      !(os.selection_radius > 0.0) || !(os.pruning_radius > 0.0)) {
    throw std::logic_error(
        "planOmpl: bounds >= 0; time limit, radii > 0; max_steps >= 1; goal_bias, stop_probability "
        "in [0, 1]");
  }
}

// A cheap certain answer: the first time sample with f = 0 at every angle, explained; empty when
// every column has an open cell.
std::string closedColumn(const ConfigMap& map, std::size_t branch) {
  const std::size_t na = map.angles.size(), nt = map.times.size();
  for (std::size_t k = 0; k < nt; ++k) {
    bool open = false;
    for (std::size_t a = 0; a < na && !open; ++a) open = map.f[map.index(branch, a, k)] > 0.0f;
    if (!open) {
      return fmt::format("time sample {} (t = {} s): f = 0 at every table angle", k, map.times[k]);
    }
  }
  return {};
}

// Start angles (rad) spread evenly over the first column's open cells: `count` of them, 0 = all.
std::vector<double> spreadStarts(const ConfigMap& map, std::size_t branch, std::size_t count) {
  std::vector<std::size_t> open;
  for (std::size_t a = 0; a < map.angles.size(); ++a) {
    if (map.f[map.index(branch, a, 0)] > 0.0f) open.push_back(a);
  }
  std::vector<double> starts;
  const std::size_t n = count == 0 ? open.size() : std::min(open.size(), count);
  for (std::size_t i = 0; i < n; ++i) starts.push_back(map.angles[open[i * open.size() / n]]);
  return starts;
}

// θ, ω, k and the accumulated J, in that order (kTheta …).
ob::StateSpacePtr makeStateSpace(const Problem& problem) {
  const ConfigMap& map = *problem.map;
  const double dt = problem.grid.dt;
  // Metric in "steps" (header): weights turn rad, rad/s and samples into comparable units.
  const double w_max = problem.settings.omega_max, a_max = problem.settings.alpha_max;
  const double theta_unit = w_max * dt > 0.0 ? w_max * dt : problem.grid.angle_step;
  const double omega_unit = a_max * dt > 0.0 ? a_max * dt : std::max(2.0 * w_max, 1.0);

  auto space = std::make_shared<ob::CompoundStateSpace>();
  if (problem.continuous) {
    space->addSubspace(std::make_shared<ob::SO2StateSpace>(), 1.0 / theta_unit);
  } else {
    auto theta_space = std::make_shared<ob::RealVectorStateSpace>(1);
    theta_space->setBounds(map.angles.front(), map.angles.back());
    space->addSubspace(theta_space, 1.0 / theta_unit);
  }
  const auto realSpace = [](double lo, double hi) {
    auto s = std::make_shared<ob::RealVectorStateSpace>(1);
    s->setBounds(lo, hi);
    return s;
  };
  // Bounds only shape sampling (validity enforces |ω| ≤ ω_max); they must be non-empty.
  const double w_bound = std::max(w_max, 1e-9);
  space->addSubspace(realSpace(-w_bound, w_bound), 1.0 / omega_unit);
  space->addSubspace(realSpace(0.0, static_cast<double>(map.times.size() - 1)), 1.0);
  // The accumulated J rides along outside the metric (weight 0); finite bounds keep sampled
  // values finite so 0·distance stays 0.
  space->addSubspace(realSpace(0.0, 1e100), 0.0);
  space->lock();
  return space;
}

oc::ControlSpacePtr makeControlSpace(const ob::StateSpacePtr& space, double stop_probability) {
  auto controls = std::make_shared<oc::RealVectorControlSpace>(space, 1);
  ob::RealVectorBounds u_bounds(1);
  u_bounds.setLow(-1.0);
  u_bounds.setHigh(1.0);
  controls->setBounds(u_bounds);
  controls->setControlSamplerAllocator([p = stop_probability](const oc::ControlSpace* cs) {
    return std::make_shared<StopBiasedSampler>(cs, p);
  });
  return controls;
}

// The dynamics (Problem::nextOmega) and validity; `problem` must outlive the result.
oc::SpaceInformationPtr makeSpaceInformation(const Problem& problem,
                                             const ob::StateSpacePtr& space,
                                             const oc::ControlSpacePtr& controls,
                                             int max_steps) {
  const StateView view{problem.continuous};
  auto si = std::make_shared<oc::SpaceInformation>(space, controls);
  si->setPropagationStepSize(problem.grid.dt);
  si->setMinMaxControlDuration(1, static_cast<unsigned>(max_steps));
  const double last = static_cast<double>(problem.map->times.size() - 1);
  si->setStatePropagator([&problem, view, last](const ob::State* from, const oc::Control* control,
                                                double, ob::State* to) {
    const double u = control->as<oc::RealVectorControlSpace::ControlType>()->values[0];
    const double k_real = StateView::real(from, kTime);
    const double theta0 = view.theta(from), omega0 = StateView::real(from, kOmega);
    const double cost0 = StateView::real(from, kCost);
    if (!(k_real < last)) {  // past the end: an invalid state stops the propagation
      view.theta(to) = theta0;
      StateView::real(to, kOmega) = omega0;
      StateView::real(to, kTime) = last + 1.0;
      StateView::real(to, kCost) = cost0;
      return;
    }
    const auto k = StateView::sample(from);
    const double omega1 = problem.nextOmega(omega0, k, u);
    const double theta1 = theta0 + omega1 * problem.grid.dt;
    const double c = problem.stepCost(theta0, omega0, k, theta1, omega1);
    view.theta(to) = view.so2 ? wrapPi(theta1) : theta1;
    StateView::real(to, kOmega) = omega1;
    StateView::real(to, kTime) = static_cast<double>(k + 1);
    StateView::real(to, kCost) = std::isfinite(c) ? cost0 + c : cost0;  // f = 0: invalid
  });
  si->setStateValidityChecker([&problem, view, last](const ob::State* s) {
    const double k_real = StateView::real(s, kTime);
    if (!(k_real >= 0.0 && k_real <= last)) return false;
    if (std::abs(StateView::real(s, kOmega)) >
        problem.settings.omega_max * (1.0 + kBoundTolerance)) {
      return false;
    }
    return problem.f(view.theta(s), StateView::sample(s)) > 0.0;
  });
  si->setup();
  return si;
}

// Start states at rest on sample 0, the last sample as the goal, J as the objective.
ob::ProblemDefinitionPtr makeProblemDefinition(const oc::SpaceInformationPtr& si,
                                               const std::vector<double>& starts,
                                               bool continuous,
                                               double last,
                                               bool stop_at_first_solution) {
  const StateView view{continuous};
  auto pdef = std::make_shared<ob::ProblemDefinition>(si);
  for (const double theta0 : starts) {
    ob::State* s = si->allocState();
    view.theta(s) = continuous ? wrapPi(theta0) : theta0;
    StateView::real(s, kOmega) = 0.0;
    StateView::real(s, kTime) = 0.0;
    StateView::real(s, kCost) = 0.0;
    pdef->addStartState(s);
    si->freeState(s);
  }
  pdef->setGoal(std::make_shared<LastSample>(si, last));
  auto objective = std::make_shared<AccumulatedCost>(si);
  // Satisfied by any solution (stop at the first) or by none (improve until stopped).
  objective->setCostThreshold(
      ob::Cost((stop_at_first_solution ? 1.0 : -1.0) * std::numeric_limits<double>::infinity()));
  pdef->setOptimizationObjective(objective);
  return pdef;
}

ob::PlannerPtr makePlanner(const oc::SpaceInformationPtr& si,
                           const ob::ProblemDefinitionPtr& pdef,
                           const OmplSettings& os) {
  ob::PlannerPtr planner;
  if (os.planner == OmplPlanner::kSst) {
    auto sst = std::make_shared<oc::SST>(si);
    sst->setGoalBias(os.goal_bias);
    sst->setSelectionRadius(os.selection_radius);
    sst->setPruningRadius(os.pruning_radius);
    planner = sst;
  } else {
    auto rrt = std::make_shared<oc::RRT>(si);
    rrt->setGoalBias(os.goal_bias);
    planner = rrt;
  }
  planner->setProblemDefinition(pdef);
  planner->setup();
  return planner;
}

struct SolveOutcome {
  ob::PlannerStatus status;
  std::size_t iterations = 0;  // calls of the termination condition
  double seconds = 0.0;        // s, of solve()
};

// solve() until the time limit or the iteration cap, whichever comes first.
SolveOutcome solveWithin(ob::Planner& planner, const OmplSettings& os) {
  SolveOutcome out;
  // The planners test the condition once per iteration: counting its calls caps iterations.
  std::size_t& iterations = out.iterations;
  const std::size_t cap = os.max_iterations;
  const std::atomic<bool>* cancel = os.cancel;
  const ob::PlannerTerminationCondition ptc = ob::plannerOrTerminationCondition(
      ob::timedPlannerTerminationCondition(os.time_limit_s),
      ob::PlannerTerminationCondition([&iterations, cap, cancel] {
        return (++iterations > cap && cap != 0) ||
               (cancel != nullptr && cancel->load(std::memory_order_relaxed));
      }));
  const auto solve_start = std::chrono::steady_clock::now();
  out.status = planner.solve(ptc);
  out.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - solve_start).count();
  return out;
}

std::string solveDetail(const OmplSettings& os, const SolveOutcome& o, std::size_t starts) {
  const bool exact = o.status == ob::PlannerStatus::EXACT_SOLUTION;
  const bool approximate = o.status == ob::PlannerStatus::APPROXIMATE_SOLUTION;
  const std::size_t cap = os.max_iterations;
  return fmt::format(
      "OMPL {}: {} after {:.3f} s{}, {} start state{}", plannerName(os.planner),
      exact         ? "exact solution"
      : approximate ? "approximate solution"
                    : o.status.asString(),
      o.seconds,
      fmt::format(" ({} iterations)", cap != 0 ? std::min(o.iterations, cap) : o.iterations),
      starts, starts == 1 ? "" : "s");
}

// `x` rounded up to two significant figures (a budget to suggest).
std::size_t roundedUp(double x) {
  const double unit = std::pow(10.0, std::max(0.0, std::floor(std::log10(std::max(x, 1.0))) - 1.0));
  return static_cast<std::size_t>(std::ceil(x / unit) * unit);
}

// Why no exact solution: none at all, or an approximate one ending before the last sample.
std::string unsolvedReason(const ConfigMap& map,
                           const OmplSettings& os,
                           const SolveOutcome& o,
                           const ob::ProblemDefinition& pdef) {
  if (o.status != ob::PlannerStatus::APPROXIMATE_SOLUTION) {
    return fmt::format("time sample 1 (t = {} s): OMPL {} found no motion from any start ({})",
                       map.times[1], plannerName(os.planner), o.status.asString());
  }
  const std::size_t nt = map.times.size(), cap = os.max_iterations;
  auto* path = pdef.getSolutionPath()->as<oc::PathControl>();
  const std::size_t reached = StateView::sample(path->getStates().back());
  const std::size_t first_missed = std::min(reached + 1, nt - 1);
  // The budget ended the search, not a missing path: say how much more it would need, in
  // proportion to the samples it has yet to reach.
  const bool by_cap = cap != 0 && o.iterations >= cap;
  const double need =
      static_cast<double>(nt - 1) / static_cast<double>(std::max<std::size_t>(reached, 1));
  const std::string raise =
      by_cap ? fmt::format("raise planner.ompl.max_iterations to about {} (now {})",
                           roundedUp(static_cast<double>(cap) * need), cap)
             : fmt::format("raise planner.ompl.time_limit_s to about {:.3g} s (now {:.3g} s)",
                           os.time_limit_s * need, os.time_limit_s);
  return fmt::format(
      "time sample {} (t = {} s): not reached in the budget: OMPL {} reached time sample {} of "
      "{} (an approximate solution) when its {} ended it; a larger budget may reach the end: {}; "
      "or use dp, which finds a path on the map's grid whenever there is one, or ray",
      first_missed, map.times[first_missed], plannerName(os.planner), reached, nt - 1,
      by_cap ? "iteration cap" : "time limit", raise);
}

// One angle per sample: replay each control for its duration from the root, unwrapped (ω does
// not depend on θ, so these are the speeds OMPL propagated). The root is the start state nearest
// the path's first state unless the start is fixed.
std::vector<double> replayPath(const Problem& problem,
                               oc::PathControl& path,  // getControlDurations() is not const
                               const std::vector<double>& starts,
                               bool fixed_start) {
  const StateView view{problem.continuous};
  const double dt = problem.grid.dt;
  const ob::State* root = path.getState(0);
  double theta = starts.front();
  if (!fixed_start) {
    double best = std::numeric_limits<double>::infinity();
    for (const double s : starts) {
      const double d =
          std::abs(problem.continuous ? wrapPi(s - view.theta(root)) : s - view.theta(root));
      if (d < best) {
        best = d;
        theta = s;
      }
    }
  }
  std::vector<double> out;
  out.reserve(problem.map->times.size());
  out.push_back(theta);
  double omega = StateView::real(root, kOmega);
  for (std::size_t i = 0; i < path.getControlCount(); ++i) {
    const double u = path.getControl(static_cast<unsigned>(i))
                         ->as<oc::RealVectorControlSpace::ControlType>()
                         ->values[0];
    const auto steps = static_cast<std::size_t>(std::llround(path.getControlDurations()[i] / dt));
    for (std::size_t j = 0; j < steps; ++j) {
      omega = problem.nextOmega(omega, out.size() - 1, u);
      theta += omega * dt;
      out.push_back(theta);
    }
  }
  return out;
}

// Our status for an OMPL result that is not (yet) an exact, checked path.
PlanResult::Status unsolvedStatus(const ob::PlannerStatus& status) {
  if (status == ob::PlannerStatus::APPROXIMATE_SOLUTION) return PlanResult::Status::kApproximate;
  if (status == ob::PlannerStatus::TIMEOUT) return PlanResult::Status::kTimeout;
  return PlanResult::Status::kNoPath;
}

}  // namespace

PlanResult planOmpl(const ConfigMap& map,
                    std::size_t branch,
                    const PlannerSettings& settings,
                    bool continuous,
                    const OmplSettings& os,
                    std::optional<double> start_theta) {
  const auto clock_start = std::chrono::steady_clock::now();
  const detail::Grid g = detail::gridOf(map, branch, continuous);
  checkSettings(settings, os);
  const std::size_t nt = map.times.size();

  const Problem problem{&map, g, branch, settings, continuous};
  PlanResult result;
  result.branch = branch;
  const auto finish = [&]() {
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
    return result;
  };

  // Cheap certain answers first: a column with f = 0 everywhere, or a blocked start.
  result.reason = closedColumn(map, branch);
  if (!result.reason.empty()) return finish();
  std::vector<double> starts;  // rad, unwrapped: the path's first sample
  if (start_theta) {
    if (!(problem.f(*start_theta, 0) > 0.0)) {
      result.reason = fmt::format("time sample 0 (t = {} s): f = 0 at the start angle {} rad",
                                  map.times[0], *start_theta);
      return finish();
    }
    starts.push_back(*start_theta);
  } else {
    starts = spreadStarts(map, branch, os.starts);
  }

  const std::lock_guard<std::mutex> lock(omplMutex());
  const LogLevelGuard quiet;
  // Reseeding after seeds were drawn makes OMPL log an error (silenced) but it does reseed: every
  // RNG built below gets the same seed sequence on every call.
  ompl::RNG::setSeed(os.seed == 0 ? 1u : os.seed);

  const ob::StateSpacePtr space = makeStateSpace(problem);
  const oc::SpaceInformationPtr si = makeSpaceInformation(
      problem, space, makeControlSpace(space, os.stop_probability), os.max_steps);
  const ob::ProblemDefinitionPtr pdef = makeProblemDefinition(
      si, starts, continuous, static_cast<double>(nt - 1), os.stop_at_first_solution);
  const ob::PlannerPtr planner = makePlanner(si, pdef, os);

  const SolveOutcome solved = solveWithin(*planner, os);
  result.status = unsolvedStatus(solved.status);  // kExact once the path is checked below
  result.detail = solveDetail(os, solved, starts.size());
  if (solved.status != ob::PlannerStatus::EXACT_SOLUTION) {
    result.reason = unsolvedReason(map, os, solved, *pdef);
    return finish();
  }

  std::vector<double> out = replayPath(problem, *pdef->getSolutionPath()->as<oc::PathControl>(),
                                       starts, start_theta.has_value());
  if (out.size() != nt) {
    result.reason = fmt::format(
        "time sample {} (t = {} s): the OMPL path replays to {} samples of {}",
        std::min(out.size(), nt - 1), map.times[std::min(out.size(), nt - 1)], out.size(), nt);
    return finish();
  }
  const ObjectiveTerms terms = evaluate(map, branch, out, settings, continuous);
  if (!terms.feasible) {
    result.reason = fmt::format(
        "time sample {} (t = {} s): the OMPL path breaks a bound: min f {}, max |omega| {} "
        "rad/s, max |alpha| {} rad/s^2",
        terms.min_f_sample, map.times[terms.min_f_sample], terms.min_f, terms.max_abs_omega,
        terms.max_abs_alpha);
    return finish();
  }
  result.status = PlanResult::Status::kExact;
  result.theta = std::move(out);
  result.terms = terms;
  return finish();
}

}  // namespace scanplan::planner
