#include "kinematics/shape.h"

namespace scanplan::kinematics {

std::string shapeKindName(const ShapeGeometry& geometry) {
  struct Namer {
    std::string operator()(const Box&) const { return "box"; }
    std::string operator()(const Sphere&) const { return "sphere"; }
    std::string operator()(const Cylinder&) const { return "cylinder"; }
    std::string operator()(const Capsule&) const { return "capsule"; }
    std::string operator()(const MeshFile&) const { return "mesh"; }
  };
  return std::visit(Namer{}, geometry);
}

}  // namespace scanplan::kinematics
