// The cases of what scanplan must never lose, never accept and never start blind: outputs that
// would replace an input, features of programs and file formats it does not model, work and
// memory it must estimate first, and errors that must name the real cause.
// tests/robustness/README.md has the rules.
#include <stdexcept>
#include <string>
#include <tuple>

#include "tests/robustness/builders.h"
#include "tests/robustness/cases.h"

namespace scanplan::robustness {
namespace {

// `text` with the first `from` replaced by `to`; a missing `from` is a broken case, not a pass.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::runtime_error("case edit: '" + from + "' not found");
  return text.replace(at, from.size(), to);
}

// `text` with `line` inserted before the n-th (1-based) line starting with `marker`.
std::string insertedBefore(std::string text,
                           const std::string& marker,
                           int n,
                           const std::string& line) {
  std::size_t at = 0;
  for (int seen = 0;; at += 1) {
    at = text.find(marker, at);
    if (at == std::string::npos) throw std::runtime_error("case edit: '" + marker + "' not found");
    if ((at == 0 || text[at - 1] == '\n') && ++seen == n) break;
  }
  return text.insert(at, line + "\n");
}

// The V+ text with the SPEED line before the n-th MOVE replaced by `line` (so that the move
// runs at a SPEED ALWAYS set there, with no speed of its own).
std::string speedBefore(std::string text, int n, const std::string& line) {
  std::size_t move = 0;
  for (int seen = 0; seen < n; ++seen) {
    move = text.find("\n    MOVE", move + 1);
    if (move == std::string::npos) throw std::runtime_error("case edit: MOVE not found");
  }
  const auto speed = text.rfind("\n    SPEED ", move);
  if (speed == std::string::npos) throw std::runtime_error("case edit: SPEED not found");
  const auto end = text.find('\n', speed + 1);
  return text.replace(speed + 1, end - speed - 1, line);
}

InputFile edit(const std::string& name,
               const std::string& source,
               std::function<std::string(std::string)> change) {
  return transformed(name, source, std::move(change));
}

// ---------------------------------------------------------------------------------------------
// Never lose a user's file: an OUT that is, holds or lies inside an input is refused, naming the
// input, and the input stays as it was.

Case clash(const std::string& name,
           std::vector<std::string> args,
           std::vector<InputFile> files,
           const std::string& input) {
  return Case{.name = name,
              .group = "users' files",
              .args = std::move(args),
              .files = std::move(files),
              .names = {input},
              .kept = {input}};
}

std::vector<Case> usersFileCases() {
  std::vector<Case> cases;
  for (const std::string command : {"plan", "path", "map"}) {
    cases.push_back(clash("out_is_the_job_folder_" + command,
                          {command, "data/job.yaml", "-o", "data"}, {jobWith("data/job.yaml", {})},
                          "data/job.yaml"));
    cases.push_back(clash("out_is_the_job_file_" + command, {command, "job.yaml", "-o", "job.yaml"},
                          {jobWith("job.yaml", {})}, "job.yaml"));
  }
  cases.push_back(clash("out_holds_the_job_two_levels_up", {"plan", "a/b/job.yaml", "-o", "a"},
                        {jobWith("a/b/job.yaml", {})}, "a/b/job.yaml"));
  cases.push_back(
      clash("out_is_the_mesh_folder", {"plan", "job.yaml", "-o", "parts"},
            {copyOf("parts/m.stl", kStl), jobWith("job.yaml", {{"part.mesh", "parts/m.stl"}})},
            "parts/m.stl"));
  cases.push_back(
      clash("out_is_the_robot_folder", {"path", "job.yaml", "-o", "robots"},
            {copyOf("robots/r.yaml", kRobot), jobWith("job.yaml", {{"robot", "robots/r.yaml"}})},
            "robots/r.yaml"));
  for (const std::string command : {"validate", "simulate", "export"}) {
    cases.push_back(clash("out_is_the_trajectory_folder_" + command,
                          {command, kLight, "-t", "run/trajectory.csv", "-o", "run"},
                          {copyOf("run/trajectory.csv", kTrajectory)}, "run/trajectory.csv"));
    cases.push_back(clash("out_is_the_job_folder_" + command,
                          {command, "data/job.yaml", "-t", kTrajectory, "-o", "data"},
                          {jobWith("data/job.yaml", {})}, "data/job.yaml"));
  }
  for (const std::string command : {"path", "map"}) {
    cases.push_back(
        clash("out_is_the_mesh_folder_" + command, {command, "job.yaml", "-o", "parts"},
              {copyOf("parts/m.stl", kStl), jobWith("job.yaml", {{"part.mesh", "parts/m.stl"}})},
              "parts/m.stl"));
  }
  for (const std::string command : {"validate", "simulate"}) {
    cases.push_back(
        clash("out_is_the_robot_folder_" + command,
              {command, "job.yaml", "-t", kTrajectory, "-o", "robots"},
              {copyOf("robots/r.yaml", kRobot), jobWith("job.yaml", {{"robot", "robots/r.yaml"}})},
              "robots/r.yaml"));
  }
  cases.push_back(clash(
      "batch_out_is_the_sweep_folder", {"batch", "s/s.yaml", "-o", "s"},
      {jobWith("s/job.yaml", {}), text("s/s.yaml", "jobs: [job.yaml]\nvary: {scan.dt_s: [0.2]}\n")},
      "s/s.yaml"));
  cases.push_back(clash("batch_out_is_the_base_job_folder", {"batch", "s.yaml", "-o", "jobs"},
                        {jobWith("jobs/job.yaml", {}),
                         text("s.yaml", "jobs: [jobs/job.yaml]\nvary: {scan.dt_s: [0.2]}\n")},
                        "jobs/job.yaml"));
  cases.push_back(clash("out_is_the_program_itself", {"export", kLight, "-t", "p.v2", "-o", "p.v2"},
                        {copyOf("p.v2", kProgram)}, "p.v2"));
  cases.push_back(clash("robot_import_onto_its_urdf", {"robot", "import", "k.urdf", "-o", "k.urdf"},
                        {copyOf("k.urdf", "@src/data/robots/urdf/viper_s650.urdf")}, "k.urdf"));
  cases.push_back(clash("out_is_the_case_folder", {"map", "job.yaml", "-o", "."},
                        {jobWith("job.yaml", {})}, "job.yaml"));
  cases.push_back(clash("out_is_a_link_to_the_job_folder", {"plan", "data/job.yaml", "-o", "link"},
                        {jobWith("data/job.yaml", {}), symlinkTo("link", "data")},
                        "data/job.yaml"));
  return cases;
}

// ---------------------------------------------------------------------------------------------
// Never accept what scanplan does not model: statements that change a program's motion or
// timing, format features it would drop, coverage below the scanner's resolution, bodies that
// overlap from the start.

Case program(const std::string& name, const std::string& file, InputFile edited) {
  return Case{.name = name,
              .group = "unmodelled input",
              .args = {"validate", kLight, "-t", file, "-o", "out"},
              .files = {std::move(edited)},
              .names = {file},
              .out = OutState::kAbsent};
}

const std::string kKrl = "@fix/programs/programs/scan.src";
const std::string kRapid = "@fix/programs/programs/scan.mod";
const std::string kUrscript = "@fix/programs/programs/scan.script";

std::vector<Case> programCases() {
  std::vector<Case> cases;
  const auto vplus = [&](const std::string& name, std::function<std::string(std::string)> f) {
    cases.push_back(program("vplus_" + name, "p.v2", edit("p.v2", kProgram, std::move(f))));
  };
  vplus("speed_500_times_slower",
        [](std::string t) { return insertedBefore(t, "    MOVE", 3, "    SPEED 0.01"); });
  vplus("speed_always_low", [](std::string t) { return speedBefore(t, 3, "    SPEED 1 ALWAYS"); });
  vplus("speed_in_mmps",
        [](std::string t) { return insertedBefore(t, "    MOVE", 4, "    SPEED 50 MMPS"); });
  vplus("speed_over_100",
        [](std::string t) { return insertedBefore(t, "    MOVE", 3, "    SPEED 150"); });
  vplus("second_program_after_end", [](std::string t) {
    return t + ".PROGRAM again()\n    MOVE #PPOINT(0, 0, 90, 0, 0, 0)\n.END\n";
  });
  vplus("call_another_program",
        [](std::string t) { return insertedBefore(t, "    MOVE", 5, "    CALL other()"); });
  vplus("duration_always", [](std::string t) {
    return replaced(t, "    DURATION 0.200000\n", "    DURATION 0.200000 ALWAYS\n");
  });
  vplus("speed_zero",
        [](std::string t) { return insertedBefore(t, "    MOVE", 3, "    SPEED 0"); });
  vplus("delay_between_moves",
        [](std::string t) { return insertedBefore(t, "    MOVE", 6, "    DELAY 5"); });
  vplus("wait_for_a_signal",
        [](std::string t) { return insertedBefore(t, "    MOVE", 6, "    WAIT SIG(1001)"); });
  const auto krl = [&](const std::string& name, std::function<std::string(std::string)> f) {
    cases.push_back(program("krl_" + name, "p.src", edit("p.src", kKrl, std::move(f))));
  };
  krl("velocity_half_under_time_block",
      [](std::string t) { return replaced(t, "SCANPLAN_VEL(100, 100)", "SCANPLAN_VEL(50, 50)"); });
  krl("velocity_routine_edited",
      [](std::string t) { return replaced(t, "$VEL_AXIS[AXIS]=ARM_PCT", "$VEL_AXIS[AXIS]=5"); });
  krl("bas_velocity_call",
      [](std::string t) { return insertedBefore(t, "  PTP_SPLINE", 1, "  BAS(#VEL_PTP,20)"); });
  krl("loop_around_the_scan",
      [](std::string t) { return insertedBefore(t, "  PTP_SPLINE", 1, "  LOOP"); });
  krl("text_after_the_routine", [](std::string t) { return t + "DEF EXTRA( )\nEND\n"; });
  krl("wait_five_seconds",
      [](std::string t) { return insertedBefore(t, "  PTP_SPLINE", 1, "  WAIT SEC 5"); });
  krl("program_override_low",
      [](std::string t) { return insertedBefore(t, "  PTP_SPLINE", 1, "  $OV_PRO=10"); });
  krl("axis_velocity_in_main",
      [](std::string t) { return insertedBefore(t, "  PTP_SPLINE", 1, "  $VEL_AXIS[1]=10"); });
  const auto rapid = [&](const std::string& name, std::function<std::string(std::string)> f) {
    cases.push_back(program("rapid_" + name, "p.mod", edit("p.mod", kRapid, std::move(f))));
  };
  rapid("main_calls_scan_twice",
        [](std::string t) { return replaced(t, "    scan;\n", "    scan;\n    scan;\n"); });
  rapid("empty_main", [](std::string t) { return replaced(t, "    scan;\n", ""); });
  rapid("no_main",
        [](std::string t) { return replaced(t, "  PROC main()\n    scan;\n  ENDPROC\n", ""); });
  rapid("move_in_main", [](std::string t) {
    return replaced(t, "    scan;\n",
                    "    scan;\n    MoveAbsJ [[0,0,90,0,0,0],[0,9E9,9E9,9E9,9E9,9E9]]\\NoEOffs, "
                    "v100\\T:=1, fine, tool0;\n");
  });
  rapid("velset_before_the_scan", [](std::string t) {
    return replaced(t, "    scan;\n", "    VelSet 10, 100;\n    scan;\n");
  });
  rapid("a_while_loop", [](std::string t) {
    return replaced(t, "    scan;\n", "    WHILE TRUE DO\n    scan;\n    ENDWHILE\n");
  });
  rapid("wait_time_in_the_scan", [](std::string t) {
    return replaced(t, "  PROC scan()\n", "  PROC scan()\n    WaitTime 5;\n");
  });
  rapid("scan_calls_another_procedure", [](std::string t) {
    return replaced(t, "  PROC scan()\n", "  PROC scan()\n    other;\n");
  });
  const auto ur = [&](const std::string& name, std::function<std::string(std::string)> f) {
    cases.push_back(
        program("urscript_" + name, "p.script", edit("p.script", kUrscript, std::move(f))));
  };
  ur("run_twice", [](std::string t) { return t + "scan()\n"; });
  ur("speed_slider", [](std::string t) {
    return replaced(t, "  a = seg(a,", "  set_speed_slider_fraction(0.1)\n  a = seg(a,");
  });
  ur("sleep_between_rows",
     [](std::string t) { return replaced(t, "  a = seg(a,", "  sleep(5)\n  a = seg(a,"); });
  ur("loop_over_the_rows",
     [](std::string t) { return replaced(t, "  a = seg(a,", "  while True:\n  a = seg(a,"); });
  return cases;
}

Case urdf(const std::string& name, std::function<std::string(std::string)> change) {
  return Case{.name = name,
              .group = "unmodelled input",
              .args = {"robot", "import", "k.urdf", "-o", "k.yaml"},
              .files = {edit("k.urdf", "@src/data/robots/urdf/viper_s650.urdf", std::move(change))},
              .names = {"k.urdf"}};
}

const std::string kStlFacet =
    "  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n      vertex 100 0 0\n"
    "      vertex 0 100 0\n";
std::string stl(const std::string& facets) { return "solid m\n" + facets + "endsolid m\n"; }

Case set(const std::string& name,
         const std::string& group,
         const std::string& command,
         std::vector<std::string> overrides,
         std::vector<std::string> names);

std::vector<Case> formatCases() {
  std::vector<Case> cases;
  cases.push_back(urdf("urdf_mimic_on_the_chain", [](std::string t) {
    return replaced(t, "<parent link=\"link_2\"/><child link=\"link_3\"/>",
                    "<parent link=\"link_2\"/><child link=\"link_3\"/><mimic joint=\"joint_2\"/>");
  }));
  cases.back().names.push_back("mimic");
  cases.push_back(urdf("urdf_closed_loop", [](std::string t) {
    return replaced(t, "</robot>",
                    "  <joint name=\"loop\" type=\"fixed\"><parent link=\"link_5\"/>"
                    "<child link=\"link_2\"/></joint>\n</robot>");
  }));
  cases.push_back(urdf("urdf_package_path_climbs_out", [](std::string t) {
    return replaced(t, "<sphere radius=\"0.08\"/>",
                    "<mesh filename=\"package://pkg/../../../etc/hostname\"/>");
  }));
  cases.push_back(Case{.name = "job_second_yaml_document",
                       .group = "unmodelled input",
                       .args = {"plan", "job.yaml", "-o", "out"},
                       .files = {jobAppended("job.yaml", "---\nscan: {dt_s: 0.05}\n")},
                       .names = {"job.yaml"},
                       .out = OutState::kExisting});
  cases.push_back(
      Case{.name = "robot_second_yaml_document",
           .group = "unmodelled input",
           .args = {"path", "job.yaml", "-o", "out"},
           .files = {edit("r.yaml", kRobot, [](std::string t) { return t + "---\nname: other\n"; }),
                     jobWith("job.yaml", {{"robot", "r.yaml"}})},
           .names = {"r.yaml"},
           .out = OutState::kExisting});
  cases.push_back(Case{.name = "sweep_second_yaml_document",
                       .group = "unmodelled input",
                       .args = {"batch", "s.yaml", "-o", "out"},
                       .files = {edit("s.yaml", "@src/data/sweeps/planners.yaml",
                                      [](std::string t) { return t + "---\nrepeats: 2\n"; })},
                       .names = {"s.yaml"}});
  cases.push_back(meshFileCase("stl_facet_with_four_vertices",
                               text("m.stl", stl(kStlFacet + "      vertex 9 9 9\n    endloop\n"
                                                             "  endfacet\n"))));
  cases.push_back(meshFileCase("stl_facet_with_two_vertices",
                               text("m.stl", stl("  facet normal 0 0 1\n    outer loop\n"
                                                 "      vertex 0 0 0\n      vertex 1 0 0\n"
                                                 "    endloop\n  endfacet\n"))));
  cases.push_back(trajectoryFileCase(
      "csv_duplicate_joint_column",
      edit("t.csv", kTrajectory, [](std::string t) { return replaced(t, "j5_deg", "j4_deg"); })));
  cases.push_back(Case{.name = "job_third_yaml_document",
                       .group = "unmodelled input",
                       .args = {"path", "job.yaml", "-o", "out"},
                       .files = {jobAppended("job.yaml", "---\nname: b\n---\nname: c\n")},
                       .names = {"job.yaml"},
                       .out = OutState::kExisting});
  cases.push_back(trajectoryFileCase(
      "csv_duplicate_table_column",
      edit("t.csv", kTrajectory, [](std::string t) { return replaced(t, ",f,", ",table_deg,"); })));
  cases.push_back(trajectoryFileCase(
      "csv_duplicate_time_column",
      edit("t.csv", kTrajectory, [](std::string t) { return replaced(t, ",f,", ",t_s,"); })));
  cases.push_back(set("set_value_second_yaml_document", "unmodelled input", "path",
                      {"table.axis.xyz_mm=[600, 0, 0]\n---\n[0, 0, 0]"}, {"second YAML document"}));
  cases.push_back(set("set_value_third_yaml_document", "unmodelled input", "plan",
                      {"scan.auto={point_spacing_mm: 1}\n...\n{}\n...\n{}"},
                      {"second YAML document"}));
  // A results row with a key twice (nlohmann keeps the last): refused, naming the key.
  const std::string row =
      "{\"case_id\": \"c0\", \"index\": 0, \"job\": \"j.yaml\", \"params\": {}, "
      "\"repeat\": 0, \"method\": \"ray\", \"status\": \"planned\", \"reason\": \"\", "
      "\"map_reused\": false";
  for (const auto& [name, body, key] :
       {std::tuple<std::string, std::string, std::string>{
            "batch_row_status_twice", row + ", \"status\": \"error\"}\n", "status"},
        {"batch_row_param_twice", replaced(row, "{}", "{\"k\": \"1\", \"k\": \"2\"}") + "}\n", "k"},
        {"batch_row_metric_twice", row + ", \"J_s\": 1, \"J_s\": 2}\n", "J_s"}}) {
    cases.push_back(Case{.name = name,
                         .group = "unmodelled input",
                         .args = {"batch", "report", "r"},
                         .files = {folder("r"), text("r/results.jsonl", body)},
                         .names = {"results.jsonl:1", "\"" + key + "\" appears twice"}});
  }
  cases.push_back(
      Case{.name = "watch_log_duplicate_column",
           .group = "unmodelled input",
           .args = {"watch", kLight, "--log", "log.csv"},
           .files = {edit("log.csv", kTrajectory,
                          [](std::string t) { return replaced(t, "j5_deg", "j4_deg"); })},
           .names = {"log.csv"}});
  return cases;
}

Case set(const std::string& name,
         const std::string& group,
         const std::string& command,
         std::vector<std::string> overrides,
         std::vector<std::string> names) {
  Case c{.name = name,
         .group = group,
         .args = {command, kLight, "-o", "out"},
         .names = std::move(names),
         .out = OutState::kExisting};
  for (const std::string& o : overrides) c.args.insert(c.args.end(), {"--set", o});
  return c;
}

std::vector<Case> cellCases() {
  const std::string g = "unmodelled input";
  std::vector<Case> cases;
  cases.push_back(set("one_ray_per_profile_plan", g, "plan", {"scanner.rays_per_profile=1"},
                      {"scanner.rays_per_profile"}));
  cases.push_back(set("one_ray_per_profile_auto", g, "plan",
                      {"scanner.rays_per_profile=1", "scan.auto={}"},
                      {"scanner.rays_per_profile"}));
  cases.push_back(set("table_around_the_base", g, "map", {"table.axis.xyz_mm=[0, 0, 0]"},
                      {"table.axis", "base"}));
  cases.push_back(set("table_into_the_base", g, "plan",
                      {"table.axis.xyz_mm=[250, 0, 0]", "table.radius_mm=200"}, {"table.axis"}));
  cases.push_back(set("table_through_a_world_post", g, "map",
                      {"obstacles=[{name: post, type: cylinder, radius_mm: 20, length_mm: 400, "
                       "carrier: world, pose: {xyz_mm: [520, 100, 0], rpy_deg: [0, 0, 0]}}]"},
                      {"post", "table"}));
  // A sensor that must fire in a window after the motion's end: not met (exit 3), never "met".
  for (const std::string command : {"plan", "validate"}) {
    Case c = set("sensor_window_after_the_end_" + command, g, command,
                 {"sensors=[{name: s, kind: presence, shape: sphere, radius_mm: 5, "
                  "pose: {xyz_mm: [0, 0, 5000], rpy_deg: [0, 0, 0]}, expect: during, "
                  "window_s: [5000, 6000]}]"},
                 {});
    if (command == "validate") c.args.insert(c.args.begin() + 2, {"-t", kTrajectory});
    c.exits = {3};
    c.out = OutState::kNone;
    cases.push_back(std::move(c));
  }
  cases.push_back(set("rule_includes_bodies_that_never_move_apart", g, "map",
                      {"constraints.clearance.pairs=[{a: table, b: part, action: include}]"},
                      {"constraints.clearance.pairs"}));
  return cases;
}

// ---------------------------------------------------------------------------------------------
// Estimate before working: a map's distance checks and memory, and numbers that are not normal.

std::string obstacles(int n, const std::string& carrier = "world") {
  std::string text = "obstacles:\n";
  for (int i = 0; i < n; ++i) {
    text += "  - {name: crate" + std::to_string(i) +
            ", type: sphere, radius_mm: 5, carrier: " + carrier + ", pose: {xyz_mm: [" +
            std::to_string(-2000 - 20 * (i % 100)) + ", " + std::to_string(20 * (i / 100)) +
            ", 0], rpy_deg: [0, 0, 0]}}\n";
  }
  return text;
}

std::vector<Case> estimateCases() {
  const std::string g = "work estimates";
  std::vector<Case> cases;
  for (const std::string command : {"map", "plan"}) {
    cases.push_back(
        Case{.name = "ten_thousand_obstacles_" + command,
             .group = g,
             .args = {command, "job.yaml", "-o", "out", "--set", "map.angle_step_deg=0.5"},
             .files = {jobAppended("job.yaml", obstacles(10000))},
             .names = {"distance checks", "obstacles"},
             .out = OutState::kExisting});
  }
  cases.push_back(Case{.name = "five_thousand_table_obstacles_map",
                       .group = g,
                       .args = {"map", "job.yaml", "-o", "out", "--set", "map.angle_step_deg=0.5"},
                       .files = {jobAppended("job.yaml", obstacles(5000, "table"))},
                       .names = {"distance checks", "obstacles"},
                       .out = OutState::kExisting});
  // Under the catalogue's 4 GB address space: a map within its own limit but not the machine's.
  cases.push_back(set("map_over_the_memory_left", g, "map",
                      {"map.memory_limit_mb=1000000", "map.angle_step_deg=0.01", "scan.dt_s=0.02"},
                      {"memory this machine has available"}));
  cases.push_back(set("plan_map_over_the_memory_left", g, "plan",
                      {"map.memory_limit_mb=1000000", "map.angle_step_deg=0.01", "scan.dt_s=0.02"},
                      {"memory this machine has available"}));
  // Numbers that are not normal (denormals): refused where SI values are made, naming the key.
  const std::vector<std::pair<std::string, std::string>> keys = {
      {"table.max_accel_deg_s2", "plan"},
      {"table.max_speed_deg_s", "plan"},
      {"scan.dt_s", "path"},
      {"map.angle_step_deg", "map"},
      {"part.scale", "path"},
      {"scanner.frame_rate_hz", "plan"},
      {"table.radius_mm", "map"},
      {"validation.collision_resolution_mm", "plan"},
      {"planner.k_omega", "plan"},
      {"scan.paths[0].speed_deg_s", "path"},
      {"scanner.optics.a_mm", "path"},
      {"scanner.optics.gamma_deg", "path"},
      {"scanner.laser.thickness_mm", "plan"},
      {"table.eccentricity_mm[0]", "plan"},
      {"scanner.noise.longitudinal_mm", "plan"},
      {"scanner.mount.xyz_mm[2]", "path"},
      {"planner.k_alpha", "plan"}};
  for (const auto& [key, command] : keys) {
    std::string name = "denormal_" + key;
    for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    cases.push_back(set(name, g, command, {key + "=1e-320"}, {key}));
    cases.back().exits = {4};
  }
  return cases;
}

// ---------------------------------------------------------------------------------------------
// Errors that name the real cause: the key whose value is wrong, or the geometric fact.

// A mesh file the part's job names, with files it pulls in: `path` of the light demo.
Case meshWith(const std::string& name,
              const std::string& group,
              const std::string& mesh,
              std::vector<InputFile> files,
              std::vector<std::string> names) {
  files.push_back(jobWith("job.yaml", {{"part.mesh", mesh}}));
  return Case{.name = name,
              .group = group,
              .args = {"path", "job.yaml", "-o", "out"},
              .files = std::move(files),
              .names = std::move(names),
              .out = OutState::kExisting};
}

const std::string kObj =
    "mtllib m.mtl\nv 0 0 0\nv 100 0 0\nv 0 100 0\nv 0 0 100\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
const std::string kDoctype =
    "<?xml version=\"1.0\"?>\n<!DOCTYPE robot [\n <!ENTITY a \"aaaaaaaaaa\">\n"
    " <!ENTITY b \"&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;\">\n <!ENTITY c "
    "\"&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;\">\n]>\n"
    "<robot name=\"&c;\"><link name=\"base_link\"/></robot>\n";

std::vector<Case> causeCases() {
  const std::string g = "real causes";
  std::vector<Case> cases;
  // Every file a mesh loader opens is checked first: an OBJ's material library too.
  cases.push_back(meshWith("obj_material_library_fifo", "work estimates", "m.obj",
                           {text("m.obj", kObj), fifo("m.mtl")}, {"m.obj", "m.mtl"}));
  cases.push_back(meshWith("obj_material_library_folder", "work estimates", "m.obj",
                           {text("m.obj", kObj), folder("m.mtl")}, {"m.obj", "m.mtl"}));
  cases.push_back(meshWith("obj_material_library_dev_zero", "work estimates", "m.obj",
                           {text("m.obj", kObj), symlinkTo("m.mtl", "/dev/zero")},
                           {"m.obj", "m.mtl"}));
  // Inside out: the winding, not "no pass sees the part".
  const std::string inside_out =
      "OFF\n4 4 0\n0 0 0\n100 0 0\n0 100 0\n0 0 100\n3 0 1 2\n3 0 3 1\n3 0 2 3\n3 1 3 2\n";
  cases.push_back(meshWith("mesh_inside_out_off", g, "m.off", {text("m.off", inside_out)},
                           {"part.mesh", "inside out"}));
  cases.push_back(meshWith("mesh_inside_out_obj", g, "m.obj",
                           {text("m.obj",
                                 "v 0 0 0\nv 100 0 0\nv 0 100 0\nv 0 0 100\nf 1 2 3\n"
                                 "f 1 4 2\nf 1 3 4\nf 2 4 3\n")},
                           {"part.mesh", "inside out"}));
  // An XML entity bomb or an external DTD: the declaration, not "no robot element".
  cases.push_back(Case{.name = "urdf_entity_bomb",
                       .group = g,
                       .args = {"robot", "import", "k.urdf", "-o", "k.yaml"},
                       .files = {text("k.urdf", kDoctype)},
                       .names = {"k.urdf", "DOCTYPE"}});
  cases.push_back(Case{
      .name = "urdf_external_dtd",
      .group = g,
      .args = {"robot", "import", "k.urdf", "-o", "k.yaml"},
      .files = {edit("k.urdf", "@src/data/robots/urdf/viper_s650.urdf",
                     [](std::string t) {
                       return replaced(t, "?>\n", "?>\n<!DOCTYPE robot SYSTEM \"robot.dtd\">\n");
                     })},
      .names = {"k.urdf:2", "DOCTYPE"}});
  cases.push_back(set("scanner_mount_one_km_path", g, "path",
                      {"scanner.mount.xyz_mm=[1000000, 0, 0]"}, {"scanner.mount"}));
  cases.push_back(set("scanner_mount_one_km_plan", g, "plan",
                      {"scanner.mount.xyz_mm=[0, 0, 1000000]"}, {"scanner.mount"}));
  cases.push_back(set("scanner_mount_ten_m_map", g, "map", {"scanner.mount.xyz_mm=[0, 10000, 0]"},
                      {"scanner.mount"}));
  cases.push_back(set("auto_point_spacing_1e-9", g, "path", {"scan.auto={point_spacing_mm: 1e-9}"},
                      {"scan.auto.point_spacing_mm"}));
  cases.push_back(set("auto_point_spacing_1e-6_plan", g, "plan",
                      {"scan.auto={point_spacing_mm: 1e-6}"}, {"scan.auto.point_spacing_mm"}));
  cases.push_back(set("auto_point_spacing_5e-4_map", g, "map",
                      {"scan.auto={point_spacing_mm: 5e-4}"}, {"scan.auto.point_spacing_mm"}));
  cases.push_back(set("table_at_the_robot_origin_map", g, "map", {"table.axis.xyz_mm=[0, 0, 0]"},
                      {"table.axis"}));
  cases.push_back(set("table_at_the_robot_origin_plan", g, "plan", {"table.axis.xyz_mm=[0, 0, 0]"},
                      {"table.axis"}));
  // What a terminal does not show is shown: a byte-order mark, zero-width and no-break spaces,
  // a carriage return (a file saved on Windows), bytes that are not UTF-8.
  cases.push_back(set("bom_in_a_value", g, "path", {"part.mesh=\xEF\xBB\xBFpart.stl"},
                      {"part.mesh", "<U+FEFF>part.stl"}));
  cases.push_back(set("zero_width_space_in_a_key", g, "path",
                      {"planner.ray\xE2\x80\x8B.horizon=20"}, {"planner.ray<U+200B>"}));
  cases.push_back(set("no_break_space_after_a_number", g, "map", {"table.radius_mm=250\xC2\xA0"},
                      {"table.radius_mm", "250<U+00A0>"}));
  cases.push_back(set("carriage_return_after_a_number", g, "plan", {"scan.dt_s=0.1\r"},
                      {"scan.dt_s", "0.1\\r"}));
  cases.push_back(set("latin1_byte_in_a_path", g, "path", {"part.mesh=p\xE4rt.stl"},
                      {"part.mesh", "p\\xE4rt.stl"}));
  cases.push_back(Case{.name = "bom_inside_a_job_value",
                       .group = g,
                       .args = {"path", "job.yaml", "-o", "out"},
                       .files = {edit("job.yaml", kLight,
                                      [](std::string t) {
                                        return replaced(t, "\nrobot: ", "\nrobot: \xEF\xBB\xBF");
                                      })},
                       .names = {"job.yaml:5", "robot", "<U+FEFF>"},
                       .out = OutState::kExisting});
  // A lock naming a live process that is not a scanplan run (pid 1) is stale: taken over.
  cases.push_back(Case{.name = "lock_of_another_process",
                       .group = g,
                       .args = {"path", kLight, "-o", "out"},
                       .files = {text(".out.scanplan-lock", "1\n")},
                       .exits = {0},
                       .out = OutState::kExisting});
  cases.push_back(Case{.name = "lock_is_a_fifo",
                       .group = g,
                       .args = {"path", kLight, "-o", "out"},
                       .files = {fifo(".out.scanplan-lock")},
                       .names = {"not a lock file"},
                       .out = OutState::kExisting});
  cases.push_back(Case{.name = "lock_is_a_folder",
                       .group = g,
                       .args = {"plan", kLight, "-o", "out"},
                       .files = {folder(".out.scanplan-lock")},
                       .names = {"not a lock file"},
                       .out = OutState::kExisting});
  return cases;
}

}  // namespace

std::vector<Case> modelLimitCases() {
  return concat({usersFileCases(), programCases(), formatCases(), cellCases(), estimateCases(),
                 causeCases()});
}

}  // namespace scanplan::robustness
