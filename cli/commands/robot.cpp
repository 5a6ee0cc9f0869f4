#include <cstdio>

#include <fmt/format.h>

#include <scanplan/collision/map_links.h>
#include <scanplan/collision/self_collision.h>
#include <scanplan/config/job.h>
#include <scanplan/config/robot_urdf.h>
#include <scanplan/kinematics/units.h>
#include "cli/commands/commands.h"
#include "cli/io/json.h"
#include "cli/io/output.h"
#include "cli/report/plan_summary.h"

namespace scanplan::cli {
namespace {

// Mesh paths as the robot file will hold them: relative to its folder (the pair moves together).
void relativeMeshPaths(config::RobotSpec& spec, const std::filesystem::path& out_file) {
  const std::filesystem::path dir = std::filesystem::absolute(out_file).parent_path();
  for (config::LinkSpec& link : spec.links) {
    for (config::ShapeSpec& shape : link.shapes) {
      if (shape.type != "mesh") continue;
      std::error_code ec;
      const std::filesystem::path rel = std::filesystem::relative(shape.file.resolved, dir, ec);
      shape.file.as_written = ec || rel.empty() ? shape.file.resolved.string() : rel.string();
    }
  }
}

std::string importHeader(const RobotImportOptions& options, const config::UrdfRobot& robot) {
  const config::UrdfRobotSource& s = options.source;
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

// What to do with a pair, from how often it collided (MoveIt setup assistant's classes).
std::string verdict(const collision::SelfPairSurvey& p, std::size_t samples) {
  if (p.adjacent) return "adjacent: not checked";
  if (p.allowed) return "allowed by the robot file";
  if (p.colliding == samples) return "always: they overlap by design, allow";
  if (20 * p.colliding >= 19 * samples) return "nearly always (>= 95%): allow";
  if (p.colliding == 0) return "never";
  return "sometimes: keep checking";
}

bool suggested(const collision::SelfPairSurvey& p, std::size_t samples) {
  return !p.adjacent && !p.allowed && samples > 0 && 20 * p.colliding >= 19 * samples;
}

Json surveyJson(const std::string& name,
                const RobotCheckOptions& o,
                const collision::SelfSurvey& s) {
  Json json;
  json["robot"] = name;
  json["samples"] = s.samples;
  json["seed"] = o.seed;
  Json pairs = Json::array(), allow = Json::array();
  for (const collision::SelfPairSurvey& p : s.pairs) {
    Json pair;
    pair["a"] = p.a;
    pair["b"] = p.b;
    pair["adjacent"] = p.adjacent;
    pair["allowed"] = p.allowed;
    pair["colliding"] = p.colliding;
    pair["share"] = static_cast<double>(p.colliding) / static_cast<double>(s.samples);
    pair["min_distance_mm"] =  // null: never within the survey's reach
        p.min_distance >= collision::kSurveyReach ? Json(nullptr) : Json(toMm(p.min_distance));
    pair["verdict"] = verdict(p, s.samples);
    pairs.push_back(std::move(pair));
    if (suggested(p, s.samples)) allow.push_back(Json::array({p.a, p.b}));
  }
  json["pairs"] = std::move(pairs);
  json["suggested_allowed_collisions"] = std::move(allow);
  return json;
}

std::string surveyText(const std::string& name,
                       const RobotCheckOptions& o,
                       const collision::SelfSurvey& s) {
  std::string text = fmt::format(
      "robot      {}: {} random configurations within the joint limits (seed {})\n\n"
      "  {:<22} {:>9} {:>7} {:>12}   {}\n",
      name, s.samples, o.seed, "pair", "colliding", "share", "min dist mm", "verdict");
  std::string allow;
  for (const collision::SelfPairSurvey& p : s.pairs) {
    const double share = 100.0 * static_cast<double>(p.colliding) / static_cast<double>(s.samples);
    text += fmt::format(
        "  {:<22} {:>9} {:>6.1f}% {:>12}   {}\n", p.a + " - " + p.b, p.colliding, share,
        p.min_distance >= collision::kSurveyReach ? std::string(">= 100")
                                                  : fmt::format("{:.1f}", toMm(p.min_distance)),
        verdict(p, s.samples));
    if (suggested(p, s.samples)) {
      allow += fmt::format("  - [{}, {}]   # collide in {:.1f}% of the samples\n", p.a, p.b, share);
    }
  }
  if (allow.empty())
    return text + "\nno pair to allow: every checked pair is apart in some configurations\n";
  return text +
         "\nsuggested, for the robot file (a job can check a pair again with "
         "constraints.clearance.pairs: [{a, b, include: true}]):\nallowed_collisions:\n" +
         allow;
}

// What the maps of a job with this robot file would measure for its mesh links, under the
// job's defaults (constraints.clearance): the pieces are fitted into, or read from, the cache
// beside the file, where the job finds them.
std::vector<collision::MapHull> mapLinks(const kinematics::RobotModel& robot,
                                         const std::filesystem::path& robot_file) {
  config::JobSpec job;
  job.robot_file.resolved = std::filesystem::absolute(robot_file);
  Progress progress("fitting link stand-ins");
  return collision::robotMapLinks(robot, config::clearanceConfig(job), std::ref(progress));
}

std::vector<std::string> linkNames(const kinematics::RobotModel& robot) {
  std::vector<std::string> names;
  for (std::size_t k = 0; k < robot.definition().links.size(); ++k) {
    const std::string& name = robot.definition().links[k].name;
    names.push_back(!name.empty() ? name : k == 0 ? std::string("base") : fmt::format("link{}", k));
  }
  return names;
}

Json mapLinksJson(const std::vector<std::string>& names,
                  const std::vector<collision::MapHull>& hulls) {
  Json out = Json::array();
  for (const collision::MapHull& h : hulls) {
    Json link;
    link["link"] = names[static_cast<std::size_t>(h.body)];
    link["mesh_triangles"] = h.mesh_triangles;
    link["hull_vertices"] = h.hull_vertices;
    link["hull_margin_mm"] = toMm(h.hull_margin);
    link["pieces"] = h.pieces;
    link["piece_vertices"] = h.piece_vertices;
    link["pieces_fit"] = h.pieces_fit;
    link["pieces_from_cache"] = h.from_cache;
    link["fit_seconds"] = h.fit_seconds;
    link["maps_measure"] = !h.used        ? "mesh"
                           : h.cylinder   ? "cylinder"
                           : h.pieces > 0 ? "pieces"
                                          : "hull";
    link["margin_mm"] = toMm(h.margin);
    out.push_back(std::move(link));
  }
  return out;
}

}  // namespace

ExitCode runRobotCheck(const RobotCheckOptions& options) {
  const config::RobotSpec spec = config::loadRobotOrUrdf(options.robot_file);
  const kinematics::RobotModel robot = config::buildRobotModel(spec, options.robot_file.string());
  const collision::SelfSurvey survey =
      collision::surveySelfCollisions(robot, options.samples, options.seed);
  const std::vector<collision::MapHull> links = mapLinks(robot, options.robot_file);
  std::string out;
  if (options.json) {
    Json json = surveyJson(spec.name, options, survey);
    json["link_meshes"] = mapLinksJson(linkNames(robot), links);
    out = jsonDocument(json);
  } else {
    out = surveyText(spec.name, options, survey);
    if (!links.empty()) out += "\n" + linkMeshLines(linkNames(robot), links);
  }
  std::fputs(out.c_str(), stdout);
  return ExitCode::kOk;
}

ExitCode runRobotImport(const RobotImportOptions& options) {
  config::UrdfRobot robot = config::importUrdf(options.source);
  std::vector<std::filesystem::path> inputs{options.source.urdf};
  for (const config::LinkSpec& link : robot.spec.links) {
    for (const config::ShapeSpec& shape : link.shapes) {
      if (!shape.file.resolved.empty()) inputs.push_back(shape.file.resolved);
    }
  }
  checkOutputApartFromInputs(options.out_file, inputs);
  // The same checks as a job's robot: OPW against DH over the workspace.
  const kinematics::RobotModel model = buildRobotModel(robot.spec, options.source.urdf.string());
  relativeMeshPaths(robot.spec, options.out_file);
  writeFileAtomically(options.out_file,
                      config::robotToYaml(robot.spec, importHeader(options, robot)));
  const std::string links = linkMeshLines(linkNames(model), mapLinks(model, options.out_file));
  std::size_t shapes = 0;
  for (const config::LinkSpec& link : robot.spec.links) shapes += link.shapes.size();
  const config::OpwSpec& o = robot.spec.opw;
  std::printf(
      "robot      %s: 6 revolute joints %s → %s\n"
      "opw        a1 %g, a2 %g, b %g, c1 %g, c2 %g, c3 %g, c4 %g mm; offsets [%s] deg; signs "
      "[%s]%s\n"
      "links      %zu collision shapes on 7 bodies (base, link1 … link6)\n"
      "%s"
      "wrote      %s\n",
      robot.spec.name.c_str(), options.source.base_link.c_str(), options.source.tip_link.c_str(),
      o.a1_mm, o.a2_mm, o.b_mm, o.c1_mm, o.c2_mm, o.c3_mm, o.c4_mm,
      fmt::format("{}", fmt::join(o.offsets_deg, ", ")).c_str(),
      fmt::format("{}", fmt::join(o.signs, ", ")).c_str(),
      options.source.opw_parameters.empty()
          ? " (derived from the chain)"
          : " (from the opw_parameters file, checked against the chain)",
      shapes, links.c_str(), options.out_file.string().c_str());
  return ExitCode::kOk;
}

}  // namespace scanplan::cli
