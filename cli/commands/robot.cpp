#include <cstdio>

#include <fmt/format.h>

#include "cli/commands/commands.h"
#include "cli/config/robot_urdf.h"
#include "cli/io/output.h"

namespace scanplan::cli {
namespace {

// Mesh paths as the robot file will hold them: relative to its folder (the pair moves together).
void relativeMeshPaths(RobotSpec& spec, const std::filesystem::path& out_file) {
  const std::filesystem::path dir = std::filesystem::absolute(out_file).parent_path();
  for (LinkSpec& link : spec.links) {
    for (ShapeSpec& shape : link.shapes) {
      if (shape.type != "mesh") continue;
      std::error_code ec;
      const std::filesystem::path rel = std::filesystem::relative(shape.file.resolved, dir, ec);
      shape.file.as_written = ec || rel.empty() ? shape.file.resolved.string() : rel.string();
    }
  }
}

std::string importHeader(const RobotImportOptions& options, const UrdfRobot& robot) {
  const UrdfRobotSource& s = options.source;
  std::string text = fmt::format(
      "{}: imported by `scanplan robot import` from {} (chain {} → {}).\n"
      "DH rows and OPW parameters {} the URDF's joints; limits and speeds are its <limit>s.\n"
      "Bodies and the URDF links whose <collision> geometry they hold, in the body's DH frame:\n",
      robot.spec.name, std::filesystem::absolute(s.urdf).lexically_normal().string(), s.base_link,
      s.tip_link,
      s.opw_parameters.empty() ? "derived from"
                               : "(OPW from " + s.opw_parameters.string() + ") checked against");
  for (std::size_t i = 0; i < robot.body_links.size(); ++i) {
    text +=
        fmt::format("  {}: {}\n", robot.spec.links[i].name, fmt::join(robot.body_links[i], ", "));
  }
  return text;
}

}  // namespace

ExitCode runRobotImport(const RobotImportOptions& options) {
  UrdfRobot robot = importUrdf(options.source);
  // The same checks as a job's robot: OPW against DH over the workspace.
  buildRobotModel(robot.spec, options.source.urdf.string());
  relativeMeshPaths(robot.spec, options.out_file);
  writeFileAtomically(options.out_file, robotToYaml(robot.spec, importHeader(options, robot)));
  std::size_t shapes = 0;
  for (const LinkSpec& link : robot.spec.links) shapes += link.shapes.size();
  const OpwSpec& o = robot.spec.opw;
  std::printf(
      "robot      %s: 6 revolute joints %s → %s\n"
      "opw        a1 %g, a2 %g, b %g, c1 %g, c2 %g, c3 %g, c4 %g mm; offsets [%s] deg; signs "
      "[%s]%s\n"
      "links      %zu collision shapes on 7 bodies (base, link1 … link6)\n"
      "wrote      %s\n",
      robot.spec.name.c_str(), options.source.base_link.c_str(), options.source.tip_link.c_str(),
      o.a1_mm, o.a2_mm, o.b_mm, o.c1_mm, o.c2_mm, o.c3_mm, o.c4_mm,
      fmt::format("{}", fmt::join(o.offsets_deg, ", ")).c_str(),
      fmt::format("{}", fmt::join(o.signs, ", ")).c_str(),
      options.source.opw_parameters.empty()
          ? " (derived from the chain)"
          : " (from the opw_parameters file, checked against the chain)",
      shapes, options.out_file.string().c_str());
  return ExitCode::kOk;
}

}  // namespace scanplan::cli
