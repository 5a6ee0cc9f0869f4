// Robots from URDF (config/robot_urdf.h, `scanplan robot import`). The yardstick is the URDF
// itself: its forward kinematics composed here straight from urdfdom's joints (origin, then the
// rotation about the axis), independent of the DH and OPW derivation under test.

#include <gtest/gtest.h>

#include <cstdlib>
#include <limits>
#include <map>
#include <numbers>
#include <random>

#include <fmt/format.h>
#include <urdf_parser/urdf_parser.h>
#include <nlohmann/json.hpp>

#include <scanplan/config/job.h>
#include <scanplan/config/robot_urdf.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/shape.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/pipeline/replay.h>
#include "cli_support.h"
#include "test_support.h"

namespace scanplan {
namespace {

namespace fs = std::filesystem;
using kinematics::JointVector;

// The URDF-derived model and the URDF's own chain: the same up to rounding (m, rad).
constexpr double kFkTol = 1e-9;

fs::path urdfDir() { return test::sourceDir() / "data/robots/urdf"; }

Eigen::Isometry3d pose(const urdf::Pose& p) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() << p.position.x, p.position.y, p.position.z;
  X.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z)
                   .normalized()
                   .toRotationMatrix();
  return X;
}

// The URDF's links at joint values q (the chain's revolute joints in order; others at 0): every
// link's pose in base_link, composed down the tree from base_link.
class UrdfTree {
 public:
  UrdfTree(const fs::path& file, const std::string& base, const std::string& tip)
      : model_(urdf::parseURDFFile(file.string())), base_(base) {
    std::vector<std::string> path;
    for (auto link = model_->getLink(tip); link->name != base;
         link = model_->getLink(link->parent_joint->parent_link_name)) {
      if (link->parent_joint->type != urdf::Joint::FIXED)
        path.insert(path.begin(), link->parent_joint->name);
    }
    for (std::size_t i = 0; i < path.size(); ++i) chain_index_[path[i]] = static_cast<int>(i);
  }

  std::map<std::string, Eigen::Isometry3d> linkPoses(const JointVector& q) const {
    std::map<std::string, Eigen::Isometry3d> poses;
    std::vector<std::pair<urdf::LinkConstSharedPtr, Eigen::Isometry3d>> stack{
        {model_->getLink(base_), Eigen::Isometry3d::Identity()}};
    while (!stack.empty()) {
      const auto [link, X] = stack.back();
      stack.pop_back();
      poses[link->name] = X;
      for (const auto& j : link->child_joints) {
        Eigen::Isometry3d X_child = X * pose(j->parent_to_joint_origin_transform);
        const auto k = chain_index_.find(j->name);
        if (k != chain_index_.end()) {
          const Eigen::Vector3d axis(j->axis.x, j->axis.y, j->axis.z);
          X_child.linear() = X_child.linear() * Eigen::AngleAxisd(q(k->second), axis.normalized());
        }
        stack.push_back({model_->getLink(j->child_link_name), X_child});
      }
    }
    return poses;
  }

  const urdf::ModelInterface& model() const { return *model_; }

 private:
  urdf::ModelInterfaceSharedPtr model_;
  std::string base_;
  std::map<std::string, int> chain_index_;
};

::testing::AssertionResult sameFrame(const Eigen::Isometry3d& a,
                                     const Eigen::Isometry3d& b,
                                     double* max_error = nullptr) {
  return test::samePose(a, b, kFkTol, max_error);
}

struct Shipped {
  std::string urdf;        // in data/robots/urdf
  std::string robot_file;  // in data/robots, or ""
  std::string opw_file;    // in data/robots/urdf, or ""
};

config::UrdfRobotSource source(const Shipped& s) {
  config::UrdfRobotSource src;
  src.urdf = urdfDir() / (s.urdf + ".urdf");
  if (!s.opw_file.empty()) src.opw_parameters = urdfDir() / s.opw_file;
  return src;
}

kinematics::RobotModel build(const config::RobotSpec& spec) {
  return config::buildRobotModel(spec, spec.name);
}

class ShippedUrdf : public ::testing::TestWithParam<Shipped> {};

TEST_P(ShippedUrdf, ModelHasTheUrdfsForwardKinematicsAndItsRobotFilesAndIkInvertsIt) {
  const Shipped& s = GetParam();
  const config::UrdfRobotSource src = source(s);
  const kinematics::RobotModel model = build(config::importUrdf(src).spec);
  const UrdfTree tree(src.urdf, "base_link", "tool0");
  std::optional<kinematics::RobotModel> file;
  if (!s.robot_file.empty()) {
    const fs::path f = test::sourceDir() / "data/robots" / s.robot_file;
    file.emplace(config::buildRobotModel(config::loadRobotFile(f), f.string()));
  }
  std::mt19937 rng(2024);
  double max_error = 0.0, max_file_error = 0.0;
  for (int k = 0; k < 1000; ++k) {
    const JointVector q = test::randomJoints(model, rng);
    ASSERT_TRUE(sameFrame(model.fk(q), tree.linkPoses(q).at("tool0"), &max_error)) << "k " << k;
    if (file) {
      ASSERT_TRUE(sameFrame(model.fk(q), file->fk(q), &max_file_error)) << "k " << k;
    }
    if (k % 5 != 0) continue;
    const Eigen::Isometry3d X = model.fk(q);
    const auto solutions = model.ik(X);
    ASSERT_FALSE(solutions.empty());
    for (const auto& sol : solutions) ASSERT_TRUE(sameFrame(model.fk(sol.q), X));
  }
  std::printf("%s: max FK difference to the URDF %.3g m or rad%s\n", s.urdf.c_str(), max_error,
              file ? fmt::format(", to the robot file {:.3g}", max_file_error).c_str() : "");
}

INSTANTIATE_TEST_SUITE_P(
    Robots,
    ShippedUrdf,
    ::testing::Values(Shipped{"viper_s650", "viper_s650.yaml", ""},
                      Shipped{"kuka_kr6_r900_sixx", "kuka_kr6_r900_sixx.yaml", ""},
                      Shipped{"kuka_kr6_r700_sixx", "", "kuka_kr6_r700_sixx_opw.yaml"},
                      Shipped{"kuka_kr6_r700_sixx", "", ""},
                      Shipped{"abb_irb2400", "", "abb_irb2400_opw.yaml"},
                      Shipped{"fanuc_lrmate200id", "", ""}),
    [](const auto& param_info) {
      return param_info.param.urdf + (param_info.param.opw_file.empty() ? "" : "_with_opw_file");
    });

TEST(Urdf, AJointAgainstItsAxisIsDirectionMinusOne) {
  // FANUC's J3, J4, J5, J6 turn about negative axes; the KR6's A1, A4, A6.
  const config::RobotSpec fanuc = config::importUrdf(source({"fanuc_lrmate200id", "", ""})).spec;
  const config::RobotSpec kuka = config::importUrdf(source({"kuka_kr6_r700_sixx", "", ""})).spec;
  const int fanuc_dirs[] = {1, 1, -1, -1, -1, -1}, kuka_dirs[] = {-1, 1, 1, -1, 1, -1};
  for (std::size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(fanuc.dh[i].direction, fanuc_dirs[i]) << "J" << i + 1;
    EXPECT_EQ(kuka.dh[i].direction, kuka_dirs[i]) << "J" << i + 1;
  }
}

TEST(Urdf, ANonOrthoParallelArmIsRefusedNamingTheConditions) {
  config::UrdfRobotSource src;
  src.urdf = test::sourceDir() / "tests/urdf/ur5.urdf";
  EXPECT_TRUE(test::throwsInputError(
      [&] { config::importUrdf(src); },
      {"ur5.urdf", "not an ortho-parallel arm",
       "J4 (wrist_1_joint) is not perpendicular to J3 (elbow_joint): the axes are 0 deg apart",
       "J4, J5 and J6 axes do not meet in one point"}));
}

TEST(Urdf, BadLinksJointsAndOpwFilesAreClearErrors) {
  config::UrdfRobotSource src = source({"abb_irb2400", "", ""});
  src.tip_link = "tool1";
  EXPECT_TRUE(test::throwsInputError(
      [&] { config::importUrdf(src); },
      {"abb_irb2400.urdf", "tip_link 'tool1': no such link", "base_link, link_1"}));
  src.tip_link = "link_4";
  EXPECT_TRUE(test::throwsInputError(
      [&] { config::importUrdf(src); },
      {"4 revolute joints between base_link 'base_link' and tip_link 'link_4'", "expected 6"}));
  // An opw file whose upper arm is 15 mm too long.
  const fs::path dir =
      fs::temp_directory_path() / ("scanplan_urdf_opw_" + std::to_string(getpid()));
  fs::create_directories(dir);
  std::string text = test::readFile(urdfDir() / "abb_irb2400_opw.yaml");
  text.replace(text.find("c2: 0.705"), 9, "c2: 0.720");
  test::writeFile(dir / "bad_opw.yaml", text);
  src = source({"abb_irb2400", "", ""});
  src.opw_parameters = dir / "bad_opw.yaml";
  EXPECT_TRUE(test::throwsInputError(
      [&] { config::importUrdf(src); },
      {"bad_opw.yaml", "c2 0.72", "disagree with the URDF chain base_link → tool0",
       "the chain's own are a1 0.1, a2 -0.135, b 0, c1 0.615, c2 0.705"}));
  fs::remove_all(dir);
}

// A joint of the chain that mimics another, and a link that two joints name as their child (a
// closed chain, which urdfdom turns into a loop of parents), are refused naming the joint and the
// link; a mimic on a joint off the chain is no concern of the arm's.
TEST(Urdf, AMimicJointOnTheChainAndAClosedChainAreRefused) {
  const fs::path dir =
      fs::temp_directory_path() / ("scanplan_urdf_tree_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string text = test::readFile(urdfDir() / "viper_s650.urdf");
  const auto imported = [&](const std::string& name, const std::string& from,
                            const std::string& to) {
    std::string edited = text;
    const auto at = edited.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    test::writeFile(dir / name, edited.replace(at, from.size(), to));
    config::UrdfRobotSource src = source({"viper_s650", "", ""});
    src.urdf = dir / name;
    return [src] { config::importUrdf(src); };
  };
  const std::string chain = "<parent link=\"link_2\"/><child link=\"link_3\"/>";
  EXPECT_TRUE(
      test::throwsInputError(imported("mimic.urdf", chain, chain + "<mimic joint=\"joint_2\"/>"),
                             {"mimic.urdf", "joint 'joint_3' has <mimic joint=\"joint_2\">"}));
  EXPECT_TRUE(test::throwsInputError(
      imported("loop.urdf", "</robot>",
               "<joint name=\"loop\" type=\"fixed\"><parent link=\"link_5\"/>"
               "<child link=\"link_2\"/></joint></robot>"),
      {"loop.urdf", "link 'link_2' is the child of two joints", "'joint_2' and 'loop'"}));
  EXPECT_TRUE(test::throwsInputError(
      imported("self.urdf", "</robot>",
               "<link name=\"x\"/><joint name=\"self\" type=\"fixed\"><parent link=\"x\"/>"
               "<child link=\"x\"/></joint></robot>"),
      {"self.urdf"}));
  EXPECT_NO_THROW(imported("off_chain.urdf", "</robot>",
                           "<link name=\"finger\"/><joint name=\"finger_joint\" "
                           "type=\"revolute\"><parent link=\"link_6\"/><child "
                           "link=\"finger\"/><limit lower=\"0\" upper=\"1\" effort=\"0\" "
                           "velocity=\"1\"/><mimic joint=\"joint_6\"/></joint></robot>")());
  fs::remove_all(dir);
}

// Links in a loop of parents away from the root (each the child of one joint, so urdfdom finds
// its root elsewhere and reads the file) are refused naming a link of the loop and its joints;
// a link hung from the tree off the chain is fine.
TEST(Urdf, ALinkThatIsItsOwnAncestorIsRefusedNamingTheLoop) {
  const fs::path dir =
      fs::temp_directory_path() / ("scanplan_urdf_loop_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string text = test::readFile(urdfDir() / "viper_s650.urdf");
  const auto withLinks = [&](const std::string& name, const std::string& extra) {
    std::string edited = text;
    test::writeFile(dir / name, edited.replace(edited.find("</robot>"), 8, extra + "</robot>"));
    config::UrdfRobotSource src = source({"viper_s650", "", ""});
    src.urdf = dir / name;
    return [src] { config::importUrdf(src); };
  };
  const auto fixed = [](const std::string& name, const std::string& parent,
                        const std::string& child) {
    return "<joint name=\"" + name + "\" type=\"fixed\"><parent link=\"" + parent +
           "\"/><child link=\"" + child + "\"/></joint>";
  };
  const std::string links = "<link name=\"a\"/><link name=\"b\"/><link name=\"c\"/>";
  EXPECT_TRUE(test::throwsInputError(
      withLinks("cycle.urdf",
                links + fixed("ab", "a", "b") + fixed("bc", "b", "c") + fixed("ca", "c", "a")),
      {"cycle.urdf", "link 'a' is its own ancestor", "the joints 'ca', 'bc', 'ab' lead from it",
       "expected a tree of links"}));
  EXPECT_NO_THROW(withLinks("tree.urdf", links + fixed("ab", "a", "b") + fixed("bc", "b", "c") +
                                             fixed("base-a", "base_link", "a"))());
  fs::remove_all(dir);
}

// A copy of the KR6 R700 URDF with a mesh in a ROS package, a box on a link fixed to link_6,
// and a joint to a gripper finger off the chain, in a scratch folder.
class UrdfPackages : public test::Cli {
 protected:
  void SetUp() override {
    Cli::SetUp();
    fs::create_directories(dir_ / "ws/my_robot_description/meshes");
    // A 20 × 20 × 20 mm cube written in millimetres: the URDF scales it by 0.001.
    writeCube(dir_ / "ws/my_robot_description/meshes/cover.stl", 20.0);
    std::string urdf = test::readFile(urdfDir() / "kuka_kr6_r700_sixx.urdf");
    insertAfter(urdf, "<link name=\"link_3\">",
                "<collision><origin xyz=\"0.1 0.02 0.05\" rpy=\"0.3 -0.2 1.1\"/><geometry>"
                "<mesh filename=\"package://my_robot_description/meshes/cover.stl\" "
                "scale=\"0.001 0.001 0.001\"/></geometry></collision>");
    insertAfter(urdf, "<link name=\"tool0\"/>",
                "<link name=\"plate\"><collision><origin xyz=\"0.01 0 0.02\" rpy=\"0 0.4 0\"/>"
                "<geometry><box size=\"0.05 0.04 0.01\"/></geometry></collision></link>"
                "<joint name=\"tool0-plate\" type=\"fixed\"><parent link=\"tool0\"/>"
                "<child link=\"plate\"/><origin xyz=\"0 0 0.03\" rpy=\"0.2 0 0\"/></joint>"
                "<link name=\"finger\"><collision><geometry><sphere radius=\"0.01\"/></geometry>"
                "</collision></link><joint name=\"finger_joint\" type=\"prismatic\">"
                "<parent link=\"plate\"/><child link=\"finger\"/><axis xyz=\"1 0 0\"/>"
                "<limit lower=\"0\" upper=\"0.02\" effort=\"1\" velocity=\"0.1\"/></joint>");
    test::writeFile(dir_ / "robot.urdf", urdf);
  }
  // `robot import` of the scratch URDF into `out`.
  test::Result importRobot(const fs::path& out) {
    fs::create_directories(out.parent_path());
    return scanplan({"robot", "import", (dir_ / "robot.urdf").string(), "-o", out.string(),
                     "--package-path", (dir_ / "ws").string()});
  }
  static void insertAfter(std::string& text, const std::string& at, const std::string& what) {
    const auto k = text.find(at);
    ASSERT_NE(k, std::string::npos) << at;
    text.insert(k + at.size(), what);
  }
  static void writeCube(const fs::path& file, double size) {
    std::string stl = "solid cube\n";
    const double s = size / 2;
    const double v[8][3] = {{-s, -s, -s}, {s, -s, -s}, {s, s, -s}, {-s, s, -s},
                            {-s, -s, s},  {s, -s, s},  {s, s, s},  {-s, s, s}};
    const int f[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                          {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
    for (const auto& t : f) {
      stl += "facet normal 0 0 0\nouter loop\n";
      for (int c : t) stl += fmt::format("vertex {} {} {}\n", v[c][0], v[c][1], v[c][2]);
      stl += "endloop\nendfacet\n";
    }
    test::writeFile(file, stl + "endsolid cube\n");
  }
  config::UrdfRobotSource robot() const {
    config::UrdfRobotSource src;
    src.urdf = dir_ / "robot.urdf";
    src.package_path = {dir_ / "ws"};
    return src;
  }
};

TEST_F(UrdfPackages, PackageUrisResolveAgainstThePackagePathOrTheEnvironment) {
  const config::RobotSpec spec = config::importUrdf(robot()).spec;
  ASSERT_EQ(spec.links[3].shapes.size(), 2u);
  EXPECT_EQ(spec.links[3].shapes[0].file.resolved,
            dir_ / "ws/my_robot_description/meshes/cover.stl");
  config::UrdfRobotSource src = robot();
  src.package_path = {dir_ / "elsewhere", dir_ / "ws/my_robot_description"};  // the package itself
  EXPECT_NO_THROW(config::importUrdf(src));
  src.package_path = {dir_ / "elsewhere"};
  EXPECT_TRUE(test::throwsInputError(
      [&] { config::importUrdf(src); },
      {"robot.urdf", "link 'link_3'", "package://my_robot_description/meshes/cover.stl",
       "package 'my_robot_description' not found", (dir_ / "elsewhere").string()}));
  ::setenv("SCANPLAN_PACKAGE_PATH", ("/nonexistent:" + (dir_ / "ws").string()).c_str(), 1);
  EXPECT_NO_THROW(config::importUrdf(src));
  ::unsetenv("SCANPLAN_PACKAGE_PATH");
  fs::remove(dir_ / "ws/my_robot_description/meshes/cover.stl");
  EXPECT_TRUE(test::throwsInputError(
      [&] { config::importUrdf(robot()); },
      {"package 'my_robot_description' is", "but it has no file", "meshes/cover.stl"}));
}

// A package:// mesh path is inside its package: one that climbs out of it ('..' past the
// package folder, an absolute path after the name, '..' as the name) is refused naming the URDF,
// the link, the URI and its normal form, even where a file lies there. '..' that stays inside,
// and a path relative to the URDF (ROS's urdf/ beside meshes/), are fine.
TEST_F(UrdfPackages, AMeshPathLeavingItsPackageIsRefused) {
  writeCube(dir_ / "ws/outside.stl", 20.0);
  const std::string text = test::readFile(dir_ / "robot.urdf");
  const std::string uri = "package://my_robot_description/meshes/cover.stl";
  const auto importWith = [&](const std::string& mesh, const fs::path& file) {
    std::string edited = text;
    test::writeFile(file, edited.replace(edited.find(uri), uri.size(), mesh));
    config::UrdfRobotSource src = robot();
    src.urdf = file;
    return [src] { config::importUrdf(src); };
  };
  const fs::path leaves = dir_ / "leaves.urdf";
  EXPECT_TRUE(test::throwsInputError(
      importWith("package://my_robot_description/meshes/../../outside.stl", leaves),
      {"leaves.urdf", "link 'link_3'",
       "mesh 'package://my_robot_description/meshes/../../outside.stl'",
       "the path 'meshes/../../outside.stl' leaves package 'my_robot_description' (normalised: "
       "'../outside.stl')",
       "expected a file inside the package"}));
  const std::string absolute = (dir_ / "ws/outside.stl").string();
  EXPECT_TRUE(test::throwsInputError(
      importWith("package://my_robot_description/" + absolute, leaves),
      {"leaves.urdf", "the path '" + absolute + "' leaves package 'my_robot_description'"}));
  EXPECT_TRUE(test::throwsInputError(importWith("package://../ws/outside.stl", leaves),
                                     {"leaves.urdf", "package name '..'"}));
  EXPECT_NO_THROW(importWith("package://my_robot_description/meshes/../meshes/cover.stl",
                             dir_ / "inside.urdf")());
  fs::create_directories(dir_ / "urdf");
  EXPECT_NO_THROW(
      importWith("../ws/my_robot_description/meshes/cover.stl", dir_ / "urdf/robot.urdf")());
}

TEST_F(UrdfPackages, EveryCollisionElementSitsWhereTheUrdfPutsItAtAnyPose) {
  const config::RobotSpec spec = config::importUrdf(robot()).spec;
  const kinematics::RobotModel model = build(spec);
  const UrdfTree tree(dir_ / "robot.urdf", "base_link", "tool0");
  std::mt19937 rng(11);
  for (int k = 0; k < 50; ++k) {
    const JointVector q = test::randomJoints(model, rng);
    const auto frames = model.linkFrames(q);
    const auto links = tree.linkPoses(q);
    std::size_t matched = 0, elements = 0;
    for (const auto& [name, X_BL] : links) {
      if (name == "finger") continue;  // moved by a joint off the chain: left out
      for (const auto& c : tree.model().getLink(name)->collision_array) {
        ++elements;
        const Eigen::Isometry3d want = X_BL * pose(c->origin);
        for (std::size_t b = 0; b < spec.links.size(); ++b) {
          for (const config::ShapeSpec& shape : spec.links[b].shapes) {
            if (sameFrame(frames[b] * config::toIsometry(shape.pose), want)) ++matched;
          }
        }
      }
    }
    EXPECT_EQ(elements, 10u);  // the 8 authored, the mesh, the plate's box
    ASSERT_EQ(matched, elements) << "q " << q.transpose();
  }
  // Geometry kinds carried over: the box and mesh with their sizes and scale.
  EXPECT_EQ(spec.links[6].shapes.back().type, "box");
  EXPECT_EQ(spec.links[6].shapes.back().size_mm, (std::array<double, 3>{50, 40, 10}));
  EXPECT_EQ(spec.links[3].shapes[0].type, "mesh");
  EXPECT_EQ(spec.links[3].shapes[0].scale, 0.001);
  EXPECT_EQ(spec.links[3].shapes[0].units, "m");
}

TEST_F(UrdfPackages, HostileUrdfsAreInputErrorsNamingWhatIsWrong) {
  const std::string good = test::readFile(urdfDir() / "kuka_kr6_r700_sixx.urdf");
  const std::pair<std::string, std::string> cases[][2] = {
      {{"origin xyz=\"0.315 0 0\"", "origin xyz=\"nan 0 0\""}, {"not a valid URDF", "nan"}},
      {{"origin xyz=\"0.315 0 0\"", "origin xyz=\"1e200 0 0\""},
       {"not a valid robot file", "expected a number within"}},
      {{"<cylinder radius=\"0.06\"", "<cylinder radius=\"-1\""},
       {"link 'link_3' <collision>: cylinder radius -1", "expected a finite number > 0"}},
      {{"axis xyz=\"0 1 0\"", "axis xyz=\"0 0 0\""}, {"J2 (joint_a2): axis (0, 0, 0)", ""}},
      {{"velocity=\"5.235987755982989\"", "velocity=\"0\""},
       {"joint 'joint_a2': <limit velocity=\"0\">", ""}},
      {{"<robot name", "<robt name"}, {"not a valid URDF", ""}},
      {{"type=\"revolute\">\n    <parent link=\"link_3\"/>",
        "type=\"prismatic\">\n    <parent link=\"link_3\"/>"},
       {"joint 'joint_a4' is prismatic", ""}},
  };
  for (const auto& [edit, expected] : cases) {
    std::string text = good;
    const auto k = text.find(edit.first);
    ASSERT_NE(k, std::string::npos) << edit.first;
    text.replace(k, edit.first.size(), edit.second);
    test::writeFile(dir_ / "hostile.urdf", text);
    config::UrdfRobotSource src;
    src.urdf = dir_ / "hostile.urdf";
    EXPECT_TRUE(
        test::throwsInputError([&] { config::importUrdf(src); }, {"hostile.urdf", expected.first}))
        << edit.second;
    if (!expected.second.empty()) {
      EXPECT_TRUE(test::throwsInputError([&] { config::importUrdf(src); }, {expected.second}));
    }
  }
}

TEST_F(UrdfPackages, RobotImportWritesARobotFileWithTheSameModel) {
  for (const std::string name : {"viper_s650", "abb_irb2400", "fanuc_lrmate200id", "robot"}) {
    const fs::path urdf = name == "robot" ? dir_ / "robot.urdf" : urdfDir() / (name + ".urdf");
    const fs::path out = dir_ / "out" / (name + ".yaml");
    fs::create_directories(out.parent_path());
    const test::Result run =
        scanplan({"robot", "import", urdf.string(), "-o", out.string(), "--package-path",
                  (dir_ / "ws").string(), "--controller", "abb_rapid"});
    ASSERT_EQ(run.exit_code, 0) << test::describe(run);
    EXPECT_TRUE(test::contains(run.out, "wrote")) << run.out;
    const config::RobotSpec file = config::loadRobotFile(out);
    EXPECT_EQ(file.controller, "abb_rapid");
    const kinematics::RobotModel a = build(file);
    config::UrdfRobotSource src;
    src.urdf = urdf;
    src.package_path = {dir_ / "ws"};
    const config::RobotSpec direct = config::importUrdf(src).spec;
    const kinematics::RobotModel b = build(direct);
    std::mt19937 rng(4);
    for (int k = 0; k < 200; ++k) {
      const JointVector q = test::randomJoints(a, rng);
      ASSERT_TRUE(sameFrame(a.fk(q), b.fk(q)));
      const auto fa = a.linkFrames(q);
      for (std::size_t i = 0; i < file.links.size(); ++i) {
        ASSERT_EQ(file.links[i].shapes.size(), direct.links[i].shapes.size());
        for (std::size_t j = 0; j < file.links[i].shapes.size(); ++j) {
          ASSERT_TRUE(sameFrame(fa[i] * config::toIsometry(file.links[i].shapes[j].pose),
                                fa[i] * config::toIsometry(direct.links[i].shapes[j].pose)));
        }
      }
    }
    if (name == "robot") {  // the mesh path, relative to the robot file, reads back
      EXPECT_EQ(file.links[3].shapes[0].file.resolved,
                dir_ / "ws/my_robot_description/meshes/cover.stl");
    }
  }
  const test::Result bad =
      scanplan({"robot", "import", (test::sourceDir() / "tests/urdf/ur5.urdf").string(), "-o",
                (dir_ / "ur5.yaml").string()});
  EXPECT_EQ(bad.exit_code, 4) << test::describe(bad);
  EXPECT_TRUE(test::contains(bad.err, "is not perpendicular to J3")) << bad.err;
  EXPECT_FALSE(fs::exists(dir_ / "ur5.yaml"));
}

// A mesh link's stand-in, reported by `robot import` and `robot check`: link 3 carries a 20 mm
// cube as a mesh. A cube is convex: its hull is the cube itself, so the maps measure the hull,
// at most the branch and bound's 0.5 mm out, with the cube's 8 corners at most.
TEST_F(UrdfPackages, RobotImportAndCheckReportWhatTheMapsMeasureForAMeshLink) {
  const fs::path out = dir_ / "out" / "robot.yaml";
  const test::Result run = importRobot(out);
  ASSERT_EQ(run.exit_code, 0) << test::describe(run);
  EXPECT_TRUE(test::contains(run.out, "link mesh  convex stand-ins")) << run.out;
  EXPECT_TRUE(test::contains(run.out, "mesh 12 triangles")) << run.out;
  EXPECT_TRUE(test::contains(run.out, "the maps measure the hull")) << run.out;
  const test::Result check =
      scanplan({"robot", "check", out.string(), "--samples", "20", "--json"});
  ASSERT_EQ(check.exit_code, 0) << test::describe(check);
  const nlohmann::json doc = nlohmann::json::parse(check.out);
  ASSERT_TRUE(doc.contains("link_meshes")) << check.out;
  ASSERT_EQ(doc["link_meshes"].size(), 1u) << check.out;
  const nlohmann::json& link = doc["link_meshes"][0];
  EXPECT_EQ(link["mesh_triangles"], 12);
  EXPECT_EQ(link["maps_measure"], "hull");
  EXPECT_LE(link["hull_vertices"].get<int>(), 8);
  EXPECT_GE(link["hull_margin_mm"].get<double>(), 0.0);
  EXPECT_LE(link["hull_margin_mm"].get<double>(), 0.5);
  // The text form says the same, after the survey.
  const test::Result text = scanplan({"robot", "check", out.string(), "--samples", "20"});
  ASSERT_EQ(text.exit_code, 0) << test::describe(text);
  EXPECT_TRUE(test::contains(text.out, "the maps measure the hull")) << text.out;
}

// The hand-written demo (two of its rings, or `whole`: its three rings and the raster; every
// 0.2 s, no simulation) with the robot swapped.
pipeline::ScanPlan planDemo(const std::vector<std::string>& robot_overrides, bool whole = false) {
  std::vector<std::string> overrides =
      whole ? std::vector<std::string>{"scan.dt_s=0.2"} : test::kLightDemo;
  overrides.push_back("simulation.enabled=false");
  overrides.insert(overrides.end(), robot_overrides.begin(), robot_overrides.end());
  const config::JobSpec job =
      config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", overrides);
  return pipeline::planScan(config::toProblem(job));
}

struct DemoCase {
  std::string name;
  std::vector<std::string> overrides;
};

class VendorArmPlansTheDemo : public ::testing::TestWithParam<DemoCase> {};

TEST_P(VendorArmPlansTheDemo, WithAValidTrajectory) {
  const pipeline::ScanPlan plan = planDemo(GetParam().overrides);
  ASSERT_TRUE(plan.planned()) << plan.reason;
  ASSERT_TRUE(plan.validation);
  EXPECT_TRUE(plan.validation->valid);
}

// The KR6 R700 and the LR Mate reach the demo's table where it is (520 mm out); the IRB 2400,
// twice their size, has its table 1.1 m out and 0.5 m up, where its wrist reaches it from above.
INSTANTIATE_TEST_SUITE_P(
    Urdf,
    VendorArmPlansTheDemo,
    ::testing::Values(
        DemoCase{"kuka_kr6_r700_sixx", {"robot=../robots/urdf/kuka_kr6_r700_sixx.urdf"}},
        DemoCase{"fanuc_lrmate200id", {"robot=../robots/urdf/fanuc_lrmate200id.urdf"}},
        DemoCase{"abb_irb2400",
                 {"robot={urdf: ../robots/urdf/abb_irb2400.urdf, opw_parameters: "
                  "../robots/urdf/abb_irb2400_opw.yaml, controller: abb_rapid}",
                  "table.axis.xyz_mm=[1100,0,500]"}}),
    [](const auto& param_info) { return param_info.param.name; });

// Joint wrap: with its table 0.9 m out at floor level, the whole hand-written
// demo (three rings and the raster) needs the IRB 2400's J4 past ±180° (it turns ±200°). Before
// joint wrap no branch could be executed ("joint 4 would have to pass its limit (-200 … 200
// deg)"); now J4 is followed continuously, the planner replans the branches whose J4 would leave
// ±200° on their joint-wrap sheets (planner::WrapSheets), and the plan is valid: on a sheet the
// planner finds a table path that keeps J4 in a window of one turn.
TEST(Urdf, Irb2400WithItsTableCloseCrossesJ4Past180) {
  const pipeline::ScanPlan plan =
      planDemo({"robot=../robots/urdf/abb_irb2400.urdf", "table.axis.xyz_mm=[900,0,0]"}, true);
  ASSERT_TRUE(plan.planned()) << plan.reason;
  ASSERT_TRUE(plan.validation);
  EXPECT_TRUE(plan.validation->valid);
  const auto& samples = plan.trajectory->trajectory.samples;
  const kinematics::RobotModel& robot = plan.prepared->scene->cell().robot;
  double lo = 0.0, hi = 0.0, step = 0.0;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    EXPECT_TRUE(robot.withinLimits(samples[k].q)) << k;
    lo = std::min(lo, samples[k].q(3));
    hi = std::max(hi, samples[k].q(3));
    if (k > 0) step = std::max(step, std::abs(samples[k].q(3) - samples[k - 1].q(3)));
  }
  EXPECT_LT(step, deg(30.0)) << "J4 jumps";
  std::printf("IRB 2400, table 0.9 m out: %s; J4 %.1f … %.1f deg, largest step %.2f deg\n",
              plan.choice.why_chosen.c_str(), toDeg(lo), toDeg(hi), toDeg(step));
}

// What the maps measure for a mesh link, drawn over it: the replay (and cell.png) get a stand-in
// body per mesh link the maps measure as a hull or pieces, in the link's frame, a colour per
// piece. It holds the link's mesh (every mesh vertex inside a piece) and stands at most the
// reported margin outside it (every stand-in vertex that near a mesh vertex: the cube's hull is
// its corners).
TEST_F(UrdfPackages, TheReplayShowsWhatTheMapsMeasureOverAMeshLink) {
  const fs::path out = dir_ / "out" / "robot.yaml";
  const test::Result run = importRobot(out);
  ASSERT_EQ(run.exit_code, 0) << test::describe(run);
  std::vector<std::string> overrides = test::kLightDemo;
  overrides.push_back("simulation.enabled=false");
  overrides.push_back("robot=" + out.string());
  const pipeline::ScanProblem problem = config::toProblem(
      config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", overrides));
  const pipeline::ScanPlan plan = pipeline::planScan(problem);
  ASSERT_TRUE(plan.planned()) << plan.reason;
  const pipeline::ReplayScene scene = pipeline::replayScene(problem.cell, problem.part, plan);
  const auto& hulls = plan.prepared->scene->mapHulls();
  ASSERT_EQ(hulls.size(), 1u);
  std::vector<const pipeline::ReplayBody*> standins;
  for (const pipeline::ReplayBody& b : scene.bodies)
    if (b.standin) standins.push_back(&b);
  ASSERT_EQ(standins.size(), 1u);
  const pipeline::ReplayBody& body = *standins.front();
  ASSERT_EQ(body.frame, 3);
  EXPECT_EQ(body.colours.size(), body.mesh.triangles.size());
  // The link's mesh in its frame, from the robot file's shapes.
  kinematics::TriangleMesh mesh;
  for (const kinematics::Shape& shape : problem.cell.robot.definition().links[3].shapes) {
    if (!std::holds_alternative<kinematics::MeshFile>(shape.geometry)) continue;
    mesh = kinematics::shapeSurface(shape);
  }
  ASSERT_EQ(mesh.triangles.size(), 12u);
  for (const Eigen::Vector3d& v : mesh.vertices) {  // inside the (one, convex) piece
    for (const Eigen::Vector3i& t : body.mesh.triangles) {
      const Eigen::Vector3d& a = body.mesh.vertices[static_cast<std::size_t>(t[0])];
      const Eigen::Vector3d n = (body.mesh.vertices[static_cast<std::size_t>(t[1])] - a)
                                    .cross(body.mesh.vertices[static_cast<std::size_t>(t[2])] - a)
                                    .normalized();
      EXPECT_LE(n.dot(v - a), 1e-9) << "a mesh vertex outside the stand-in";
    }
  }
  for (const Eigen::Vector3d& w : body.mesh.vertices) {
    double nearest = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& v : mesh.vertices) nearest = std::min(nearest, (v - w).norm());
    EXPECT_LE(nearest, hulls.front().margin + 1e-9);
  }
}

}  // namespace
}  // namespace scanplan
