#include "collision/chain_levers.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "collision/fcl_geometry.h"

namespace scanplan::collision {
namespace {

using detail::Primitive;

// A body's shapes as primitives in its link's DH frame (a mesh as its bounding box).
std::vector<Primitive> linkPrimitives(const Scene& scene, std::size_t body) {
  const Eigen::Isometry3d X_link_body = scene.bodies()[body].motion == BodyMotion::kScanner
                                            ? scene.cell().scanner.X_FS
                                            : Eigen::Isometry3d::Identity();
  std::vector<Primitive> out;
  for (const detail::CollisionShape& s : scene.geometry().bodies[body].shapes) {
    Primitive p = s.primitive ? *s.primitive : *s.bounding_box;
    p.X_W = X_link_body * s.X_BG * p.X_W;
    out.push_back(p);
  }
  return out;
}

// The points that span a primitive when padded by the returned radius: a capsule's or
// cylinder's axis ends, a box's corners.
std::vector<Eigen::Vector3d> spanPoints(const Primitive& p, double& pad) {
  if (p.kind != Primitive::Kind::kBox) {
    pad = p.radius();
    return {p.end(-1.0), p.end(1.0)};
  }
  pad = 0.0;
  std::vector<Eigen::Vector3d> corners;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d s((i & 1) ? 1.0 : -1.0, (i & 2) ? 1.0 : -1.0, (i & 4) ? 1.0 : -1.0);
    corners.push_back(p.X_W * s.cwiseProduct(p.half));
  }
  return corners;
}

// The farthest any point of the shapes is from the line (point o, unit direction u); a capsule
// or cylinder on the line turns into itself about it and counts 0.
double reachFromLine(const std::vector<Primitive>& shapes,
                     const Eigen::Vector3d& o,
                     const Eigen::Vector3d& u) {
  double reach = 0.0;
  for (const Primitive& p : shapes) {
    double pad = 0.0;
    double far = 0.0;
    for (const Eigen::Vector3d& x : spanPoints(p, pad)) {
      const Eigen::Vector3d v = x - o;
      far = std::max(far, (v - v.dot(u) * u).norm());
    }
    const bool on_axis = p.kind != Primitive::Kind::kBox && far < 1e-12;
    if (!on_axis) reach = std::max(reach, far + pad);
  }
  return reach;
}

// The farthest any point of the shapes is from the point o.
double reachFromPoint(const std::vector<Primitive>& shapes, const Eigen::Vector3d& o) {
  double reach = 0.0;
  for (const Primitive& p : shapes) {
    double pad = 0.0;
    double far = 0.0;
    for (const Eigen::Vector3d& x : spanPoints(p, pad)) far = std::max(far, (x - o).norm());
    reach = std::max(reach, far + pad);
  }
  return reach;
}

// Distance between the origins of DH frames `from` < `to`, bounded over every configuration.
double chainLength(const kinematics::RobotModel& robot, int from, int to) {
  double length = 0.0;
  for (int m = from + 1; m <= to; ++m)
    length += std::hypot(robot.joint(m - 1).a, robot.joint(m - 1).d);
  return length;
}

// ρ of a body on link j about joint k's axis (z_{k−1}), bounded over every configuration.
double lever(const kinematics::RobotModel& robot,
             const std::vector<Primitive>& shapes,
             int j,
             int k) {
  const Eigen::Vector3d origin = Eigen::Vector3d::Zero(), z = Eigen::Vector3d::UnitZ();
  if (j == k - 1) return reachFromLine(shapes, origin, z);  // the axis is the frame's own z
  if (j < k) return reachFromPoint(shapes, origin) + chainLength(robot, j, k - 1);
  const kinematics::DhJoint& dh = robot.joint(k - 1);
  if (j == k) {  // z_{k−1} seen from frame k
    const Eigen::Isometry3d M = Eigen::Translation3d(dh.a, 0.0, dh.d) *
                                Eigen::AngleAxisd(dh.alpha, Eigen::Vector3d::UnitX());
    const Eigen::Isometry3d M_inv = M.inverse();
    return reachFromLine(shapes, M_inv.translation(), M_inv.linear().col(2));
  }
  return std::abs(dh.a) + chainLength(robot, k, j) + reachFromPoint(shapes, origin);
}

bool carried(BodyMotion motion) {
  return motion == BodyMotion::kRobotLink || motion == BodyMotion::kScanner;
}

}  // namespace

ChainLevers::ChainLevers(const Scene& scene) {
  const kinematics::RobotModel& robot = scene.cell().robot;
  for (const PairInfo& pair : scene.pairs()) {
    auto a = static_cast<std::size_t>(pair.a), b = static_cast<std::size_t>(pair.b);
    const BodyInfo *ia = &scene.bodies()[a], *ib = &scene.bodies()[b];
    Weights w{};
    const bool both = carried(ia->motion) && carried(ib->motion);
    if (both) {
      if (ia->link > ib->link) {
        std::swap(a, b);
        std::swap(ia, ib);
      }
      const std::vector<Primitive> before = linkPrimitives(scene, a),
                                   after = linkPrimitives(scene, b);
      for (int k = ia->link + 1; k <= ib->link; ++k) {
        w[static_cast<std::size_t>(k - 1)] =
            std::min(lever(robot, before, ia->link, k), lever(robot, after, ib->link, k));
      }
    }
    together_.push_back(both);
    weights_.push_back(w);
  }
}

double ChainLevers::relativeMotion(std::size_t pair,
                                   const kinematics::JointVector& q0,
                                   const kinematics::JointVector& q1) const {
  constexpr double kTurn = 2.0 * std::numbers::pi;
  const Weights& w = weights_[pair];
  double motion = 0.0;
  for (int k = 0; k < kinematics::kNumJoints; ++k) {
    const double weight = w[static_cast<std::size_t>(k)];
    if (weight == 0.0) continue;
    double turn = std::fmod(std::abs(q1(k) - q0(k)), kTurn);
    turn = std::min(turn, kTurn - turn);
    motion += weight * turn;
  }
  return motion;
}

}  // namespace scanplan::collision
