#include <cmath>
#include <cstdio>
#include <optional>

#include <fmt/format.h>

#include <scanplan/config/robot_file.h>
#include <scanplan/config/robot_urdf.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/units.h>
#include "cli/commands/commands.h"
#include "cli/io/json.h"
#include "cli/io/output.h"

namespace scanplan::cli {
namespace {

using kinematics::JointVector;

struct LoadedRobot {
  kinematics::RobotModel robot;
  std::optional<Eigen::Isometry3d> X_FS;  ///< from a job, when one was given
};

LoadedRobot loadRobot(const RobotSource& source) {
  if (!source.job_file.empty()) {
    const config::JobSpec job = config::loadJob(source.job_file);
    const kinematics::CellModel cell = config::buildCell(job);
    return {cell.robot, cell.scanner.X_FS};
  }
  return {config::buildRobotModel(config::loadRobotOrUrdf(source.robot_file),
                                  source.robot_file.string()),
          std::nullopt};
}

std::vector<double> toVector(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

std::vector<double> jointsDeg(const JointVector& q) { return toVector(q * kRadToDeg); }

// The pose's members, added to `json`.
void addPose(Json& json, const Eigen::Isometry3d& X) {
  json["position_mm"] = toVector(X.translation() * kMToMm);
  Json rotation = Json::array();
  for (int r = 0; r < 3; ++r) rotation.push_back(toVector(X.linear().row(r).transpose()));
  json["rotation_matrix"] = std::move(rotation);
  json["quaternion_wxyz"] = toVector(quaternionWxyz(X.linear()));
  json["trans_zyz_deg"] = toVector(kinematics::zyzFromRotation(X.linear()) * kRadToDeg);
}

std::string poseText(const std::string& title, const Eigen::Isometry3d& X) {
  const Eigen::Vector3d p = X.translation() * kMToMm;
  const Eigen::Vector3d zyz = kinematics::zyzFromRotation(X.linear()) * kRadToDeg;
  const Eigen::Vector4d q = quaternionWxyz(X.linear());
  const Eigen::Matrix3d& R = X.linear();
  std::string s = title + "\n";
  s += fmt::format("  position_mm      {:10.4f} {:10.4f} {:10.4f}\n", p.x(), p.y(), p.z());
  s += fmt::format("  trans_zyz_deg    {:10.4f} {:10.4f} {:10.4f}   (V+ TRANS y, p, r)\n", zyz.x(),
                   zyz.y(), zyz.z());
  s += fmt::format("  quaternion_wxyz  {:10.7f} {:10.7f} {:10.7f} {:10.7f}\n", q(0), q(1), q(2),
                   q(3));
  for (int r = 0; r < 3; ++r) {
    s += fmt::format("  {:16} {:10.7f} {:10.7f} {:10.7f}\n", r == 0 ? "rotation_matrix" : "",
                     R(r, 0), R(r, 1), R(r, 2));
  }
  return s;
}

}  // namespace

std::vector<double> parseNumberList(const std::string& text,
                                    std::size_t count,
                                    const std::string& option,
                                    const std::string& what) {
  std::vector<double> values;
  // Split keeping empty fields, so "1,2,3," and "1,,3" are errors rather than shorter lists.
  std::vector<std::string> items;
  for (std::size_t start = 0;;) {
    const std::size_t comma = text.find(',', start);
    items.push_back(
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  for (const std::string& item : items) {
    std::size_t used = 0;
    double v = std::nan("");
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    while (used < item.size() && std::isspace(static_cast<unsigned char>(item[used]))) ++used;
    // ±1e9, the bound of every number in the job files (docs/limits.md): 1e300 mm or degrees
    // is no pose, and its products overflow.
    if (used == 0 || used != item.size() || !std::isfinite(v) || std::abs(v) > 1e9) {
      throw InputError(
          fmt::format("{}: '{}' in '{}' is not a finite number within ±1e9: expected {}", option,
                      item, text, what));
    }
    values.push_back(v);
  }
  if (values.size() != count) {
    throw InputError(
        fmt::format("{}: '{}' has {} numbers: expected {}", option, text, values.size(), what));
  }
  return values;
}

ExitCode runFk(const FkOptions& options) {
  const LoadedRobot loaded = loadRobot(options.source);
  const auto& robot = loaded.robot;
  const auto values =
      parseNumberList(options.joints_deg, 6, "--joints", "6 joint angles in degrees, j1,…,j6");
  JointVector q;
  for (int i = 0; i < 6; ++i) q(i) = deg(values[static_cast<std::size_t>(i)]);
  const Eigen::Isometry3d X_BF = robot.fk(q);
  const bool in_limits = robot.withinLimits(q);
  const auto branch = robot.branchOf(q);
  const auto sing = robot.singularity(q);

  if (options.json) {
    Json json;
    json["robot"] = robot.name();
    json["joints_deg"] = values;
    addPose(json, X_BF);
    if (loaded.X_FS) {
      Json sensor = Json::object();
      addPose(sensor, X_BF * *loaded.X_FS);
      json["sensor"] = std::move(sensor);
    }
    json["within_limits"] = in_limits;
    json["branch"] = branch.words();
    json["singularity"] = {{"wrist", sing.wrist},
                           {"elbow", sing.elbow},
                           {"shoulder_mm", toMm(sing.shoulder)},
                           {"manipulability", sing.manipulability}};
    std::fputs(jsonDocument(json).c_str(), stdout);
    return ExitCode::kOk;
  }
  std::string text = fmt::format("{}, joints (deg): {}\n", robot.name(), fmt::join(values, ", "));
  text += poseText("flange X_BF (robot base frame)", X_BF);
  if (loaded.X_FS) text += poseText("sensor X_BS (robot base frame)", X_BF * *loaded.X_FS);
  text += fmt::format("within joint limits: {}   branch: {}\n", in_limits ? "yes" : "NO",
                      branch.words());
  text += fmt::format(
      "singularity: wrist |sin q5| {:.4f}, elbow {:.4f}, shoulder {:.1f} mm, manipulability "
      "{:.4f}\n",
      sing.wrist, sing.elbow, toMm(sing.shoulder), sing.manipulability);
  std::fputs(text.c_str(), stdout);
  return ExitCode::kOk;
}

ExitCode runIk(const IkOptions& options) {
  const LoadedRobot loaded = loadRobot(options.source);
  const auto& robot = loaded.robot;
  Eigen::Isometry3d X_BF = Eigen::Isometry3d::Identity();
  if (!options.trans.empty()) {
    const auto v = parseNumberList(options.trans, 6, "--trans",
                                   "x,y,z in mm then y,p,r in degrees (V+ TRANS, ZYZ' Euler)");
    X_BF.translation() = Eigen::Vector3d(v[0], v[1], v[2]) * kMmToM;
    X_BF.linear() = kinematics::rotationFromZyz(Eigen::Vector3d(v[3], v[4], v[5]) * kDegToRad);
  } else {
    const auto v = parseNumberList(options.matrix, 16, "--matrix",
                                   "16 numbers, a 4x4 pose row-major, translation in mm");
    Eigen::Matrix4d M;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) M(r, c) = v[static_cast<std::size_t>(4 * r + c)];
    const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
    const double ortho = (R.transpose() * R - Eigen::Matrix3d::Identity()).norm();
    if (ortho > 1e-6 || R.determinant() < 0 ||
        (M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-9) {
      throw InputError(fmt::format(
          "--matrix: not a rigid transform (rotation orthonormality error {:.2e}, det {:.6f}, "
          "last row [{}]): expected a rotation matrix with det +1 and last row 0,0,0,1",
          ortho, R.determinant(),
          fmt::join(std::vector<double>(M.row(3).data(), M.row(3).data() + 4), ",")));
    }
    // Re-orthonormalise the printed digits so IK sees an exact rotation.
    X_BF.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
    X_BF.translation() = M.topRightCorner<3, 1>() * kMmToM;
  }
  kinematics::IkRequest request;
  request.within_limits_only = options.within_limits_only;
  const auto solutions = robot.ik(X_BF, request);

  if (options.json) {
    Json json;
    json["robot"] = robot.name();
    Json target = Json::object();
    addPose(target, X_BF);
    json["target"] = std::move(target);
    json["reachable"] = !solutions.empty();
    Json all = Json::array();
    for (const auto& s : solutions) {
      all.push_back({{"branch", s.branch.words()},
                     {"joints_deg", jointsDeg(s.q)},
                     {"within_limits", s.within_limits}});
    }
    json["solutions"] = std::move(all);
    std::fputs(jsonDocument(json).c_str(), stdout);
  } else if (solutions.empty()) {
    std::fputs(fmt::format("{}: no solution: the pose is out of reach{}\n", robot.name(),
                           options.within_limits_only ? " or outside the joint limits" : "")
                   .c_str(),
               stdout);
  } else {
    std::string text = poseText(robot.name() + ": flange target X_BF", X_BF);
    text += fmt::format("{} solution(s), joints in degrees:\n", solutions.size());
    text += fmt::format("  #  {:<21}{:>9}{:>9}{:>9}{:>9}{:>9}{:>9}  limits\n", "branch", "j1", "j2",
                        "j3", "j4", "j5", "j6");
    for (std::size_t i = 0; i < solutions.size(); ++i) {
      const auto q = jointsDeg(solutions[i].q);
      text += fmt::format("{:3}  {:<21}", i + 1, solutions[i].branch.words());
      for (double v : q) text += fmt::format("{:9.3f}", v);
      text += solutions[i].within_limits ? "  ok\n" : "  OUTSIDE\n";
    }
    std::fputs(text.c_str(), stdout);
  }
  return solutions.empty() ? ExitCode::kNoPlan : ExitCode::kOk;
}

}  // namespace scanplan::cli
