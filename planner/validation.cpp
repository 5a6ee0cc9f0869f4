#include <scanplan/planner/validation.h>

#include <scanplan/kinematics/error.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <tuple>
#include <type_traits>
#include <variant>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <scanplan/collision/clearance.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/units.h>

namespace scanplan::planner {
namespace {

using kinematics::JointVector;
using kinematics::kNumJoints;

constexpr double kInf = std::numeric_limits<double>::infinity();

// How far a reported distance may exceed the true one. FCL's GJK (libccd) stops at
// distance_tolerance = 1e-6 m; on curved shapes its distance was seen up to 1e-5 m off
// (tests/test_collision.cpp, kGjkCurvedTol = 2e-5). The bounded query itself is exact to 1e-9 m.
constexpr double kDistanceSlack = 5e-5;  // m
// Joint angles read back from a trajectory CSV are exact to 12 significant digits: a joint at
// its limit must not fail on the last printed digit.
constexpr double kLimitTolerance = 1e-9;        // rad
constexpr std::size_t kMaxSamples = 5'000'000;  // densified poses (about 1.3 GB)
// Bisection poses in the worst case (boundRefinement()): about as long as checking kMaxSamples.
constexpr std::size_t kMaxRefinementPoses = 5'000'000;
// Each bisection halves the motion bound; 60 halvings take any real motion far below any
// resolution. Reaching it ends the refinement with a (conservative) collision span.
constexpr int kMaxDepth = 60;

struct Pose {
  double t = 0.0;
  double theta = 0.0;
  JointVector q = JointVector::Zero();
};

Pose midpoint(const Pose& a, const Pose& b) {
  return {0.5 * (a.t + b.t), 0.5 * (a.theta + b.theta), 0.5 * (a.q + b.q)};
}

// A ball enclosing part of a body, in the frame the bound is computed in.
struct Ball {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  double r = 0.0;
};

// Balls enclosing `shape` (whose frame is X_FB · X_BG in frame F): one bounding ball for a
// primitive, the vertices of a mesh (every bound below is a convex function of the point, so
// its maximum over the mesh's hull is at a vertex).
void appendBalls(const kinematics::Shape& shape,
                 const Eigen::Isometry3d& X_FB,
                 std::vector<Ball>& out) {
  const Eigen::Isometry3d X_FG = X_FB * shape.X_BG;
  std::visit(
      [&](const auto& g) {
        using G = std::decay_t<decltype(g)>;
        if constexpr (std::is_same_v<G, kinematics::Box>) {
          out.push_back({X_FG.translation(), 0.5 * g.size.norm()});
        } else if constexpr (std::is_same_v<G, kinematics::Sphere>) {
          out.push_back({X_FG.translation(), g.radius});
        } else if constexpr (std::is_same_v<G, kinematics::Cylinder>) {
          out.push_back({X_FG.translation(), std::hypot(g.radius, 0.5 * g.length)});
        } else if constexpr (std::is_same_v<G, kinematics::Capsule>) {
          out.push_back({X_FG.translation(), g.radius + 0.5 * g.length});
        } else {
          const kinematics::LoadedMesh loaded = kinematics::loadMesh(g.path, g.options);
          for (const Eigen::Vector3d& v : loaded.mesh.vertices) out.push_back({X_FG * v, 0.0});
        }
      },
      shape.geometry);
}

// A point p on link k (coordinates p_k in DH frame k) is moved by joint i < k (axis z of frame
// i) at |q̇_i| times its distance from that axis. In frame i, p = Rz(θ_i)·((a_i, 0, d_i) +
// Rx(α_i)·v) with v its coordinates in frame i + 1, so the distance is |xy((a_i,0,0) + Rx(α_i)v)|:
// exact for i = k − 1 (v = p_k), and at most |a_i| + |v| ≤ |a_i| + Σ_{l=i+1}^{k−1} √(a_l² + d_l²)
// + |p_k| for the joints further down the chain, whatever the configuration.
detail::BodyBound armBound(const kinematics::RobotModel& robot,
                           int link,
                           const std::vector<Ball>& balls) {
  detail::BodyBound b;
  b.link = link;
  double rho = 0.0;  // farthest point from the frame origin
  for (const Ball& ball : balls) rho = std::max(rho, ball.c.norm() + ball.r);
  for (int i = 0; i < link; ++i) {
    const kinematics::DhJoint& joint = robot.joint(i);
    double r = 0.0;
    if (i == link - 1) {
      const Eigen::AngleAxisd Rx(joint.alpha, Eigen::Vector3d::UnitX());
      for (const Ball& ball : balls) {
        const Eigen::Vector3d p = Rx * ball.c + Eigen::Vector3d(joint.a, 0.0, 0.0);
        r = std::max(r, p.head<2>().norm() + ball.r);
      }
    } else {
      double chain = 0.0;
      for (int l = i + 1; l < link; ++l) chain += std::hypot(robot.joint(l).a, robot.joint(l).d);
      r = std::abs(joint.a) + chain + rho;
    }
    b.arm[static_cast<std::size_t>(i)] = r;
  }
  return b;
}

// A point p_R on the table top is at X_WA · Rz(θ) · E · p_R: its distance from the axis (z of
// A) is |xy(E · p_R)| whatever θ.
detail::BodyBound tableBound(const kinematics::RotaryTableModel& table,
                             const std::vector<Ball>& balls) {
  detail::BodyBound b;
  b.on_table = true;
  const Eigen::Isometry3d E = table.axisError();
  for (const Ball& ball : balls)
    b.table = std::max(b.table, (E * ball.c).head<2>().norm() + ball.r);
  return b;
}

}  // namespace

namespace detail {

std::vector<BodyBound> bodyBounds(const collision::Scene& scene) {
  const kinematics::CellModel& cell = scene.cell();
  std::vector<BodyBound> out;
  for (const collision::BodyInfo& body : scene.bodies()) {
    std::vector<Ball> balls;
    switch (body.motion) {
      case collision::BodyMotion::kWorld:
        out.emplace_back();
        continue;
      case collision::BodyMotion::kRobotLink:
        for (const auto& s :
             cell.robot.definition().links[static_cast<std::size_t>(body.link)].shapes)
          appendBalls(s, Eigen::Isometry3d::Identity(), balls);
        out.push_back(armBound(cell.robot, body.link, balls));
        continue;
      case collision::BodyMotion::kScanner:
        for (const auto& s : cell.scanner.body) appendBalls(s, cell.scanner.X_FS, balls);
        out.push_back(armBound(cell.robot, kNumJoints, balls));
        continue;
      case collision::BodyMotion::kTable:
        break;
    }
    // The table-carried bodies as Scene builds them: the table's cylinder (top at z = 0), the
    // part, and the obstacles the table carries (names are unique in a scene).
    if (body.name == "table") {
      kinematics::Shape s;
      s.geometry = kinematics::Cylinder{cell.table.radius, cell.table.height};
      s.X_BG.translation() << 0.0, 0.0, -0.5 * cell.table.height;
      appendBalls(s, Eigen::Isometry3d::Identity(), balls);
    } else if (body.name == "part") {
      kinematics::Shape s;
      s.geometry = cell.part.mesh;
      s.X_BG = cell.part.X_RP;
      appendBalls(s, Eigen::Isometry3d::Identity(), balls);
    } else {
      const auto it =
          std::find_if(cell.obstacles.begin(), cell.obstacles.end(),
                       [&](const kinematics::Obstacle& o) { return o.name == body.name; });
      if (it == cell.obstacles.end()) {
        throw std::logic_error("validateTrajectory: no geometry for table body '" + body.name +
                               "'");
      }
      for (const auto& s : it->shapes) appendBalls(s, Eigen::Isometry3d::Identity(), balls);
    }
    out.push_back(tableBound(cell.table, balls));
  }
  return out;
}

// Two bodies on the arm's chain move relative to each other only through the joints between
// them; bodies on different carriers add their motions.
double pairMotion(const BodyBound& a,
                  const BodyBound& b,
                  const std::array<double, kNumJoints>& dq,
                  double dtheta) noexcept {
  double m = 0.0;
  if (a.link >= 0 && b.link >= 0) {
    const BodyBound& far = a.link >= b.link ? a : b;
    for (int i = std::min(a.link, b.link); i < far.link; ++i) {
      m += dq[static_cast<std::size_t>(i)] * far.arm[static_cast<std::size_t>(i)];
    }
    return m;
  }
  for (const BodyBound* body : {&a, &b}) {
    for (int i = 0; i < body->link; ++i) {
      m += dq[static_cast<std::size_t>(i)] * body->arm[static_cast<std::size_t>(i)];
    }
    if (body->on_table) m += dtheta * body->table;
  }
  return m;
}

}  // namespace detail

namespace {

struct PairSample {
  double distance = 0.0;  // m, a lower bound (d_high when beyond it), 0 when penetrating
  bool beyond = false;    // only known to be at least d_high
  bool penetrating = false;
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();  // midpoint of the witness points, world
};
using PoseCheck = std::vector<PairSample>;

PoseCheck checkPose(collision::ClearanceEvaluator& evaluator, const Pose& pose) {
  const collision::ClearanceResult r =
      evaluator.evaluate(pose.theta, pose.q, {.bounded = true, .witness_points = true});
  PoseCheck out(r.pairs.size());
  for (std::size_t i = 0; i < r.pairs.size(); ++i) {
    const collision::PairClearance& p = r.pairs[i];
    out[i].penetrating = p.penetrating;
    out[i].beyond = p.beyond_bound;
    // Anything but a non-negative number proves nothing: read it as contact.
    out[i].distance = p.penetrating || !(p.distance >= 0.0) ? 0.0 : p.distance;
    if (!p.beyond_bound) out[i].p_W = 0.5 * (p.p_a + p.p_b);
  }
  return out;
}

// Each pair's least distance (below its d_high) and when it first came that close.
struct Closest {
  std::vector<double> distance;  // per pair, kInf when never below d_high
  std::vector<double> t;

  void update(const PoseCheck& check, double t_pose) {
    grow(check.size());
    for (std::size_t i = 0; i < check.size(); ++i) {
      if (!check[i].beyond && check[i].distance < distance[i]) {
        distance[i] = check[i].distance;
        t[i] = t_pose;
      }
    }
  }
  void update(const Closest& other) {
    grow(other.distance.size());
    for (std::size_t i = 0; i < other.distance.size(); ++i) {
      if (other.distance[i] < distance[i]) {
        distance[i] = other.distance[i];
        t[i] = other.t[i];
      }
    }
  }
  // The closest of the pairs `take` accepts: the least distance, then the earliest time, then
  // the first pair; -1 when none came below its d_high.
  template <class Take>
  int least(Take&& take) const {
    int best = -1;
    for (std::size_t i = 0; i < distance.size(); ++i) {
      if (!take(i) || !(distance[i] < kInf)) continue;
      const auto b = static_cast<std::size_t>(best);
      if (best < 0 || std::tie(distance[i], t[i]) < std::tie(distance[b], t[b])) {
        best = static_cast<int>(i);
      }
    }
    return best;
  }

 private:
  void grow(std::size_t n) {
    if (distance.size() >= n) return;
    distance.resize(n, kInf);
    t.resize(n, 0.0);
  }
};

// Where a pair could not be proven apart: [t0, t1], with the smaller distance of its two ends
// and the contact point at t0.
struct Span {
  int pair = -1;
  double t0 = 0.0, t1 = 0.0;
  double distance = 0.0;
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();
};

struct IntervalOutcome {
  std::vector<Span> spans;
  std::size_t evaluations = 0;  // bisection poses
  Closest closest;              // over the bisection poses
  double proven = kInf;         // lowest certified distance of the proven (sub)intervals
};

// A pair over an interval [a, b]: its motion bound L and what the end distances prove.
struct PairJudgement {
  bool in_contact = false;  // penetrating at both ends: one run, not refined
  double motion = 0.0;      // L, m
  double certified = 0.0;   // > 0: proven at least this far apart over the interval
};

PairJudgement judgePair(const detail::BodyBound& body_a,
                        const detail::BodyBound& body_b,
                        const std::array<double, kNumJoints>& dq,
                        double dtheta,
                        const PairSample& sa,
                        const PairSample& sb) {
  PairJudgement j;
  j.in_contact = sa.penetrating && sb.penetrating;
  j.motion = detail::pairMotion(body_a, body_b, dq, dtheta);
  // With true end distances δ ≥ d − s: δ(u) ≥ max(δ_a − L·u, δ_b − L·(1 − u)) over the
  // interval (u ∈ [0, 1]), whose minimum is min(δ_a, δ_b, (δ_a + δ_b − L)/2).
  const double da = sa.distance - kDistanceSlack, db = sb.distance - kDistanceSlack;
  j.certified = std::min({da, db, 0.5 * (da + db - j.motion)});
  return j;
}

std::array<double, kNumJoints> jointMotion(const Pose& a, const Pose& b) {
  std::array<double, kNumJoints> dq{};
  for (int j = 0; j < kNumJoints; ++j) dq[static_cast<std::size_t>(j)] = std::abs(b.q(j) - a.q(j));
  return dq;
}

// Conservative advancement by bisection over one densified interval (see validateTrajectory()).
class IntervalRefiner {
 public:
  IntervalRefiner(const std::vector<collision::PairInfo>& pairs,
                  const std::vector<detail::BodyBound>& bodies,
                  double resolution,
                  collision::ClearanceEvaluator& evaluator,
                  IntervalOutcome& out)
      : pairs_(pairs), bodies_(bodies), resolution_(resolution), evaluator_(evaluator), out_(out) {}

  void refine(const Pose& a,
              const PoseCheck& ca,
              const Pose& b,
              const PoseCheck& cb,
              const std::vector<int>& open,
              int depth) {
    const std::array<double, kNumJoints> dq = jointMotion(a, b);
    const double dtheta = std::abs(b.theta - a.theta);
    std::vector<int> unresolved;
    for (const int p : open) {
      const auto i = static_cast<std::size_t>(p);
      const PairSample &sa = ca[i], &sb = cb[i];
      const collision::PairInfo& pair = pairs_[i];
      const PairJudgement j =
          judgePair(bodies_[static_cast<std::size_t>(pair.a)],
                    bodies_[static_cast<std::size_t>(pair.b)], dq, dtheta, sa, sb);
      if (j.in_contact) {
        out_.spans.push_back({p, a.t, b.t, 0.0, sa.p_W});
        continue;
      }
      if (j.certified > 0.0) {
        out_.proven = std::min(out_.proven, j.certified);
        continue;
      }
      if (j.motion <= resolution_ || depth >= kMaxDepth) {
        out_.spans.push_back({p, a.t, b.t, std::min(sa.distance, sb.distance), sa.p_W});
        continue;
      }
      unresolved.push_back(p);
    }
    if (unresolved.empty()) return;
    const Pose m = midpoint(a, b);
    const PoseCheck cm = checkPose(evaluator_, m);
    ++out_.evaluations;
    out_.closest.update(cm, m.t);
    refine(a, ca, m, cm, unresolved, depth + 1);
    refine(m, cm, b, cb, unresolved, depth + 1);
  }

 private:
  const std::vector<collision::PairInfo>& pairs_;
  const std::vector<detail::BodyBound>& bodies_;
  double resolution_;
  collision::ClearanceEvaluator& evaluator_;
  IntervalOutcome& out_;
};

// One checked pose or interval that breaks a bound: over [t0, t1], `value` at t; `excess` (> 0)
// orders the items of a run by severity.
struct Breach {
  double t0 = 0.0, t1 = 0.0, t = 0.0;
  double value = 0.0, limit = 0.0, excess = 0.0;
};

// Runs of consecutive breaches (item(k) for k < count; nullopt: within bounds) become one
// Violation each, with the worst breach's value and time.
template <class Item>
void collectRuns(std::vector<Violation>& out,
                 Violation::Kind kind,
                 const std::string& what,
                 int joint,
                 std::size_t count,
                 const Item& item) {
  std::optional<Violation> run;
  double worst = 0.0;
  for (std::size_t k = 0; k <= count; ++k) {
    const std::optional<Breach> b = k < count ? item(k) : std::nullopt;
    if (!b) {
      if (run) out.push_back(std::move(*run));
      run.reset();
      continue;
    }
    if (!run) {
      run = Violation{};
      run->kind = kind;
      run->what = what;
      run->joint = joint;
      run->t_start = b->t0;
      worst = -1.0;
    }
    if (b->excess > worst) {
      worst = b->excess;
      run->t = b->t;
      run->value = b->value;
      run->limit = b->limit;
    }
    run->t_end = b->t1;
  }
}

// A value against [min, max] at time t.
std::optional<Breach> outside(double t, double value, double min, double max) {
  if (value > max + kLimitTolerance) return Breach{t, t, t, value, max, value - max};
  if (value < min - kLimitTolerance) return Breach{t, t, t, value, min, min - value};
  return std::nullopt;
}

// A rate over [t0, t1] against its bound (with the relative tolerance), reported at t.
std::optional<Breach> tooFast(
    double t0, double t1, double t, double rate, double bound, double tol) {
  if (rate > bound * (1.0 + tol)) return Breach{t0, t1, t, rate, bound, rate - bound};
  return std::nullopt;
}

std::string jointName(int j) { return "joint " + std::to_string(j + 1); }

void checkLimitsAndSpeeds(const kinematics::CellModel& cell,
                          const kinematics::Trajectory& original,
                          const std::vector<kinematics::TrajectorySample>& s,
                          double omega_max,
                          double alpha_max,
                          double tol,
                          std::vector<Violation>& out) {
  const std::size_t n = s.size();
  for (int j = 0; j < kNumJoints; ++j) {
    const kinematics::DhJoint& joint = cell.robot.joint(j);
    collectRuns(out, Violation::Kind::kJointLimit, jointName(j), j, n,
                [&](std::size_t k) { return outside(s[k].t, s[k].q(j), joint.min, joint.max); });
    if (joint.max_speed > 0.0) {
      collectRuns(out, Violation::Kind::kJointSpeed, jointName(j), j, n - 1, [&](std::size_t k) {
        const double v = std::abs(s[k + 1].q(j) - s[k].q(j)) / (s[k + 1].t - s[k].t);
        return tooFast(s[k].t, s[k + 1].t, s[k].t, v, joint.max_speed, tol);
      });
    }
  }
  if (!cell.table.continuous) {
    collectRuns(out, Violation::Kind::kTableLimit, "table", -1, n, [&](std::size_t k) {
      return outside(s[k].t, s[k].theta, cell.table.min, cell.table.max);
    });
  }
  if (omega_max > 0.0) {
    collectRuns(out, Violation::Kind::kTableSpeed, "table", -1, n - 1, [&](std::size_t k) {
      const double w = std::abs(s[k + 1].theta - s[k].theta) / (s[k + 1].t - s[k].t);
      return tooFast(s[k].t, s[k + 1].t, s[k].t, w, omega_max, tol);
    });
  }
  const auto& o = original.samples;
  if (alpha_max > 0.0 && o.size() >= 3) {
    // On the original samples (planner::evaluate()'s finite differences), reported at the knot
    // t_k−1 where the piecewise-linear motion changes speed.
    collectRuns(out, Violation::Kind::kTableAccel, "table", -1, o.size() - 2, [&](std::size_t i) {
      const std::size_t k = i + 2;
      const double dt1 = o[k].t - o[k - 1].t, dt0 = o[k - 1].t - o[k - 2].t;
      const double w1 = (o[k].theta - o[k - 1].theta) / dt1;
      const double w0 = (o[k - 1].theta - o[k - 2].theta) / dt0;
      const double a = std::abs(w1 - w0) / (0.5 * (dt0 + dt1));
      const double t = o[k - 1].t;
      return tooFast(t, t, t, a, alpha_max, tol);
    });
  }
}

std::string pairName(const collision::Scene& scene, int pair) {
  const collision::PairInfo& p = scene.pairs()[static_cast<std::size_t>(pair)];
  return scene.bodies()[static_cast<std::size_t>(p.a)].name + " - " +
         scene.bodies()[static_cast<std::size_t>(p.b)].name;
}

}  // namespace

std::string kindName(Violation::Kind kind) {
  switch (kind) {
    case Violation::Kind::kJointLimit:
      return "joint limit";
    case Violation::Kind::kTableLimit:
      return "table limit";
    case Violation::Kind::kJointSpeed:
      return "joint speed";
    case Violation::Kind::kTableSpeed:
      return "table speed";
    case Violation::Kind::kTableAccel:
      return "table acceleration";
    case Violation::Kind::kCollision:
      return "collision";
    case Violation::Kind::kSensor:
      return "sensor";
  }
  return "unknown";
}

std::string describe(const Violation& v) {
  const std::string when =
      fmt::format("{}: {} at t = {:.3f} s ({:.3f} … {:.3f} s): ", kindName(v.kind), v.what, v.t,
                  v.t_start, v.t_end);
  const char* cmp = v.value > v.limit ? ">" : "<";
  switch (v.kind) {
    case Violation::Kind::kJointLimit:
    case Violation::Kind::kTableLimit:
      return when + fmt::format("{:.2f} deg {} {:.2f} deg", toDeg(v.value), cmp, toDeg(v.limit));
    case Violation::Kind::kJointSpeed:
    case Violation::Kind::kTableSpeed:
      return when + fmt::format("{:.2f} deg/s > {:.2f} deg/s", toDeg(v.value), toDeg(v.limit));
    case Violation::Kind::kTableAccel:
      return when + fmt::format("{:.2f} deg/s² > {:.2f} deg/s²", toDeg(v.value), toDeg(v.limit));
    case Violation::Kind::kCollision:
      return when + fmt::format("distance {:.3f} mm, contact at ({:.1f}, {:.1f}, {:.1f}) mm",
                                toMm(v.value), toMm(v.p_W.x()), toMm(v.p_W.y()), toMm(v.p_W.z()));
    case Violation::Kind::kSensor:
      return fmt::format("sensor: {} {:.3f} … {:.3f} s: {}", v.what, v.t_start, v.t_end, v.note);
  }
  return when;
}

kinematics::Trajectory densify(const kinematics::Trajectory& trajectory, double dt) {
  if (!(dt > 0.0) || !std::isfinite(dt)) {
    throw std::invalid_argument(
        fmt::format("densify: sample step {} s: expected a positive finite number", dt));
  }
  const auto& in = trajectory.samples;
  std::vector<std::size_t> steps(in.empty() ? 0 : in.size() - 1);
  std::size_t total = in.size();
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const double span = in[k + 1].t - in[k].t;
    if (!(span > 0.0) || !std::isfinite(span)) {
      throw std::invalid_argument(fmt::format(
          "densify: sample {} at t = {} s does not follow t = {} s: expected strictly increasing "
          "times",
          k + 1, in[k + 1].t, in[k].t));
    }
    // A ratio within 1e-9 of a whole number is that number (no sliver step from rounding).
    const double n = std::max(1.0, std::ceil(span / dt - 1e-9));
    if (n > static_cast<double>(kMaxSamples) ||
        total + static_cast<std::size_t>(n) - 1 > kMaxSamples) {
      throw InputError(fmt::format(
          "the trajectory's {:.6g} s sampled every {} s would be more than {} poses: expected a "
          "shorter trajectory or a lower rate (scanner.frame_rate_hz)",
          in.back().t - in.front().t, dt, kMaxSamples));
    }
    steps[k] = static_cast<std::size_t>(n);
    total += steps[k] - 1;
  }
  kinematics::Trajectory out;
  out.samples.reserve(total);
  for (std::size_t k = 0; k < in.size(); ++k) {
    out.samples.push_back(in[k]);
    if (k + 1 == in.size()) break;
    const kinematics::TrajectorySample &a = in[k], &b = in[k + 1];
    const Eigen::Quaterniond qa(a.X_PS.linear()), qb(b.X_PS.linear());
    for (std::size_t i = 1; i < steps[k]; ++i) {
      const double s = static_cast<double>(i) / static_cast<double>(steps[k]);
      kinematics::TrajectorySample x;
      x.t = a.t + s * (b.t - a.t);
      x.theta = a.theta + s * (b.theta - a.theta);
      x.q = a.q + s * (b.q - a.q);
      x.f = std::numeric_limits<double>::quiet_NaN();
      x.scanning = a.scanning && b.scanning;
      x.X_PS.linear() = qa.slerp(s, qb).toRotationMatrix();
      x.X_PS.translation() =
          a.X_PS.translation() + s * (b.X_PS.translation() - a.X_PS.translation());
      out.samples.push_back(std::move(x));
    }
  }
  return out;
}

namespace {

void checkInputs(const kinematics::Trajectory& trajectory, const ValidationSettings& settings) {
  if (trajectory.samples.empty()) {
    throw std::invalid_argument("validateTrajectory: the trajectory has no samples");
  }
  if (!(settings.collision_resolution > 0.0) || !std::isfinite(settings.collision_resolution)) {
    throw std::invalid_argument(fmt::format(
        "validateTrajectory: collision_resolution {} m: expected a positive finite number",
        settings.collision_resolution));
  }
  if (!(settings.speed_tolerance >= 0.0) || !std::isfinite(settings.speed_tolerance)) {
    throw std::invalid_argument(
        fmt::format("validateTrajectory: speed_tolerance {}: expected a non-negative finite number",
                    settings.speed_tolerance));
  }
  for (const auto& s : trajectory.samples) {
    if (!std::isfinite(s.t) || !std::isfinite(s.theta) || !s.q.allFinite()) {
      throw std::invalid_argument(
          fmt::format("validateTrajectory: sample at t = {} s is not finite", s.t));
    }
  }
}

// Clearance at every densified pose, and conservative advancement over every interval.
struct ClearanceSweep {
  std::vector<Pose> poses;
  std::vector<PoseCheck> checks;           // one per pose
  std::vector<IntervalOutcome> intervals;  // one per pair of consecutive poses
};

// The largest motion bound over [a, b] of a pair its end distances do not prove apart (0: none).
double unprovenMotion(const std::vector<collision::PairInfo>& pairs,
                      const std::vector<detail::BodyBound>& bodies,
                      const Pose& a,
                      const PoseCheck& ca,
                      const Pose& b,
                      const PoseCheck& cb) {
  const std::array<double, kNumJoints> dq = jointMotion(a, b);
  const double dtheta = std::abs(b.theta - a.theta);
  double unproven = 0.0;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const PairJudgement j =
        judgePair(bodies[static_cast<std::size_t>(pairs[i].a)],
                  bodies[static_cast<std::size_t>(pairs[i].b)], dq, dtheta, ca[i], cb[i]);
    if (!j.in_contact && !(j.certified > 0.0)) unproven = std::max(unproven, j.motion);
  }
  return unproven;
}

// The bisection's worst case over an interval whose largest unproven motion bound is `motion`:
// it splits until every open pair is proven or its bound is at most the resolution (a halving
// halves every bound), so it checks at most 2^D − 1 poses, D the halvings that bring `motion`
// to the resolution (at most kMaxDepth).
double worstRefinement(double motion, double resolution) {
  if (!(motion > resolution)) return 0.0;
  const double depth = std::min<double>(kMaxDepth, std::ceil(std::log2(motion / resolution)));
  return std::exp2(depth) - 1.0;
}

// Refuses, before it runs, a refinement whose worst case exceeds kMaxRefinementPoses: a joint
// turning thousands of degrees between two samples would have its interval split without end
// (time, and a collision span per piece).
void boundRefinement(const std::vector<collision::PairInfo>& pairs,
                     const std::vector<detail::BodyBound>& bodies,
                     const std::vector<Pose>& poses,
                     const std::vector<PoseCheck>& checks,
                     double resolution) {
  const auto motion = [&](std::size_t k) {
    return unprovenMotion(pairs, bodies, poses[k], checks[k], poses[k + 1], checks[k + 1]);
  };
  const auto worst = [&](std::size_t k) { return worstRefinement(motion(k), resolution); };
  const double total = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, poses.size() - 1), 0.0,
      [&](const tbb::blocked_range<std::size_t>& r, double sum) {
        for (std::size_t k = r.begin(); k != r.end(); ++k) sum += worst(k);
        return sum;
      },
      std::plus<>());
  if (total <= static_cast<double>(kMaxRefinementPoses)) return;
  std::size_t at = 0;  // the interval with the most, for the message
  double most = 0.0;
  for (std::size_t k = 0; k + 1 < poses.size(); ++k) {
    if (const double w = worst(k); w > most) {
      most = w;
      at = k;
    }
  }
  throw InputError(fmt::format(
      "the continuous collision check could need up to {:.3g} poses between the densified "
      "samples, more than {} (the most, {:.3g}, between t = {:.6g} and {:.6g} s, where a body "
      "may move {:.3g} m): expected smaller joint and table steps between samples, or a coarser "
      "validation.collision_resolution_mm than {:.6g}",
      total, kMaxRefinementPoses, most, poses[at].t, poses[at + 1].t, motion(at),
      toMm(resolution)));
}

// f(k) for every k in [0, n), in parallel, each k a task of its own: the costly poses and
// intervals (near contact, refined deep) come in runs of neighbours, which chunks of neighbours
// would leave to one thread.
template <class F>
void eachInParallel(std::size_t n, const F& f) {
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, n, 1),
      [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t k = r.begin(); k != r.end(); ++k) f(k);
      },
      tbb::simple_partitioner());
}

ClearanceSweep sweepClearance(const collision::Scene& scene,
                              const std::vector<kinematics::TrajectorySample>& samples,
                              double resolution) {
  const std::size_t n = samples.size();
  const std::vector<detail::BodyBound> bodies = detail::bodyBounds(scene);
  const auto& pairs = scene.pairs();
  ClearanceSweep sweep;
  std::vector<Pose>& poses = sweep.poses;
  poses.resize(n);
  for (std::size_t k = 0; k < n; ++k) poses[k] = {samples[k].t, samples[k].theta, samples[k].q};
  tbb::enumerable_thread_specific<collision::ClearanceEvaluator> evaluators(
      [&] { return collision::ClearanceEvaluator(scene); });
  std::vector<PoseCheck>& checks = sweep.checks;
  checks.resize(n);
  eachInParallel(n, [&](std::size_t k) { checks[k] = checkPose(evaluators.local(), poses[k]); });
  boundRefinement(pairs, bodies, poses, checks, resolution);
  std::vector<int> all_pairs(pairs.size());
  std::iota(all_pairs.begin(), all_pairs.end(), 0);
  sweep.intervals.resize(n - 1);
  eachInParallel(n - 1, [&](std::size_t k) {
    IntervalRefiner refiner(pairs, bodies, resolution, evaluators.local(), sweep.intervals[k]);
    refiner.refine(poses[k], checks[k], poses[k + 1], checks[k + 1], all_pairs, 0);
  });
  return sweep;
}

// The sweep's results in time order (independent of how the work was split).
struct Gathered {
  Closest closest;
  double proven = kInf;
  std::vector<std::vector<Span>> spans;  // per pair
  std::size_t poses_checked = 0;
};

Gathered gatherInTimeOrder(const ClearanceSweep& sweep, std::size_t pair_count) {
  const std::size_t n = sweep.poses.size();
  Gathered g;
  g.spans.resize(pair_count);
  g.poses_checked = n;
  for (std::size_t k = 0; k < n; ++k) {
    const PoseCheck& check = sweep.checks[k];
    const double t = sweep.poses[k].t;
    g.closest.update(check, t);
    for (std::size_t p = 0; p < pair_count; ++p) {
      if (check[p].penetrating)
        g.spans[p].push_back({static_cast<int>(p), t, t, 0.0, check[p].p_W});
    }
    if (k + 1 == n) break;
    const IntervalOutcome& o = sweep.intervals[k];
    g.poses_checked += o.evaluations;
    g.closest.update(o.closest);
    g.proven = std::min(g.proven, o.proven);
    for (const Span& s : o.spans) g.spans[static_cast<std::size_t>(s.pair)].push_back(s);
  }
  if (n == 1) {
    for (const PairSample& s : sweep.checks[0])
      g.proven = std::min(g.proven, s.distance - kDistanceSlack);
  }
  return g;
}

// One collision violation per run of overlapping spans of a pair; true when there is any.
bool emitCollisions(const collision::Scene& scene,
                    std::vector<std::vector<Span>>& spans,
                    double resolution,
                    std::vector<Violation>& violations) {
  bool collided = false;
  for (std::size_t p = 0; p < spans.size(); ++p) {
    std::vector<Span>& list = spans[p];
    if (list.empty()) continue;
    collided = true;
    std::sort(list.begin(), list.end(), [](const Span& x, const Span& y) {
      return std::tie(x.t0, x.t1) < std::tie(y.t0, y.t1);
    });
    const auto emit = [&](const Violation& v) { violations.push_back(v); };
    Violation run;
    bool open = false;
    for (const Span& s : list) {
      if (open && s.t0 <= run.t_end) {
        run.t_end = std::max(run.t_end, s.t1);
        run.value = std::min(run.value, s.distance);
        continue;
      }
      if (open) emit(run);
      run = Violation{};
      run.kind = Violation::Kind::kCollision;
      run.what = pairName(scene, static_cast<int>(p));
      run.pair = static_cast<int>(p);
      run.t = run.t_start = s.t0;
      run.t_end = s.t1;
      run.value = s.distance;
      run.limit = resolution;
      run.p_W = s.p_W;
      open = true;
    }
    if (open) emit(run);
  }
  return collided;
}

// The sensors' broken rules as violations: the sensor's name, the run, the rule and what the
// sensor did there (with the bodies a presence volume saw).
void appendSensorViolations(const collision::Scene& scene,
                            const collision::SensorEvaluation& evaluation,
                            std::vector<Violation>& out) {
  const auto& sensors = scene.cell().sensors;
  for (const collision::SensorRuleViolation& r : collision::checkSensorRules(sensors, evaluation)) {
    const kinematics::Sensor& sensor = sensors[r.sensor];
    Violation v;
    v.kind = Violation::Kind::kSensor;
    v.what = sensor.name;
    v.t = v.t_start = r.span.t_start;
    v.t_end = r.span.t_end;
    v.note = "expect " + collision::describeExpectation(sensor.expect) + ": " +
             (r.fired ? "fires" : "does not fire");
    if (!r.span.bodies.empty()) {
      std::vector<std::string> names;
      for (int b : r.span.bodies) names.push_back(scene.bodies()[static_cast<std::size_t>(b)].name);
      v.note += fmt::format(" ({})", fmt::join(names, ", "));
    }
    out.push_back(std::move(v));
  }
}

// Orders the violations, and fills in the verdict and the distances.
void concludeReport(const collision::Scene& scene,
                    const Gathered& gathered,
                    bool collided,
                    ValidationReport& report) {
  std::stable_sort(report.violations.begin(), report.violations.end(),
                   [](const Violation& a, const Violation& b) {
                     return std::tie(a.t_start, a.kind, a.what) <
                            std::tie(b.t_start, b.kind, b.what);
                   });
  for (const Violation& v : report.violations) {
    if (v.kind == Violation::Kind::kCollision) {
      report.first_collision = v;
      break;
    }
  }
  report.valid = report.violations.empty();
  const Closest& closest = gathered.closest;
  const auto fill = [&](int pair, double& distance, std::string& name, double& t) {
    distance = kInf;
    if (pair < 0) return;
    distance = closest.distance[static_cast<std::size_t>(pair)];
    name = pairName(scene, pair);
    t = closest.t[static_cast<std::size_t>(pair)];
  };
  const auto self = [&](std::size_t p) { return scene.armPair(p); };
  fill(closest.least([](std::size_t) { return true; }), report.min_distance,
       report.min_distance_pair, report.min_distance_t);
  fill(closest.least([&](std::size_t p) { return !self(p); }), report.min_cell_distance,
       report.min_cell_distance_pair, report.min_cell_distance_t);
  fill(closest.least(self), report.min_self_distance, report.min_self_distance_pair,
       report.min_self_distance_t);
  if (scene.pairs().empty()) {
    report.proven_clearance = kInf;
  } else {
    report.proven_clearance = collided ? 0.0 : std::max(0.0, gathered.proven);
  }
}

}  // namespace

ValidationReport validateTrajectory(const collision::Scene& scene,
                                    const kinematics::Trajectory& trajectory,
                                    const ValidationSettings& settings) {
  const auto start = std::chrono::steady_clock::now();
  checkInputs(trajectory, settings);
  const kinematics::CellModel& cell = scene.cell();
  const kinematics::Trajectory dense = densify(trajectory, settings.sample_dt);
  const auto& samples = dense.samples;

  ValidationReport report;
  report.samples = samples.size();
  checkLimitsAndSpeeds(cell, trajectory, samples,
                       settings.table_omega_max.value_or(cell.table.max_speed),
                       settings.table_alpha_max.value_or(cell.table.max_accel),
                       settings.speed_tolerance, report.violations);

  const ClearanceSweep sweep = sweepClearance(scene, samples, settings.collision_resolution);
  Gathered gathered = gatherInTimeOrder(sweep, scene.pairs().size());
  report.poses_checked = gathered.poses_checked;
  const bool collided =
      emitCollisions(scene, gathered.spans, settings.collision_resolution, report.violations);
  if (!cell.sensors.empty()) {
    report.sensors = collision::evaluateSensors(scene, samples);
    appendSensorViolations(scene, *report.sensors, report.violations);
  }
  concludeReport(scene, gathered, collided, report);
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace scanplan::planner
