// Unicode and odd paths; read-only, missing and misplaced output folders; every command's own
// arguments.
#include <string>

#include "tests/robustness/builders.h"
#include "tests/robustness/cases.h"

namespace scanplan::robustness {
namespace {

const std::string kJoints = "--joints=0,-90,180,0,90,0";

// Odd names that are fine: `job show` of the light demo copied there succeeds.
std::vector<Case> oddNameCases() {
  std::vector<Case> cases;
  const auto ok = [&cases](const std::string& name, const std::string& file) {
    cases.push_back(Case{.name = name,
                         .group = "odd paths",
                         .args = {"path", file, "-o", file + ".out"},
                         .files = {copyOf(file, kLight)},
                         .exits = {0}});
  };
  ok("unicode_name", "jöb 📐 ü.yaml");
  ok("spaces_name", "my job  file.yaml");
  ok("leading_dash_name", "./-o.yaml");
  ok("long_name", std::string(240, 'j') + ".yaml");
  ok("quote_and_dollar_name", "job'$HOME\"`x`.yaml");
  ok("newline_name", "job\nname.yaml");
  cases.push_back(Case{.name = "unicode_folders",
                       .group = "odd paths",
                       .args = {"path", "dïr ü/jöb.yaml", "-o", "öut dïr/ü"},
                       .files = {folder("dïr ü"), copyOf("dïr ü/jöb.yaml", kLight)},
                       .exits = {0}});
  cases.push_back(Case{.name = "unicode_mesh_path",
                       .group = "odd paths",
                       .args = {"path", "job.yaml", "-o", "out"},
                       .files = {copyOf("mésh ü.stl", "@src/data/parts/demo_housing.stl"),
                                 jobWith("job.yaml", {{"part.mesh", "mésh ü.stl"}})},
                       .exits = {0}});
  return cases;
}

std::vector<Case> badNameCases() {
  std::vector<Case> cases;
  const auto bad = [&cases](const std::string& name, std::vector<std::string> args,
                            std::vector<InputFile> files, std::string names,
                            std::vector<int> exits = {4}) {
    cases.push_back(Case{.name = name,
                         .group = "odd paths",
                         .args = std::move(args),
                         .files = std::move(files),
                         .exits = std::move(exits),
                         .names = {std::move(names)}});
  };
  const std::string too_long = std::string(300, 'n') + ".yaml";
  bad("name_too_long", {"job", "show", too_long}, {}, too_long.substr(0, 40));
  std::string deep;
  for (int i = 0; i < 30; ++i) deep += std::string(200, 'd') + "/";
  bad("path_too_long", {"job", "show", deep + "j.yaml"}, {}, "j.yaml");
  bad("leading_dash_missing", {"job", "show", "--", "-x.yaml"}, {}, "-x.yaml", {2, 4});
  bad("empty_job_name", {"job", "show", ""}, {}, "", {2, 4});
  bad("bad_utf8_name", {"job", "show", "j\xff\xfe.yaml"}, {}, "j");
  bad("job_is_dot", {"job", "show", "."}, {}, ".");
  bad("job_symlink_loop", {"job", "show", "loop.yaml"}, {symlinkTo("loop.yaml", "loop.yaml")},
      "loop.yaml");
  bad("job_dangling_symlink", {"job", "show", "dangling.yaml"},
      {symlinkTo("dangling.yaml", "nope")}, "dangling.yaml");
  bad("out_too_long", {"path", kLight, "-o", deep + "out"}, {}, "ddd");
  return cases;
}

// `command` writes to OUT: OUT is a file, under a file, read-only, under a read-only folder.
std::vector<std::vector<std::string>> writingCommands(const std::string& out) {
  return {{"plan", kLight, "-o", out},
          {"path", kLight, "-o", out},
          {"map", kLight, "-o", out},
          {"validate", kLight, "-t", kTrajectory, "-o", out},
          {"simulate", kLight, "-t", kTrajectory, "-o", out},
          {"export", kLight, "-t", kTrajectory, "-o", out},
          {"batch", "@src/data/sweeps/planners.yaml", "-o", out}};
}

std::vector<Case> outFolderCases() {
  std::vector<Case> cases;
  const auto each = [&cases](const std::string& label, const std::string& out,
                             std::vector<InputFile> files, bool as_nobody, OutState state) {
    for (const auto& args : writingCommands(out)) {
      cases.push_back(Case{.name = args[0] + "_" + label,
                           .group = "output folders",
                           .args = args,
                           .files = files,
                           .names = {out.substr(0, out.find('/'))},
                           .out = state,
                           .as_nobody = as_nobody});
    }
  };
  each("out_is_file", "out", {text("out", "a file\n")}, false, OutState::kNone);
  each("out_under_file", "f/out", {text("f", "a file\n")}, false, OutState::kNone);
  each("out_read_only", "out", {}, true, OutState::kExisting);
  each("out_parent_read_only", "ro/out", {readOnlyFolder("ro")}, true, OutState::kNone);
  return cases;
}

std::vector<Case> outMissingCases() {
  std::vector<Case> cases;
  cases.push_back(Case{.name = "path_out_parents_missing",
                       .group = "output folders",
                       .args = {"path", kLight, "-o", "a/b/c/out"},
                       .exits = {0}});
  cases.push_back(Case{.name = "path_out_dev_null",
                       .group = "output folders",
                       .args = {"path", kLight, "-o", "/dev/null"},
                       .names = {"/dev/null"}});
  cases.push_back(Case{.name = "path_out_proc",
                       .group = "output folders",
                       .args = {"path", kLight, "-o", "/proc/self/out"},
                       .names = {"/proc/self/out"}});
  cases.push_back(Case{.name = "path_out_fifo",
                       .group = "output folders",
                       .args = {"path", kLight, "-o", "out"},
                       .files = {fifo("out")},
                       .names = {"out"}});
  return cases;
}

}  // namespace

std::vector<Case> pathCases() {
  std::vector<Case> all;
  for (auto part : {oddNameCases(), badNameCases(), outFolderCases(), outMissingCases()}) {
    all.insert(all.end(), part.begin(), part.end());
  }
  return all;
}

namespace {

std::vector<Case> kinematicsCases() {
  std::vector<Case> cases;
  const auto add = [&cases](const std::string& name, std::vector<std::string> args,
                            std::vector<std::string> names, std::vector<int> exits) {
    cases.push_back(Case{.name = name,
                         .group = "command arguments",
                         .args = std::move(args),
                         .exits = std::move(exits),
                         .names = std::move(names)});
  };
  const std::vector<int> usage_or_input{2, 4};
  add("fk_joints_nan", {"fk", "--robot", kRobot, "--joints=nan,0,0,0,0,0"}, {"--joints"},
      usage_or_input);
  add("fk_joints_inf", {"fk", "--robot", kRobot, "--joints=inf,0,0,0,0,0"}, {"--joints"},
      usage_or_input);
  add("fk_joints_1e300", {"fk", "--robot", kRobot, "--joints=1e300,0,0,0,0,0"}, {"--joints"},
      usage_or_input);
  add("fk_joints_five", {"fk", "--robot", kRobot, "--joints=0,0,0,0,0"}, {"--joints"},
      usage_or_input);
  add("fk_joints_text", {"fk", "--robot", kRobot, "--joints=a,b,c,d,e,f"}, {"--joints"},
      usage_or_input);
  add("ik_trans_nan", {"ik", "--robot", kRobot, "--trans", "nan,0,695,0,90,0"}, {"--trans"},
      usage_or_input);
  add("ik_trans_1e300", {"ik", "--robot", kRobot, "--trans", "1e300,0,695,0,90,0"}, {"--trans"},
      usage_or_input);
  add("ik_trans_short", {"ik", "--robot", kRobot, "--trans", "1,2"}, {"--trans"}, usage_or_input);
  add("ik_matrix_not_rotation",
      {"ik", "--robot", kRobot, "--matrix", "2,0,0,450,0,2,0,0,0,0,2,695,0,0,0,1"}, {"--matrix"},
      usage_or_input);
  add("ik_matrix_nan",
      {"ik", "--robot", kRobot, "--matrix", "nan,0,0,450,0,1,0,0,0,0,1,695,0,0,0,1"}, {"--matrix"},
      usage_or_input);
  add("ik_unreachable", {"ik", "--robot", kRobot, "--trans", "90000,0,695,0,90,0"}, {}, {3});
  add("ik_robot_garbage", {"ik", "--robot", "r.yaml", "--trans", "450,0,695,0,90,0"}, {"r.yaml"},
      {4});
  cases.back().files = {garbage("r.yaml", 3000)};
  add("fk_robot_fifo", {"fk", "--robot", "r.yaml", kJoints}, {"r.yaml"}, {4});
  cases.back().files = {fifo("r.yaml")};
  add("fk_robot_dev_zero", {"fk", "--robot", "r.yaml", kJoints}, {"r.yaml"}, {4});
  cases.back().files = {symlinkTo("r.yaml", "/dev/zero")};
  return cases;
}

std::vector<Case> checkCases() {
  std::vector<Case> cases;
  const auto add = [&cases](const std::string& name, std::vector<std::string> extra,
                            std::vector<std::string> names, std::vector<int> exits) {
    std::vector<std::string> args{"check", kLight};
    args.insert(args.end(), extra.begin(), extra.end());
    cases.push_back(Case{.name = name,
                         .group = "command arguments",
                         .args = std::move(args),
                         .exits = std::move(exits),
                         .names = std::move(names)});
  };
  add("check_table_nan", {"--table", "nan", kJoints}, {"--table"}, {2, 4});
  add("check_table_1e300", {"--table", "1e300", kJoints}, {"--table"}, {2, 4});
  add("check_table_inf", {"--table", "inf", kJoints}, {"--table"}, {2, 4});
  add("check_time_negative", {"--table", "0", "--time", "-1"}, {"--time"}, {2, 4});
  add("check_time_1e300", {"--table", "0", "--time", "1e300"}, {"--time"}, {2, 4});
  add("check_time_nan", {"--table", "0", "--time", "nan"}, {"--time"}, {2, 4});
  add("check_joints_huge", {"--table", "0", "--joints=1e300,0,0,0,0,0"}, {"--joints"}, {2, 4});
  return cases;
}

std::vector<Case> verifyCases() {
  std::vector<Case> cases;
  const auto add = [&cases](const std::string& name, std::vector<std::string> args,
                            std::vector<std::string> names, std::vector<int> exits, OutState out) {
    cases.push_back(Case{.name = name,
                         .group = "command arguments",
                         .args = std::move(args),
                         .exits = std::move(exits),
                         .names = std::move(names),
                         .out = out});
  };
  add("export_format_bogus", {"export", kLight, "-t", kTrajectory, "-o", "out", "-f", "bogus"},
      {"bogus"}, {2, 4}, OutState::kExisting);
  add("export_format_empty", {"export", kLight, "-t", kTrajectory, "-o", "out", "-f", ""},
      {"format"}, {0, 2, 4}, OutState::kAbsent);  // an empty list: the job's formats
  add("plan_setups_3", {"plan", kLight, "-o", "out", "--setups", "3"}, {"--setups"}, {2},
      OutState::kExisting);
  add("plan_planner_bogus", {"plan", kLight, "-o", "out", "--planner", "x"}, {"--planner"}, {2},
      OutState::kAbsent);
  add("plan_set_no_equals", {"plan", kLight, "-o", "out", "--set", "scan.dt_s"}, {"scan.dt_s"},
      {2, 4}, OutState::kExisting);
  add("plan_set_unknown", {"plan", kLight, "-o", "out", "--set", "scan.bogus=1"}, {"scan.bogus"},
      {4}, OutState::kExisting);
  add("plan_set_index_huge",
      {"plan", kLight, "-o", "out", "--set", "scan.paths[99999999999].height_mm=1"}, {"scan.paths"},
      {4}, OutState::kExisting);
  add("batch_shard_zero",
      {"batch", "@src/data/sweeps/planners.yaml", "-o", "out", "--shard", "0/4"}, {"--shard"},
      {2, 4}, OutState::kAbsent);
  add("batch_shard_huge",
      {"batch", "@src/data/sweeps/planners.yaml", "-o", "out", "--shard", "1/99999999999999999999"},
      {"--shard"}, {2, 4}, OutState::kAbsent);
  return cases;
}

}  // namespace

std::vector<Case> commandCases() {
  std::vector<Case> all;
  for (auto part : {kinematicsCases(), checkCases(), verifyCases()}) {
    all.insert(all.end(), part.begin(), part.end());
  }
  return all;
}

}  // namespace scanplan::robustness
