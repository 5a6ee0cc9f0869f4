// Truncated, garbage, special and misplaced input files, each through the commands that read it.
#include <string>

#include "tests/robustness/builders.h"
#include "tests/robustness/cases.h"

namespace scanplan::robustness {
namespace {


// Every command that reads a job, the job being `job` (and OUT "out" where there is one).
std::vector<std::pair<std::string, std::vector<std::string>>> jobCommands(const std::string& job) {
  const std::string joints = "--joints=0,-90,180,0,90,0";
  return {{"plan", {"plan", job, "-o", "out"}},
          {"path", {"path", job, "-o", "out"}},
          {"map", {"map", job, "-o", "out"}},
          {"check", {"check", job, "--table", "0", joints}},
          {"show", {"job", "show", job}},
          {"validate", {"validate", job, "-t", kTrajectory, "-o", "out"}},
          {"simulate", {"simulate", job, "-t", kTrajectory, "-o", "out"}},
          {"export", {"export", job, "-t", kTrajectory, "-o", "out"}},
          {"fk", {"fk", "--job", job, joints}},
          {"ik", {"ik", "--job", job, "--trans", "450,0,695,0,90,0"}}};
}

// The job file `file` (named job.yaml) through every command that reads a job.
void everyCommand(std::vector<Case>& cases, const std::string& name, const InputFile& file) {
  bool existing = false;
  for (const auto& [command, args] : jobCommands(file.name)) {
    const bool has_out = args.back() == "out";
    existing = !existing;
    cases.push_back(Case{.name = name + "_" + command,
                         .group = "job files",
                         .args = args,
                         .files = {file},
                         .names = {file.name},
                         .out = !has_out   ? OutState::kNone
                                : existing ? OutState::kExisting
                                           : OutState::kAbsent});
  }
}

std::vector<Case> jobFileCases() {
  std::vector<Case> cases;
  everyCommand(cases, "job_truncated_half", truncated("job.yaml", kLight, 0.5));
  for (std::size_t i = cases.size() - 10; i < cases.size(); ++i) {
    cases[i].exits = {0, 3, 4};  // half a job may still be a valid job, its defaults the rest
  }
  everyCommand(cases, "job_garbage", garbage("job.yaml", 4096));
  everyCommand(cases, "job_empty", text("job.yaml", ""));
  everyCommand(cases, "job_fifo", fifo("job.yaml"));
  everyCommand(cases, "job_dev_zero", symlinkTo("job.yaml", "/dev/zero"));
  everyCommand(cases, "job_folder", folder("job.yaml"));
  everyCommand(cases, "job_missing_robot", jobWith("job.yaml", {{"robot", "nope.yaml"}}));
  everyCommand(cases, "job_deep_nesting",
               jobAppended("job.yaml", "deep: " + nestedText(5000) + "\n"));
  return cases;
}

std::vector<Case> moreJobFileCases() {
  std::vector<Case> cases;
  const auto show = [&cases](const std::string& name, InputFile file,
                             std::vector<std::string> names) {
    if (names.empty()) names.push_back(file.name);  // else the file named is another one
    cases.push_back(Case{.name = name,
                         .group = "job files",
                         .args = {"job", "show", file.name},
                         .files = {std::move(file)},
                         .names = std::move(names)});
  };
  show("job_nul_bytes", text("job.yaml", std::string("name: a\0b\n", 10)), {});
  show("job_truncated_tenth", truncated("job.yaml", kLight, 0.1), {});
  show("job_not_a_mapping", text("job.yaml", "- 1\n- 2\n"), {});
  show("job_scalar", text("job.yaml", "42\n"), {});
  show("job_bad_utf8", text("job.yaml", "name: \xff\xfe\xfd\n"), {});
  show("job_tabs", text("job.yaml", "name:\tx\n\trobot: y\n"), {});
  show("job_unclosed_flow", jobAppended("job.yaml", "obstacles: [{name: a, type: box\n"), {});
  show("job_huge_scalar", jobAppended("job.yaml", "comment_x: " + std::string(1 << 20, 'x') + "\n"),
       {"comment_x"});
  show("job_robot_fifo", jobWith("job.yaml", {{"robot", "r.yaml"}}), {"r.yaml"});
  cases.back().files.insert(cases.back().files.begin(), fifo("r.yaml"));
  show("job_robot_dev_zero", jobWith("job.yaml", {{"robot", "r.yaml"}}), {"r.yaml"});
  cases.back().files.insert(cases.back().files.begin(), symlinkTo("r.yaml", "/dev/zero"));
  show("job_robot_garbage", jobWith("job.yaml", {{"robot", "r.yaml"}}), {"r.yaml"});
  cases.back().files.insert(cases.back().files.begin(), garbage("r.yaml", 2000));
  show("job_robot_truncated", jobWith("job.yaml", {{"robot", "r.yaml"}}), {"r.yaml"});
  cases.back().files.insert(cases.back().files.begin(), truncated("r.yaml", kRobot, 0.5));
  show("job_robot_is_job", jobWith("job.yaml", {{"robot", "r.yaml"}}), {"r.yaml"});
  cases.back().files.insert(cases.back().files.begin(), copyOf("r.yaml", kLight));
  show("job_robot_self", jobWith("job.yaml", {{"robot", "job.yaml"}}), {});
  show("job_mesh_missing", jobWith("job.yaml", {{"part.mesh", "nope.stl"}}), {"nope.stl"});
  show("job_obstacle_mesh_fifo",
       jobWith("job.yaml", {{"obstacles", "[{name: f, type: mesh, file: m.stl}]"}}), {"m.stl"});
  cases.back().files.insert(cases.back().files.begin(), fifo("m.stl"));
  return cases;
}

std::vector<Case> meshFileCases() {
  std::vector<Case> cases;
  cases.push_back(meshFileCase("stl_binary_truncated_half", truncated("m.stl", kStl, 0.5)));
  cases.push_back(
      meshFileCase("stl_binary_header_only", truncated("m.stl", kStl, 84.0 / 1562284.0)));
  cases.push_back(
      meshFileCase("stl_binary_count_huge", transformed("m.stl", kStl, [](std::string s) {
                     s[80] = s[81] = s[82] = s[83] = '\xff';
                     return s;
                   })));
  cases.push_back(
      meshFileCase("stl_ascii_truncated",
                   text("m.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n")));
  cases.push_back(meshFileCase(
      "stl_ascii_nan", text("m.stl",
                            "solid x\nfacet normal 0 0 1\nouter loop\nvertex nan 0 0\n"
                            "vertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid x\n")));
  cases.push_back(meshFileCase("stl_garbage", garbage("m.stl", 100000)));
  cases.push_back(meshFileCase("stl_empty", text("m.stl", "")));
  cases.push_back(meshFileCase("off_truncated", text("m.off", offText().substr(0, 40))));
  cases.push_back(meshFileCase("off_huge_coordinate",
                               text("m.off", "OFF\n3 1 0\n1e300 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")));
  cases.push_back(meshFileCase("off_inf_coordinate",
                               text("m.off", "OFF\n3 1 0\ninf 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")));
  cases.push_back(meshFileCase("off_negative_counts", text("m.off", "OFF\n-3 -1 0\n")));
  cases.push_back(meshFileCase("off_garbage", garbage("m.off", 5000)));
  cases.push_back(meshFileCase("ply_truncated_body",
                               text("m.ply", plyText().substr(0, plyText().size() - 20))));
  cases.push_back(meshFileCase(
      "ply_endless_header", text("m.ply", "ply\nformat ascii 1.0\n" + std::string(200000, 'c'))));
  cases.push_back(meshFileCase("ply_garbage", garbage("m.ply", 5000)));
  cases.push_back(meshFileCase("obj_garbage", garbage("m.obj", 5000)));
  cases.push_back(
      meshFileCase("obj_bad_indices", text("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n")));
  cases.push_back(meshFileCase("obj_no_faces", text("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n")));
  cases.push_back(meshFileCase("mesh_unknown_extension", copyOf("m.xyz", kStl)));
  cases.push_back(
      meshFileCase("mesh_degenerate", text("m.off", "OFF\n3 1 0\n0 0 0\n0 0 0\n0 0 0\n3 0 1 2\n")));
  return cases;
}

std::vector<Case> trajectoryFileCases() {
  std::vector<Case> cases;
  const auto csv = [&cases](const std::string& name, std::function<std::string(std::string)> f) {
    cases.push_back(trajectoryFileCase(name, transformed("t.csv", kTrajectory, std::move(f))));
  };
  csv("csv_nan_joint", [](std::string s) { return trajectoryCell(s, 2, "nan"); });
  csv("csv_inf_table", [](std::string s) { return trajectoryCell(s, 1, "inf"); });
  csv("csv_huge_joint", [](std::string s) { return trajectoryCell(s, 3, "1e300"); });
  csv("csv_text_joint", [](std::string s) { return trajectoryCell(s, 4, "abc"); });
  csv("csv_time_backwards", [](std::string s) { return trajectoryCell(s, 0, "-5"); });
  csv("csv_missing_column", [](std::string s) { return trajectoryCell(s, 5, ""); });
  csv("csv_header_only", [](std::string s) { return s.substr(0, s.find('\n') + 1); });
  csv("csv_truncated_mid_row", [](std::string s) { return s.substr(0, s.size() / 2); });
  cases.back().exits = {3, 4};  // a valid prefix of the motion may be read, and judged
  cases.push_back(trajectoryFileCase("csv_garbage", garbage("t.csv", 20000)));
  cases.push_back(trajectoryFileCase("csv_empty", text("t.csv", "")));
  cases.push_back(
      trajectoryFileCase("csv_long_line", text("t.csv", std::string(5 << 20, '1') + "\n")));
  cases.push_back(trajectoryFileCase("vplus_truncated", truncated("p.v2", kProgram, 0.5)));
  cases.push_back(trajectoryFileCase(
      "vplus_no_end",
      transformed("p.v2", kProgram, [](std::string s) { return s.substr(0, s.rfind(".END")); })));
  cases.push_back(
      trajectoryFileCase("vplus_nan_joint", transformed("p.v2", kProgram, [](std::string s) {
                           const auto at = s.find("MOVE #PPOINT(") + 13;
                           return s.replace(at, s.find(',', at) - at, "nan");
                         })));
  cases.push_back(trajectoryFileCase(
      "vplus_garbage", text("p.v2", ".PROGRAM x()\n" + std::string(2000, '\x01') + "\n.END\n")));
  cases.push_back(trajectoryFileCase("trajectory_is_job", copyOf("t.csv", kLight)));
  cases.push_back(trajectoryFileCase("trajectory_is_mesh", copyOf("t.csv", kStl)));
  cases.push_back(trajectoryFileCase("trajectory_missing", text("other.csv", "")));
  cases.back().args[3] = "t.csv";
  cases.back().names = {"t.csv"};
  return cases;
}

std::vector<Case> sweepFileCases() {
  std::vector<Case> cases;
  const auto batch = [&cases](const std::string& name, InputFile file) {
    cases.push_back(Case{.name = name,
                         .group = "sweep files",
                         .args = {"batch", file.name, "-o", "out", "--jobs", "2"},
                         .files = {file},
                         .names = {file.name},
                         .out = OutState::kAbsent});
  };
  batch("sweep_truncated", truncated("s.yaml", "@src/data/sweeps/planners.yaml", 0.3));
  batch("sweep_garbage", garbage("s.yaml", 3000));
  batch("sweep_fifo", fifo("s.yaml"));
  batch("sweep_dev_zero", symlinkTo("s.yaml", "/dev/zero"));
  batch("sweep_folder", folder("s.yaml"));
  batch("sweep_empty", text("s.yaml", ""));
  const auto report = [&cases](const std::string& name, InputFile file) {
    cases.push_back(Case{.name = name,
                         .group = "sweep files",
                         .args = {"batch", "report", "r"},
                         .files = {folder("r"), file},
                         .names = {"r"}});
  };
  report("batch_report_garbage", garbage("r/results.jsonl", 3000));
  report("batch_report_empty", text("r/results.jsonl", ""));
  cases.back().exits = {0, 4};  // no rows yet: an empty report
  report("batch_report_bad_row", text("r/results.jsonl", "{\"case_id\": 5, \"J_s\": \"x\"}\n"));
  report("batch_report_fifo", fifo("r/results.jsonl"));
  report("batch_report_no_results", text("r/other.txt", ""));
  cases.push_back(Case{.name = "batch_merge_garbage",
                       .group = "sweep files",
                       .args = {"batch", "merge", "a", "b", "-o", "out"},
                       .files = {folder("a"), folder("b"), garbage("a/results.jsonl", 3000),
                                 text("b/results.jsonl", "{}\n")},
                       .names = {"results.jsonl"},
                       .out = OutState::kExisting});
  return cases;
}

}  // namespace

std::vector<Case> fileCases() {
  return concat({jobFileCases(), moreJobFileCases(), meshFileCases(), trajectoryFileCases(),
                 sweepFileCases()});
}

}  // namespace scanplan::robustness
