#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include <scanplan/collision/scene.h>
#include <scanplan/collision/sensors.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/planner/constraints.h>
#include "cli/commands/commands.h"
#include "cli/io/json.h"
#include "cli/io/output.h"
#include "cli/report/sensor_report.h"

namespace scanplan::cli {
namespace {

std::vector<double> mmVector(const Eigen::Vector3d& p) {
  return {toMm(p.x()), toMm(p.y()), toMm(p.z())};
}

// The scan-path sample nearest --time, solved on the job's branch (or the best of all), with
// the words that say where the pose came from; nullopt (after a message) when it is out of
// reach.
std::optional<std::pair<kinematics::JointVector, std::string>> poseAtTime(
    const config::JobSpec& job,
    const collision::Scene& scene,
    planner::PoseEvaluator& evaluator,
    const CheckOptions& options,
    double theta) {
  const auto& robot = scene.cell().robot;
  kinematics::JointVector q = kinematics::JointVector::Zero();
  const kinematics::ScanPath path = generateScanPath(job, scene.cell()).path;
  if (!(options.time_s >= 0.0) || options.time_s > path.duration() + 0.5 * path.dt) {
    throw InputError(fmt::format("--time: {} s: expected a time within the scan path, 0 … {:.2f} s",
                                 options.time_s, path.duration()));
  }
  const auto k = std::min(path.samples.size() - 1,
                          static_cast<std::size_t>(std::llround(options.time_s / path.dt)));
  const auto& sample = path.samples[k];
  const auto solutions = robot.ik(scene.cell().flangeTarget(theta, sample.X_PS));
  const std::optional<kinematics::IkBranch> wanted =
      job.map.branch == "auto" ? std::nullopt : config::parseBranch(job.map.branch);
  double best = -1.0;
  for (const auto& solution : solutions) {
    if (wanted && !(solution.branch == *wanted)) continue;
    const double f = evaluator.score(theta, solution.q).total;
    if (f > best) {
      best = f;
      q = solution.q;
    }
  }
  if (best < 0.0) {
    std::fputs(fmt::format("table {} deg, t = {:.2f} s: the scan pose is out of reach{}\n",
                           options.table_deg, sample.t, wanted ? " on " + wanted->words() : "")
                   .c_str(),
               stdout);
    return std::nullopt;
  }
  return std::pair{q, fmt::format(" (scan sample t = {:.2f} s{})", sample.t,
                                  sample.scanning ? "" : ", not scanning")};
}

std::string pairName(const collision::Scene& scene, const collision::PairInfo& p) {
  const auto& bodies = scene.bodies();
  return bodies[static_cast<std::size_t>(p.a)].name + " - " +
         bodies[static_cast<std::size_t>(p.b)].name;
}

Json pairsJson(const collision::Scene& scene, const planner::PoseScore& s) {
  const auto& bodies = scene.bodies();
  Json pairs = Json::array();
  for (std::size_t i = 0; i < scene.pairs().size(); ++i) {
    const auto& p = scene.pairs()[i];
    const auto& c = s.clearance.pairs[i];
    Json pair = {{"a", bodies[static_cast<std::size_t>(p.a)].name},
                 {"b", bodies[static_cast<std::size_t>(p.b)].name},
                 {"distance_mm", toMm(c.distance)},
                 {"beyond_d_high", c.beyond_bound},
                 {"penetrating", c.penetrating},
                 {"d_low_mm", toMm(p.thresholds.d_low)},
                 {"d_high_mm", toMm(p.thresholds.d_high)},
                 {"gamma", p.thresholds.gamma},
                 {"factor", c.factor}};
    if (!c.beyond_bound) {
      pair["witness_a_mm"] = mmVector(c.p_a);
      pair["witness_b_mm"] = mmVector(c.p_b);
    }
    pairs.push_back(std::move(pair));
  }
  return pairs;
}

// `check --json`: the pose, every factor and every pair.
std::string checkJson(const config::JobSpec& job,
                      const collision::Scene& scene,
                      const CheckOptions& options,
                      const kinematics::JointVector& q,
                      const planner::PoseScore& s) {
  const auto& robot = scene.cell().robot;
  std::vector<double> joints;
  for (int i = 0; i < 6; ++i) joints.push_back(toDeg(q(i)));
  Json json;
  json["job"] = job.name;
  json["table_deg"] = options.table_deg;
  json["joints_deg"] = joints;
  json["branch"] = robot.branchOf(q).words();
  json["joint_factors"] = std::vector<double>(s.joint.begin(), s.joint.end());
  json["singularity"] = {{"wrist", s.singularity.wrist},
                         {"wrist_factor", s.wrist},
                         {"elbow", s.singularity.elbow},
                         {"elbow_factor", s.elbow},
                         {"shoulder_mm", toMm(s.singularity.shoulder)},
                         {"shoulder_factor", s.shoulder},
                         {"manipulability", s.singularity.manipulability}};
  json["pairs"] = pairsJson(scene, s);
  json["clearance_factor"] = s.clearance.factor;
  json["collision"] = s.clearance.collision;
  json["f"] = s.total;
  json["limiting"] = s.limiting;
  if (!scene.cell().sensors.empty()) {
    json["sensors"] = sensorReadingsJson(
        scene, collision::SensorEvaluator(scene).evaluate(deg(options.table_deg), q));
  }
  return jsonDocument(json);
}

// `check`: the pose, the factors and a table of the pairs.
std::string checkText(const collision::Scene& scene,
                      const CheckOptions& options,
                      const kinematics::JointVector& q,
                      const std::string& origin,
                      const planner::PoseScore& s) {
  const auto& robot = scene.cell().robot;
  std::vector<double> joints;
  for (int i = 0; i < 6; ++i) joints.push_back(toDeg(q(i)));
  std::string t;
  t += fmt::format("pose         table {} deg, joints {:.3f} deg  [{}{}]{}\n", options.table_deg,
                   fmt::join(joints, ", "), robot.branchOf(q).words(),
                   robot.withinLimits(q) ? "" : ", OUTSIDE the joint limits", origin);
  t += "joint limits";
  for (int j = 0; j < 6; ++j)
    t += fmt::format("  f{}={:.3f}", j + 1, s.joint[static_cast<std::size_t>(j)]);
  t += "   (Eq. 7)\n";
  t += fmt::format(
      "singularity  wrist |sin q5| {:.3f} -> f {:.3f}   elbow {:.3f} -> f {:.3f}   shoulder "
      "{:.1f} mm -> f {:.3f}   (manipulability {:.3f})\n",
      s.singularity.wrist, s.wrist, s.singularity.elbow, s.elbow, toMm(s.singularity.shoulder),
      s.shoulder, s.singularity.manipulability);
  t += fmt::format("clearance    {} pairs (Eq. 8); distances beyond d_high are shown as >\n",
                   scene.pairs().size());
  t += fmt::format("  {:<24} {:>11} {:>7} {:>7} {:>7}\n", "pair", "distance_mm", "d_low", "d_high",
                   "f_C");
  for (std::size_t i = 0; i < scene.pairs().size(); ++i) {
    const auto& p = scene.pairs()[i];
    const auto& c = s.clearance.pairs[i];
    const std::string d = c.penetrating    ? "CONTACT"
                          : c.beyond_bound ? fmt::format("> {:.1f}", toMm(c.distance))
                                           : fmt::format("{:.3f}", toMm(c.distance));
    t += fmt::format("  {:<24} {:>11} {:>7.1f} {:>7.1f} {:>7.3f}\n", pairName(scene, p), d,
                     toMm(p.thresholds.d_low), toMm(p.thresholds.d_high), c.factor);
  }
  t += fmt::format("collision    {}\n", s.clearance.collision ? "YES" : "no");
  t += fmt::format("f            {:.4f}   limiting: {}\n", s.total, s.limiting);
  if (s.clearance.limiting_pair >= 0) {
    const auto& c = s.clearance.pairs[static_cast<std::size_t>(s.clearance.limiting_pair)];
    const auto a = mmVector(c.p_a), b = mmVector(c.p_b);
    t += fmt::format(
        "closest      {}: {:.3f} mm between ({:.1f}, {:.1f}, {:.1f}) and ({:.1f}, {:.1f}, "
        "{:.1f}) mm (world)\n",
        pairName(scene, scene.pairs()[static_cast<std::size_t>(s.clearance.limiting_pair)]),
        toMm(c.distance), a[0], a[1], a[2], b[0], b[1], b[2]);
  }
  if (!scene.cell().sensors.empty()) {
    t += sensorReadingsText(scene,
                            collision::SensorEvaluator(scene).evaluate(deg(options.table_deg), q));
  }
  return t;
}

}  // namespace

ExitCode runCheck(const CheckOptions& options) {
  if (!std::isfinite(options.table_deg) || std::abs(options.table_deg) > 1e9) {
    throw InputError(fmt::format(
        "--table: {}: expected a finite table angle in degrees (within ±1e9)", options.table_deg));
  }
  const config::JobSpec job = config::loadJob(options.job_file, options.overrides);
  const collision::Scene scene(config::buildCell(job), config::clearanceConfig(job));
  const double theta = deg(options.table_deg);
  planner::PoseEvaluator evaluator(scene, config::constraintSettings(job));
  kinematics::JointVector q = kinematics::JointVector::Zero();
  std::string origin;
  if (!options.joints_deg.empty()) {
    const auto values =
        parseNumberList(options.joints_deg, 6, "--joints", "6 joint angles in degrees, j1,…,j6");
    for (int i = 0; i < 6; ++i) q(i) = deg(values[static_cast<std::size_t>(i)]);
  } else {
    const auto pose = poseAtTime(job, scene, evaluator, options, theta);
    if (!pose) return ExitCode::kNoPlan;
    std::tie(q, origin) = *pose;
  }
  const planner::PoseScore s = evaluator.score(theta, q);
  std::fputs((options.json ? checkJson(job, scene, options, q, s)
                           : checkText(scene, options, q, origin, s))
                 .c_str(),
             stdout);
  return s.total > 0.0 ? ExitCode::kOk : ExitCode::kNoPlan;
}

}  // namespace scanplan::cli
