#include <scanplan/config/spec.h>

#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/units.h>

namespace scanplan::config {

Eigen::Isometry3d toIsometry(const PoseSpec& pose) {
  const Eigen::Vector3d xyz = Eigen::Vector3d(pose.xyz_mm.data()) * kMmToM;
  const Eigen::Vector3d rpy = Eigen::Vector3d(pose.rpy_deg.data()) * kDegToRad;
  return kinematics::poseFromXyzRpy(xyz, rpy);
}

PoseSpec toPoseSpec(const Eigen::Isometry3d& X) {
  PoseSpec s;
  const Eigen::Vector3d rpy = kinematics::rpyFromRotation(X.linear());
  for (int i = 0; i < 3; ++i) {
    const auto k = static_cast<std::size_t>(i);
    s.xyz_mm[k] = toMm(X.translation()(i));
    s.rpy_deg[k] = toDeg(rpy(i));
  }
  return s;
}

kinematics::LengthUnit toLengthUnit(const std::string& units) {
  return units == "m" ? kinematics::LengthUnit::kMetre : kinematics::LengthUnit::kMillimetre;
}

kinematics::Shape toShape(const ShapeSpec& spec) {
  using namespace kinematics;
  Shape shape;
  shape.X_BG = toIsometry(spec.pose);
  if (spec.type == "box") {
    shape.geometry = Box{Eigen::Vector3d(spec.size_mm.data()) * kMmToM};
  } else if (spec.type == "sphere") {
    shape.geometry = Sphere{mm(spec.radius_mm)};
  } else if (spec.type == "cylinder" || spec.type == "capsule") {
    double length = mm(spec.length_mm);
    if (spec.by_end_points) {
      // Frame at the midpoint, z along from → to.
      const Eigen::Vector3d from = Eigen::Vector3d(spec.from_mm.data()) * kMmToM;
      const Eigen::Vector3d to = Eigen::Vector3d(spec.to_mm.data()) * kMmToM;
      length = (to - from).norm();
      shape.X_BG = Eigen::Isometry3d::Identity();
      shape.X_BG.translation() = 0.5 * (from + to);
      if (length > 0.0) {
        shape.X_BG.linear() =
            Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), to - from)
                .toRotationMatrix();
      }
    }
    if (spec.type == "cylinder") {
      shape.geometry = Cylinder{mm(spec.radius_mm), length};
    } else {
      shape.geometry = Capsule{mm(spec.radius_mm), length};
    }
  } else {
    shape.geometry = MeshFile{spec.file.resolved, {toLengthUnit(spec.units), spec.scale}};
  }
  return shape;
}

}  // namespace scanplan::config
