// The hand-written cases, by class. A case: its name, class, command line (after "scanplan"; run
// in the case's scratch folder, "out" is its OUT), input files, the exit codes that pass and
// what stderr must name. tests/robustness/README.md has the rules.
#include "tests/robustness/cases.h"

#include <string>

#include "tests/robustness/builders.h"

namespace scanplan::robustness {
namespace {

// A YAML alias bomb ("billion laughs"): 9 levels of 9 aliases, 9^9 nodes when expanded.
std::string aliasBomb() {
  std::string text = "[&a0 [1, 1, 1, 1, 1, 1, 1, 1, 1]";
  for (int level = 1; level < 9; ++level) {
    const std::string prev = "*a" + std::to_string(level - 1);
    text += ", &a" + std::to_string(level) + " [" + prev;
    for (int i = 1; i < 9; ++i) text += ", " + prev;
    text += "]";
  }
  return text + "]";
}

std::string nested(int depth) {
  const auto n = static_cast<std::size_t>(depth);
  return std::string(n, '[') + "1" + std::string(n, ']');
}

// A small closed mesh (a tetrahedron) in each format, for the ones edited below.
const std::string kOff =
    "OFF\n4 4 0\n0 0 0\n100 0 0\n0 100 0\n0 0 100\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
const std::string kPlyHeader =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
    "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n";
const std::string kPlyBody =
    "0 0 0\n100 0 0\n0 100 0\n0 0 100\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

// `path` on the light demo with its mesh replaced by `mesh` (made by `file`).
Case meshCase(const std::string& name, InputFile file, std::vector<int> exits = {4}) {
  const std::string mesh = file.name;
  return Case{.name = name,
              .group = "mesh files",
              .args = {"path", "job.yaml", "-o", "out"},
              .files = {std::move(file), jobWith("job.yaml", {{"part.mesh", mesh}})},
              .exits = std::move(exits),
              .names = {mesh},
              .out = OutState::kExisting};
}

// `validate` of the light demo's plan with its trajectory replaced by `file`.
Case trajectoryCase(const std::string& name, InputFile file, std::vector<int> exits = {4}) {
  const std::string trajectory = file.name;
  return Case{.name = name,
              .group = "trajectory files",
              .args = {"validate", kLight, "-t", trajectory, "-o", "out"},
              .files = {std::move(file)},
              .exits = std::move(exits),
              .names = {trajectory},
              .out = OutState::kAbsent};
}

// The last row's time set to `t_s` (the rows before keep theirs).
std::string lastTime(std::string csv, const std::string& t_s) {
  while (!csv.empty() && csv.back() == '\n') csv.pop_back();
  const auto row = csv.rfind('\n') + 1;
  return csv.replace(row, csv.find(',', row) - row, t_s) + "\n";
}

// Row 3's column `column` (0-based) replaced by `value`.
std::string cell(const std::string& csv, int column, const std::string& value) {
  std::size_t at = 0;
  for (int line = 0; line < 3; ++line) at = csv.find('\n', at) + 1;
  for (int c = 0; c < column; ++c) at = csv.find(',', at) + 1;
  const std::size_t end = csv.find_first_of(",\n", at);
  return csv.substr(0, at) + value + csv.substr(end);
}

std::vector<Case> reportedJobCases() {
  std::vector<Case> cases;
  const auto set = [&cases](const std::string& name, const std::string& command,
                            const std::string& override_text, const std::string& key) {
    cases.push_back(Case{.name = name,
                         .group = "reported classes",
                         .args = {command, kLight, "-o", "out", "--set", override_text},
                         .names = {key},
                         .out = OutState::kExisting});
  };
  set("set_height_1e300", "plan", "scan.paths[0].height_mm=1e300", "scan.paths[0].height_mm");
  set("set_alias_bomb", "plan", "scan.paths=" + aliasBomb(), "scan.paths");
  set("set_alias_bomb_name", "path", "name=" + aliasBomb(), "name");
  set("set_deep_nesting", "path", "table.axis.xyz_mm=" + nested(200), "table.axis.xyz_mm");
  set("ring_speed_1e-6", "path", "scan.paths[0].speed_deg_s=1e-6", "scan.paths");
  set("ring_speed_1e-6_plan", "plan", "scan.paths[0].speed_deg_s=1e-6", "scan.paths");
  set("raster_lead_huge", "path", "scan.paths=[{type: raster, view: [0, 0, -1], lead_mm: 900000}]",
      "scan.paths[0]");
  set("part_scale_1e7", "path", "part.scale=1e7", "part.scale");
  set("part_scale_1e7_plan", "plan", "part.scale=1e7", "part.scale");
  // A mesh in mm declared m: 100 m across; accepted with a warning, then no path (exit 3).
  set("part_units_m", "path", "part.units=m", "part.units");
  cases.back().exits = {0, 3, 4};
  set("part_units_m_plan", "plan", "part.units=m", "part.units");
  cases.back().exits = {3, 4};
  set("dt_tiny", "plan", "scan.dt_s=1e-4", "scan.dt_s");
  set("map_step_tiny", "map", "map.angle_step_deg=0.0001", "map.angle_step_deg");
  set("map_memory_tiny", "map", "map.memory_limit_mb=1", "map.memory_limit_mb");
  set("rays_per_profile_huge_sim", "plan", "scanner.rays_per_profile=1e9",
      "scanner.rays_per_profile");
  set("frame_rate_huge", "plan", "scanner.frame_rate_hz=1e9", "scanner.frame_rate_hz");
  set("validation_resolution_tiny", "plan", "validation.collision_resolution_mm=1e-9",
      "validation.collision_resolution_mm");
  return cases;
}

std::vector<Case> reportedFileCases() {
  std::vector<Case> cases;
  cases.push_back(
      meshCase("off_2pow31_vertices", text("m.off", "OFF\n2147483648 1 0\n0 0 0\n3 0 1 2\n")));
  cases.push_back(meshCase("off_face_index_out_of_range",
                           text("m.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")));
  cases.push_back(meshCase("off_negative_face_index",
                           text("m.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n")));
  cases.push_back(meshCase("ply_header_only", text("m.ply", kPlyHeader)));
  cases.push_back(
      meshCase("ply_1e9_vertices",
               text("m.ply",
                    "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\n"
                    "property float x\nproperty float y\nproperty float z\nend_header\n")));
  cases.push_back(meshCase("ply_face_index_out_of_range",
                           text("m.ply", kPlyHeader + "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 9\n"
                                                      "3 0 1 3\n3 0 3 2\n3 1 2 3\n")));
  cases.push_back(meshCase("mesh_fifo", fifo("m.stl")));
  cases.push_back(meshCase("mesh_dev_zero", symlinkTo("m.stl", "/dev/zero")));
  cases.push_back(meshCase("mesh_folder", folder("m.stl")));
  cases.push_back(meshCase("mesh_in_mm_declared_m", copyOf("m.stl", kStl), {0, 3, 4}));
  cases.back().files.back() = jobWith("job.yaml", {{"part.mesh", "m.stl"}, {"part.units", "m"}});
  cases.back().names = {"part"};
  cases.push_back(Case{
      .name = "part_sunk_into_table",
      .group = "reported classes",
      .args = {"path", "job.yaml", "-o", "out"},
      .files = {jobWith("job.yaml", {{"part.place", "none"}, {"part.pose.xyz_mm", "[0, 0, -40]"}})},
      .names = {"job.yaml", "part.pose"},
      .out = OutState::kAbsent});
  return cases;
}

std::vector<Case> reportedTrajectoryCases() {
  std::vector<Case> cases;
  cases.push_back(
      trajectoryCase("vplus_30kb_move_line", transformed("p.v2", kProgram, [](std::string s) {
                       const auto at = s.find("    MOVE #PPOINT(");
                       return s.insert(at + 17, std::string(30000, '1') + ", ");
                     })));
  cases.push_back(trajectoryCase(
      "vplus_30kb_comment_line",
      transformed("p.v2", kProgram,
                  [](std::string s) {
                    return s.insert(s.find("\n") + 1, "; " + std::string(30000, 'x') + "\n");
                  }),
      {0, 4}));
  cases.push_back(
      trajectoryCase("vplus_30kb_garbage_line", transformed("p.v2", kProgram, [](std::string s) {
                       return s.insert(s.find("    SPEED"), std::string(30000, 'Q') + "\n");
                     })));
  cases.push_back(trajectoryCase(
      "trajectory_time_100000s",
      transformed("t.csv", kTrajectory, [](std::string s) { return lastTime(s, "100000"); })));
  cases.push_back(trajectoryCase(
      "trajectory_time_1e300",
      transformed("t.csv", kTrajectory, [](std::string s) { return lastTime(s, "1e300"); })));
  cases.push_back(trajectoryCase("trajectory_fifo", fifo("t.csv")));
  cases.push_back(trajectoryCase("trajectory_dev_zero", symlinkTo("t.csv", "/dev/zero")));
  cases.push_back(trajectoryCase("trajectory_folder", folder("t.csv")));
  return cases;
}

std::vector<Case> reportedSweepCases() {
  std::vector<Case> cases;
  const auto sweep = [&cases](const std::string& name, const std::string& body,
                              std::vector<std::string> names, std::vector<int> exits = {4}) {
    names.insert(names.begin(), "s.yaml");
    cases.push_back(
        Case{.name = name,
             .group = "sweep files",
             .args = {"batch", "s.yaml", "-o", "out", "--jobs", "2"},
             .files = {copyOf("light.yaml", kLight), text("s.yaml", "jobs: [light.yaml]\n" + body)},
             .exits = std::move(exits),
             .names = std::move(names),
             .out = OutState::kAbsent});
  };
  sweep("sweep_list_key", "vary:\n  [planner.method]: [ray]\n", {"vary"});
  sweep("sweep_indexed_list_key", "vary:\n  scan.paths[9].height_mm: [10, 20]\n",
        {"scan.paths[9]"});
  sweep("sweep_duplicate_key", "vary:\n  planner.method: [ray]\n  planner.method: [dp]\n",
        {"planner.method"});
  sweep("sweep_duplicate_top_key", "set: []\nset: []\n", {"set"});
  sweep("sweep_huge_grid",
        "vary:\n  planner.ray.horizon: {from: 1, to: 1000000, step: 1}\n"
        "  planner.ray.rays: {from: 1, to: 1000000, step: 1}\n",
        {"planner.ray.horizon"});
  sweep("sweep_range_step_tiny", "vary:\n  planner.k_omega: {from: 0, to: 1, step: 1e-300}\n",
        {"planner.k_omega"});
  sweep("sweep_range_nan", "vary:\n  planner.k_omega: {from: .nan, to: 1, step: 0.5}\n",
        {"planner.k_omega"});
  sweep("sweep_seeds_huge", "seeds: {from: 0, to: 2147483647, step: 1}\n", {"seeds"});
  sweep("sweep_seed_negative", "seeds: [-1]\n", {"seeds"});
  sweep("sweep_repeats_huge", "repeats: 1000000000\n", {"repeats"});
  sweep("sweep_alias_bomb", "vary:\n  planner.ray.horizon: " + aliasBomb() + "\n", {"s.yaml"});
  sweep("sweep_unknown_top_key", "bogus: 1\n", {"bogus"});
  sweep("sweep_bad_value", "vary:\n  table.radius_mm: [-5]\n", {"table.radius_mm"});
  sweep("sweep_missing_job", "vary: {}\n", {});
  cases.back().files.back() = text("s.yaml", "jobs: [nope.yaml]\n");
  cases.back().names = {"nope.yaml"};
  cases.push_back(
      Case{.name = "batch_jobs_100000000",
           .group = "reported classes",
           .args = {"batch", "@src/data/sweeps/planners.yaml", "-o", "out", "--jobs", "100000000"},
           .exits = {2},
           .names = {"--jobs"},
           .out = OutState::kAbsent});
  return cases;
}

std::vector<Case> reportedMiscCases() {
  std::vector<Case> cases;
  std::string unknown;
  for (int i = 0; i < 5000; ++i) unknown += "unknown_key_" + std::to_string(i) + ": 1\n";
  cases.push_back(Case{.name = "job_5000_unknown_keys",
                       .group = "reported classes",
                       .args = {"plan", "job.yaml", "-o", "out"},
                       .files = {jobAppended("job.yaml", unknown)},
                       .names = {"job.yaml", "unknown_key_0"},
                       .out = OutState::kExisting});
  cases.push_back(Case{.name = "job_alias_bomb",
                       .group = "reported classes",
                       .args = {"plan", "job.yaml", "-o", "out"},
                       .files = {jobAppended("job.yaml", "bomb: " + aliasBomb() + "\n")},
                       .names = {"job.yaml"},
                       .out = OutState::kExisting});
  cases.push_back(Case{.name = "job_duplicate_key",
                       .group = "reported classes",
                       .args = {"plan", "job.yaml", "-o", "out"},
                       .files = {jobAppended("job.yaml", "name: again\n")},
                       .names = {"job.yaml", "name"},
                       .out = OutState::kExisting});
  cases.push_back(Case{
      .name = "job_duplicate_nested_key",
      .group = "reported classes",
      .args = {"path", "job.yaml", "-o", "out"},
      .files = {text("job.yaml", "name: x\nrobot: " + expand(kRobot) +
                                     "\npart: {mesh: " + expand(kStl) + ", scale: 1, scale: 2}\n")},
      .names = {"job.yaml", "scale"},
      .out = OutState::kAbsent});
  for (const auto& [name, command] :
       {std::pair{"plan_full_disk", "plan"}, std::pair{"path_full_disk", "path"},
        std::pair{"map_full_disk", "map"}}) {
    cases.push_back(Case{.name = name,
                         .group = "output folders",
                         .args = {command, kLight, "-o", "out"},
                         .names = {"out"},
                         .out = OutState::kExisting,
                         .file_size_limit = 8 * 1024});
  }
  return cases;
}

}  // namespace

std::vector<Case> concat(std::initializer_list<std::vector<Case>> parts) {
  std::vector<Case> all;
  for (const auto& part : parts) all.insert(all.end(), part.begin(), part.end());
  return all;
}

std::vector<Case> reportedCases() {
  return concat({reportedJobCases(), reportedFileCases(), reportedTrajectoryCases(),
                 reportedSweepCases(), reportedMiscCases()});
}

// Shared with files.cpp and paths.cpp.
Case meshFileCase(const std::string& name, InputFile file, std::vector<int> exits) {
  return meshCase(name, std::move(file), std::move(exits));
}
Case trajectoryFileCase(const std::string& name, InputFile file, std::vector<int> exits) {
  return trajectoryCase(name, std::move(file), std::move(exits));
}
std::string trajectoryCell(std::string csv, int column, const std::string& value) {
  return cell(std::move(csv), column, value);
}
const std::string& offText() { return kOff; }
const std::string& plyText() {
  static const std::string ply = kPlyHeader + kPlyBody;
  return ply;
}
std::string aliasBombText() { return aliasBomb(); }
std::string nestedText(int depth) { return nested(depth); }

}  // namespace scanplan::robustness
