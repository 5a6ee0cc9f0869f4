#pragma once
// Robots from URDF (docs/design.md §12): the chain base_link → tip_link of a URDF file, read with
// urdfdom, becomes the same RobotSpec a robot file gives (DH rows, OPW parameters, link shapes),
// so everything downstream is unchanged. urdfdom stays inside this file's .cpp.

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include <scanplan/config/robot_file.h>

namespace scanplan::config {

/// Where a robot comes from when it is a URDF: a job's `robot: {urdf: …}` (or `robot: x.urdf`)
/// and `scanplan robot import`.
struct UrdfRobotSource {
  std::filesystem::path urdf;
  std::string base_link = "base_link";  ///< DH frame 0: z along J1, origin on it
  std::string tip_link = "tool0";       ///< the flange (DH frame 6): z along J6, origin on it
  /// Folders searched for `package://PKG/…` (each holding a folder PKG, or being PKG), before
  /// those of the environment variable SCANPLAN_PACKAGE_PATH.
  std::vector<std::filesystem::path> package_path;
  /// A ROS-Industrial opw_kinematics parameter file (m, rad) to use for the IK, checked against
  /// the chain; empty: the parameters are derived from the chain.
  std::filesystem::path opw_parameters;
  std::string name;                 ///< empty: the URDF's robot name
  std::string controller = "none";  ///< one of kControllers
};

/// A URDF robot as a robot file, and which URDF links went into each body.
struct UrdfRobot {
  RobotSpec spec;
  std::array<std::vector<std::string>, kinematics::kNumJoints + 1> body_links;
};

/// The robot file equivalent to the URDF: kinematics from the revolute joints between base_link
/// and tip_link (six; fixed joints folded in; origins, axes, limits, velocities), OPW parameters
/// derived from the chain (or the opw file's, checked against it), and the `<collision>`
/// geometry of every link fixed to a body of the chain, in that body's DH frame. Bodies are named
/// `base`, `link1` … `link6` (what jobs' clearance rules name). Throws InputError naming the
/// file, the element and the value: a missing link, a joint that is not revolute, an arm that is
/// not ortho-parallel (which condition, by how much), a package or mesh not found (with the
/// folders searched), a `<mimic>` joint on the chain, a closed chain (a link the child of two
/// joints, or its own ancestor), a `package://` mesh path leaving its package.
UrdfRobot importUrdf(const UrdfRobotSource& source);

/// `explicit_paths`, then the folders of SCANPLAN_PACKAGE_PATH (colon-separated).
std::vector<std::filesystem::path> packageSearchPath(
    const std::vector<std::filesystem::path>& explicit_paths);

/// A URDF mesh `filename`: `package://PKG/REST` (PKG/REST under a folder of `search`, or REST in
/// a folder of `search` named PKG), `file://PATH`, or a path (relative to `urdf_dir`). Throws
/// InputError naming the URI and the folders searched when the package or the file is missing,
/// and naming the URI and its normal form when REST leaves the package (`..` past PKG, or an
/// absolute path).
std::filesystem::path resolveUrdfUri(const std::string& uri,
                                     const std::filesystem::path& urdf_dir,
                                     const std::vector<std::filesystem::path>& search);

/// Is `file` a URDF by its name (`.urdf`, any case)?
bool isUrdfFile(const std::filesystem::path& file);

/// A robot file, or a URDF (by its name) with the default base_link and tip_link.
RobotSpec loadRobotOrUrdf(const std::filesystem::path& file);

}  // namespace scanplan::config
