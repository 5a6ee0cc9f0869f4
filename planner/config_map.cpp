#include <scanplan/planner/config_map.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>
#include <string>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/ramp.h>
#include <scanplan/kinematics/resources.h>
#include <scanplan/kinematics/units.h>

namespace scanplan::planner {

const char* limitName(Limit limit) {
  switch (limit) {
    case Limit::kNone:
      return "none";
    case Limit::kUnreachable:
      return "unreachable";
    case Limit::kJointLimit:
      return "joint limit";
    case Limit::kSingularity:
      return "singularity";
    case Limit::kClearance:
      return "clearance";
  }
  return "?";
}

std::size_t mapBytes(std::size_t branches, std::size_t angles, std::size_t times) {
  return branches * angles * times * (4 * sizeof(float) + sizeof(std::uint8_t));
}

std::vector<double> mapAngles(const kinematics::RotaryTableModel& table, double step) {
  std::vector<double> angles;
  if (table.continuous) {
    const auto n = static_cast<std::size_t>(std::llround(2.0 * std::numbers::pi / step));
    for (std::size_t i = 0; i < n; ++i)
      angles.push_back(static_cast<double>(i) * 2.0 * std::numbers::pi / static_cast<double>(n));
  } else {
    const auto n = static_cast<std::size_t>(std::floor((table.max - table.min) / step + 1e-9)) + 1;
    for (std::size_t i = 0; i < n; ++i) angles.push_back(table.min + static_cast<double>(i) * step);
  }
  return angles;
}

namespace {

// Eq. 7's joint-limit factor of q.
double jointFactor(const kinematics::RobotModel& robot,
                   const ConstraintSettings& settings,
                   const kinematics::JointVector& q) {
  double joint = 1.0;
  for (int j = 0; j < kinematics::kNumJoints; ++j) {
    const auto& limits = robot.joint(j);
    joint *= jointLimitFactor(q(j), limits.min, limits.max,
                              settings.joint_gamma[static_cast<std::size_t>(j)]);
  }
  return joint;
}

// Eq. 7's sine of each joint (0 outside its limits), for the solutions of one branch: they
// differ only by whole turns of the joints that turn more than once, so each joint's few
// values are computed once.
class JointSines {
 public:
  explicit JointSines(const kinematics::RobotModel& robot) : robot_(robot) {}
  double operator()(int j, double q) {
    Seen& seen = seen_[static_cast<std::size_t>(j)];
    for (std::size_t i = 0; i < seen.count; ++i) {
      if (seen.q[i] == q) return seen.sine[i];
    }
    const auto& limits = robot_.joint(j);
    const double sine = jointLimitFactor(q, limits.min, limits.max, 1.0);
    if (seen.count < seen.q.size()) {
      seen.q[seen.count] = q;
      seen.sine[seen.count++] = sine;
    }
    return sine;
  }

 private:
  struct Seen {
    std::array<double, 3> q{}, sine{};
    std::size_t count = 0;
  };
  const kinematics::RobotModel& robot_;
  std::array<Seen, kinematics::kNumJoints> seen_{};
};

// The branch's solution farthest from the limits and its sines.
struct Farthest {
  const kinematics::IkSolution* solution = nullptr;  ///< null when the branch has none
  std::array<double, kinematics::kNumJoints> sines{};
};

// Eq. 7's joint factor from the sines: with one γ for all joints, the product's power (one pow
// instead of six; equal to the product of the powers up to rounding).
double jointFactor(const ConstraintSettings& settings,
                   const std::array<double, kinematics::kNumJoints>& sines) {
  const auto& g = settings.joint_gamma;
  const bool one_gamma = std::all_of(g.begin(), g.end(), [&](double v) { return v == g[0]; });
  double product = 1.0;
  for (std::size_t j = 0; j < sines.size(); ++j) {
    product *= one_gamma || g[j] == 1.0 ? sines[j] : std::pow(sines[j], g[j]);
  }
  return one_gamma && g[0] != 1.0 ? std::pow(product, g[0]) : product;
}

// Among the branch's solutions (they differ only by whole turns of joints like J6), the one
// farthest from the limits (the first of equals).
Farthest farthestFromLimits(const kinematics::RobotModel& robot,
                            const ConstraintSettings& settings,
                            const std::vector<kinematics::IkSolution>& all,
                            const kinematics::IkBranch& branch) {
  const auto& g = settings.joint_gamma;
  const bool one_gamma = std::all_of(g.begin(), g.end(), [&](double v) { return v == g[0]; });
  JointSines sine(robot);
  Farthest best;
  double best_score = 0.0;
  for (const kinematics::IkSolution& s : all) {
    if (!(s.branch == branch)) continue;
    if (!s.within_limits) {  // a joint outside its limits: every sine product is 0
      if (!best.solution) best = {&s, {}};
      continue;
    }
    std::array<double, kinematics::kNumJoints> sines{};
    for (int j = 0; j < kinematics::kNumJoints; ++j)
      sines[static_cast<std::size_t>(j)] = sine(j, s.q(j));
    // With one γ the product of the sines orders the solutions as the factor does.
    double score = 1.0;
    for (double v : sines) score *= v;
    if (!one_gamma) score = jointFactor(settings, sines);
    if (!best.solution || score > best_score) {
      best = {&s, sines};
      best_score = score;
    }
  }
  return best;
}

// The rest of the cell's score once the branch's joints q (joint factor `joint`) are chosen.
template <class Clearance>
CellScore scoreJoints(const kinematics::RobotModel& robot,
                      const ConstraintSettings& settings,
                      const kinematics::JointVector& q,
                      double joint,
                      Clearance&& clearance) {
  CellScore best;
  best.q = q;
  best.joint = static_cast<float>(joint);
  if (best.joint <= 0.0f) {
    best.limit = Limit::kJointLimit;
    best.singularity = 0.0f;
    return best;
  }
  const kinematics::SingularityMeasures m = robot.singularity(q, false);
  const double sing =
      rampFactor(m.wrist, settings.wrist.low, settings.wrist.high, settings.wrist.gamma) *
      rampFactor(m.elbow, settings.elbow.low, settings.elbow.high, settings.elbow.gamma) *
      rampFactor(m.shoulder, settings.shoulder.low, settings.shoulder.high,
                 settings.shoulder.gamma);
  best.singularity = static_cast<float>(sing);
  const double c = sing > 0.0 ? clearance(q) : 1.0;
  best.clearance = static_cast<float>(c);
  best.f = static_cast<float>(static_cast<double>(best.joint) * sing * c);
  const float lowest = std::min({best.joint, best.singularity, best.clearance});
  best.limit = lowest >= 1.0f               ? Limit::kNone
               : best.joint == lowest       ? Limit::kJointLimit
               : best.singularity == lowest ? Limit::kSingularity
                                            : Limit::kClearance;
  return best;
}

// The map's memory against map.memory_limit_mb and what this process can still allocate, and its
// work (a distance per body pair, branch and cell at most) against kMaxMapPairChecks: refused
// before anything is allocated or computed.
void checkMapCost(const collision::Scene& scene,
                  std::size_t nb,
                  std::size_t na,
                  std::size_t nt,
                  const MapRequest& request) {
  const std::string grid = fmt::format("{} branch(es) x {} angles x {} time samples", nb, na, nt);
  const std::string coarser =
      "a coarser map.angle_step_deg, a larger scan.dt_s, a fixed map.branch";
  const std::size_t bytes = mapBytes(nb, na, nt);
  const std::size_t available = kinematics::availableMemoryBytes();
  if (bytes > request.memory_limit_bytes || bytes > available) {
    const bool setting = request.memory_limit_bytes <= available;
    throw InputError(
        fmt::format("map: {} need {}, over {} ({}): expected {} or {}", grid,
                    kinematics::megabytes(static_cast<double>(bytes)),
                    setting ? "map.memory_limit_mb" : "the memory this machine has available",
                    kinematics::megabytes(
                        static_cast<double>(setting ? request.memory_limit_bytes : available)),
                    coarser, setting ? "a higher limit" : "more memory"));
  }
  const double checks =
      static_cast<double>(nb * na * nt) * static_cast<double>(scene.pairs().size());
  if (checks > kMaxMapPairChecks) {
    throw InputError(fmt::format(
        "map: {} x {} body pairs = {:.1e} distance checks at most, over the {:.0e} a map takes "
        "on (hours of work on a workstation): expected fewer obstacles, "
        "constraints.clearance.pairs "
        "that exclude pairs which cannot meet, or {}",
        grid, scene.pairs().size(), checks, kMaxMapPairChecks, coarser));
  }
}

ConfigMap emptyMap(const collision::Scene& scene,
                   const kinematics::ScanPath& path,
                   const MapRequest& request) {
  ConfigMap map;
  map.angles = mapAngles(scene.cell().table, request.angle_step);
  for (const auto& s : path.samples) map.times.push_back(s.t);
  map.branches = request.branches;
  const std::size_t nb = map.branches.size(), na = map.angles.size(), nt = map.times.size();
  checkMapCost(scene, nb, na, nt, request);
  const std::size_t cells = nb * na * nt;
  map.f.assign(cells, 0.0f);
  map.joint.assign(cells, 0.0f);
  map.singularity.assign(cells, 0.0f);
  map.clearance.assign(cells, 1.0f);
  map.limit.assign(cells, static_cast<std::uint8_t>(Limit::kUnreachable));
  return map;
}

void store(ConfigMap& map, std::size_t i, const CellScore& s) {
  map.f[i] = s.f;
  map.joint[i] = s.joint;
  map.singularity[i] = s.singularity;
  map.clearance[i] = s.clearance;
  map.limit[i] = static_cast<std::uint8_t>(s.limit);
}

// Every (angle, time) cell in parallel: score(cell's θ, flange target, solutions, a, t), then
// the progress report. Each task takes whole pieces of θ rows, in a serpentine (even rows
// forward in time, odd rows backward), so the next cell a thread scores is usually a
// neighbour of its last one: what MapClearance's motion bounds need to skip queries.
template <class ScoreCell>
void forEachCell(const collision::Scene& scene,
                 const kinematics::ScanPath& path,
                 const ConfigMap& map,
                 const ProgressFn& progress,
                 ScoreCell&& score) {
  const kinematics::CellModel& cell = scene.cell();
  const std::size_t na = map.angles.size(), nt = map.times.size(), cells = na * nt;
  // Pieces per row: enough work items for the threads to share even when rows are few.
  const std::size_t pieces = std::clamp<std::size_t>(64 / std::max<std::size_t>(na, 1), 1,
                                                     std::max<std::size_t>(nt / 64, 1));
  const std::size_t piece = (nt + pieces - 1) / pieces;
  std::atomic<std::size_t> done{0};
  const std::size_t report_every = std::max<std::size_t>(1, cells / 200);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, na * pieces, 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t w = r.begin(); w != r.end(); ++w) {
                        const std::size_t a = w / pieces, first = (w % pieces) * piece;
                        const std::size_t n = std::min(nt, first + piece) - std::min(nt, first);
                        const Eigen::Isometry3d X_BP = cell.partIn(map.angles[a]);
                        for (std::size_t i = 0; i < n; ++i) {
                          const std::size_t t = a % 2 == 0 ? first + i : nt - 1 - (first + i);
                          const Eigen::Isometry3d X_BF =
                              cell.flangeTarget(X_BP, path.samples[t].X_PS);
                          score(map.angles[a], X_BF, cell.robot.ik(X_BF), a, t);
                          const std::size_t k = done.fetch_add(1, std::memory_order_relaxed) + 1;
                          if (progress && (k % report_every == 0 || k == cells)) progress(k, cells);
                        }
                      }
                    });
}

}  // namespace

CellScore scoreCell(const collision::Scene& scene,
                    const ConstraintSettings& settings,
                    collision::MapClearance& clearance,
                    std::size_t branch_index,
                    const std::vector<kinematics::IkSolution>& solutions,
                    const kinematics::IkBranch& branch) {
  const kinematics::RobotModel& robot = scene.cell().robot;
  const Farthest best = farthestFromLimits(robot, settings, solutions, branch);
  if (!best.solution) return {};  // unreachable on this branch
  return scoreJoints(
      robot, settings, best.solution->q, jointFactor(settings, best.sines),
      [&](const kinematics::JointVector& q) { return clearance.factor(branch_index, q); });
}

ConfigMap buildConfigMap(const collision::Scene& scene,
                         const ConstraintSettings& settings,
                         const kinematics::ScanPath& path,
                         const MapRequest& request,
                         const ProgressFn& progress) {
  ConfigMap map = emptyMap(scene, path, request);
  const std::size_t nb = map.branches.size();
  const collision::MapClearanceOptions options{.skip = request.motion_bounds,
                                               .exact_distances = request.exact_distances};
  tbb::enumerable_thread_specific<collision::MapClearance> clearances(std::cref(scene), nb,
                                                                      options);
  forEachCell(
      scene, path, map, progress,
      [&](double theta, const Eigen::Isometry3d& X_BF,
          const std::vector<kinematics::IkSolution>& solutions, std::size_t a, std::size_t t) {
        collision::MapClearance& clearance = clearances.local();
        clearance.beginCell(theta, X_BF);
        for (std::size_t b = 0; b < nb; ++b) {
          store(map, map.index(b, a, t),
                scoreCell(scene, settings, clearance, b, solutions, map.branches[b]));
        }
      });
  return map;
}

namespace detail {

ConfigMap buildConfigMapReference(const collision::Scene& scene,
                                  const ConstraintSettings& settings,
                                  const kinematics::ScanPath& path,
                                  const MapRequest& request) {
  ConfigMap map = emptyMap(scene, path, request);
  const kinematics::RobotModel& robot = scene.cell().robot;
  tbb::enumerable_thread_specific<collision::ClearanceEvaluator> evaluators(
      std::cref(scene), false, collision::Geometry::kMap);
  forEachCell(
      scene, path, map, {},
      [&](double theta, const Eigen::Isometry3d&,
          const std::vector<kinematics::IkSolution>& solutions, std::size_t a, std::size_t t) {
        collision::ClearanceEvaluator& evaluator = evaluators.local();
        for (std::size_t b = 0; b < map.branches.size(); ++b) {
          // Eq. 7 on every solution of the branch, the first strictly best kept.
          const kinematics::IkSolution* best = nullptr;
          float best_joint = 0.0f;
          for (const kinematics::IkSolution& s : solutions) {
            if (!(s.branch == map.branches[b])) continue;
            const double joint = jointFactor(robot, settings, s.q);
            if (!best || joint > best_joint) {
              best = &s;
              best_joint = static_cast<float>(joint);
            }
          }
          if (!best) continue;
          store(map, map.index(b, a, t),
                scoreJoints(
                    robot, settings, best->q, jointFactor(robot, settings, best->q),
                    [&](const kinematics::JointVector& q) { return evaluator.factor(theta, q); }));
        }
      });
  return map;
}

}  // namespace detail

}  // namespace scanplan::planner
