// Robot files and the arm's kinematics: load_robot() and Robot.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <scanplan/config/robot_file.h>
#include <scanplan/config/robot_urdf.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/robot_model.h>

#include "python/bindings.h"
#include "python/objects.h"

namespace py = pybind11;

namespace scanplan::python {

namespace {

Robot loadRobot(const std::filesystem::path& file) {
  const config::RobotSpec spec = config::loadRobotOrUrdf(file);
  return Robot{
      std::make_shared<const kinematics::RobotModel>(config::buildRobotModel(spec, file.string()))};
}

kinematics::JointVector jointsOf(const Eigen::VectorXd& q) {
  if (q.size() != kinematics::kNumJoints || !q.allFinite()) {
    throw InputError("q: expected 6 finite joint values (rad)");
  }
  return q;
}

Eigen::Isometry3d poseOf(const Eigen::Matrix4d& T) {
  const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
  const bool rigid = T.allFinite() && T.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1)) &&
                     (R * R.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-9) &&
                     R.determinant() > 0.0;
  if (!rigid) throw InputError("T: expected a 4x4 rigid transform (rotation and translation, m)");
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.matrix() = T;
  return X;
}

// The joints' values as (6,) arrays of one DhJoint field.
template <class Field>
Eigen::VectorXd jointField(const Robot& r, Field field) {
  Eigen::VectorXd v(kinematics::kNumJoints);
  for (int i = 0; i < kinematics::kNumJoints; ++i) v[i] = r.model->joint(i).*field;
  return v;
}

}  // namespace

void bindRobot(py::module_& m) {
  py::class_<Robot>(m, "Robot", "A 6-axis arm (kinematics::RobotModel): DH chain, analytic IK.")
      .def_property_readonly("name", [](const Robot& r) { return r.model->name(); })
      .def_property_readonly(
          "lower", [](const Robot& r) { return jointField(r, &kinematics::DhJoint::min); },
          "(6,) joint lower limits, rad.")
      .def_property_readonly(
          "upper", [](const Robot& r) { return jointField(r, &kinematics::DhJoint::max); },
          "(6,) joint upper limits, rad.")
      .def_property_readonly(
          "max_speed",
          [](const Robot& r) { return jointField(r, &kinematics::DhJoint::max_speed); },
          "(6,) joint speed limits, rad/s.")
      .def(
          "fk",
          [](const Robot& r, const Eigen::VectorXd& q) {
            return Eigen::Matrix4d(r.model->fk(jointsOf(q)).matrix());
          },
          py::arg("q"), "The flange pose X_BF (4x4, base frame, m) at joints q (6,), rad.")
      .def(
          "ik",
          [](const Robot& r, const Eigen::Matrix4d& T, bool within_limits) {
            kinematics::IkRequest request;
            request.within_limits_only = within_limits;
            const std::vector<kinematics::IkSolution> solutions = r.model->ik(poseOf(T), request);
            Eigen::MatrixXd q(static_cast<Eigen::Index>(solutions.size()), kinematics::kNumJoints);
            for (std::size_t k = 0; k < solutions.size(); ++k)
              q.row(static_cast<Eigen::Index>(k)) = solutions[k].q.transpose();
            return q;
          },
          py::arg("T"), py::arg("within_limits") = false,
          "Every joint solution (k, 6), rad, that puts the flange at T (4x4, base frame, m): up "
          "to 8 branches, with the whole-turn variants of joints whose range exceeds 2 pi. Empty "
          "(0, 6) when T is out of reach.")
      .def(
          "branch_of",
          [](const Robot& r, const Eigen::VectorXd& q) {
            return r.model->branchOf(jointsOf(q)).words();
          },
          py::arg("q"), "The IK branch of joints q, in V+ words ('RIGHTY ABOVE NOFLIP').");
  m.def("load_robot", &loadRobot, py::arg("path"),
        "Reads a robot file (.yaml) or a URDF (.urdf), as a job's `robot:` does.");
}

}  // namespace scanplan::python
