#include <scanplan/collision/chain_levers.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <utility>
#include <vector>

#include <scanplan/collision/fcl_geometry.h>

namespace scanplan::collision {
namespace {

using detail::Primitive;

struct Line {
  Eigen::Vector3d o = Eigen::Vector3d::Zero(), u = Eigen::Vector3d::UnitZ();
  double distance(const Eigen::Vector3d& x) const {
    const Eigen::Vector3d v = x - o;
    return (v - v.dot(u) * u).norm();
  }
};

// One body of a pair as the levers see it: its link (world and table bodies count as link 0)
// and its shapes as primitives (a mesh as its bounding box), a convex polytope as its vertices,
// in that link's DH frame; a table body's at θ = 0, with the table axis to sweep them about.
struct Side {
  int link = 0;
  std::vector<Primitive> shapes;
  std::vector<Eigen::Vector3d> points;  ///< convex polytopes' vertices: their hull is the shape
  std::optional<Line> table_axis;
};

Side sideOf(const Scene& scene, std::size_t body) {
  const kinematics::CellModel& cell = scene.cell();
  const Eigen::Isometry3d X_BW = cell.X_WB.inverse();
  Side side;
  Eigen::Isometry3d X_link_body = Eigen::Isometry3d::Identity();
  switch (scene.bodies()[body].motion) {
    case BodyMotion::kRobotLink:
      side.link = scene.bodies()[body].link;
      break;
    case BodyMotion::kScanner:
      side.link = kinematics::kNumJoints;
      X_link_body = cell.scanner.X_FS;
      break;
    case BodyMotion::kWorld:
      X_link_body = X_BW;
      break;
    case BodyMotion::kTable: {
      X_link_body = X_BW * cell.table.X_WR(0.0);
      const Eigen::Isometry3d X_BA = X_BW * cell.table.X_WA;
      side.table_axis = Line{X_BA.translation(), X_BA.linear().col(2)};
      break;
    }
  }
  for (const detail::CollisionShape& s : scene.geometry().map_bodies[body].shapes) {
    if (s.geometry->getNodeType() == fcl::GEOM_CONVEX) {  // a point's reach is convex in it
      for (const Eigen::Vector3d& v : static_cast<const fcl::Convexd&>(*s.geometry).getVertices())
        side.points.push_back(X_link_body * s.X_BG * v);
      continue;
    }
    Primitive p = s.primitive ? *s.primitive : *s.bounding_box;
    p.X_W = X_link_body * s.X_BG * p.X_W;
    side.shapes.push_back(p);
  }
  return side;
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

// The farthest the side's points get by `measure` (of a point); a table body's over every
// table angle: each point sweeps a circle about the axis, within its radius of the centre.
// `on_axis`: a capsule or cylinder whose ends all measure 0 turns into itself and counts 0.
template <class Measure>
double reach(const Side& side, Measure&& measure, bool on_axis_is_still) {
  const auto farthest = [&](const Eigen::Vector3d& x) {
    if (!side.table_axis) return measure(x);
    const Line& axis = *side.table_axis;
    const Eigen::Vector3d centre = axis.o + (x - axis.o).dot(axis.u) * axis.u;
    return measure(centre) + (x - centre).norm();
  };
  double out = 0.0;
  for (const Primitive& p : side.shapes) {
    double pad = 0.0, far = 0.0;
    for (const Eigen::Vector3d& x : spanPoints(p, pad)) far = std::max(far, farthest(x));
    const bool still =
        on_axis_is_still && !side.table_axis && p.kind != Primitive::Kind::kBox && far < 1e-12;
    if (!still) out = std::max(out, far + pad);
  }
  // A polytope's points reach no farther than its vertices (a distance from a line, from a
  // point, and the table's sweep are convex).
  for (const Eigen::Vector3d& x : side.points) out = std::max(out, farthest(x));
  return out;
}

double reachFromLine(const Side& side, const Line& line) {
  return reach(
      side, [&](const Eigen::Vector3d& x) { return line.distance(x); }, true);
}

double reachFromOrigin(const Side& side) {
  return reach(
      side, [](const Eigen::Vector3d& x) { return x.norm(); }, false);
}

// Distance between the origins of DH frames `from` < `to`, bounded over every configuration.
double chainLength(const kinematics::RobotModel& robot, int from, int to) {
  double length = 0.0;
  for (int m = from + 1; m <= to; ++m) {
    length += std::hypot(robot.joint(m - 1).a, robot.joint(m - 1).d);
  }
  return length;
}

// ρ of a side about joint k's axis (z_{k−1}), bounded over every configuration.
double lever(const kinematics::RobotModel& robot, const Side& side, int k) {
  const int j = side.link;
  if (j == k - 1) return reachFromLine(side, Line{});  // the axis is the frame's own z
  if (j < k) return reachFromOrigin(side) + chainLength(robot, j, k - 1);
  const kinematics::DhJoint& dh = robot.joint(k - 1);
  if (j == k) {  // z_{k−1} seen from frame k
    const auto [o, u] = detail::ownJointAxis(robot, k);
    return reachFromLine(side, Line{o, u});
  }
  return std::abs(dh.a) + chainLength(robot, k, j) + reachFromOrigin(side);
}

}  // namespace

std::pair<Eigen::Vector3d, Eigen::Vector3d> detail::ownJointAxis(
    const kinematics::RobotModel& robot, int k) {
  const kinematics::DhJoint& dh = robot.joint(k - 1);
  const Eigen::Isometry3d M =
      Eigen::Translation3d(dh.a, 0.0, dh.d) * Eigen::AngleAxisd(dh.alpha, Eigen::Vector3d::UnitX());
  const Eigen::Isometry3d M_inv = M.inverse();
  return {M_inv.translation(), M_inv.linear().col(2)};
}

// A body's bounding sphere in its frame: the shapes' spheres' mean centre, and the radius
// reaching around them all.
std::pair<Eigen::Vector3d, double> detail::boundingSphere(const detail::BodyGeometry& body) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const detail::CollisionShape& s : body.shapes) c += s.X_BG * s.centre_G;
  if (!body.shapes.empty()) c /= static_cast<double>(body.shapes.size());
  double r = 0.0;
  for (const detail::CollisionShape& s : body.shapes) {
    r = std::max(r, (s.X_BG * s.centre_G - c).norm() + s.radius);
  }
  return {c, r};
}

ChainLevers::ChainLevers(const Scene& scene) {
  const kinematics::RobotModel& robot = scene.cell().robot;
  for (const PairInfo& pair : scene.pairs()) {
    const auto a = static_cast<std::size_t>(pair.a), b = static_cast<std::size_t>(pair.b);
    const bool link = scene.bodies()[a].motion == BodyMotion::kRobotLink ||
                      scene.bodies()[b].motion == BodyMotion::kRobotLink;
    PairWeights weights;
    if (link) {
      Side before = sideOf(scene, a), after = sideOf(scene, b);
      weights.distal = b;
      if (before.link > after.link) {
        std::swap(before, after);
        weights.distal = a;
      }
      for (int k = before.link + 1; k <= after.link; ++k) {
        weights.w[static_cast<std::size_t>(k - 1)] =
            std::min(lever(robot, before, k), lever(robot, after, k));
      }
      for (Side* side : {&before, &after}) {
        if (!side->table_axis) continue;
        const Line axis = *side->table_axis;
        side->table_axis.reset();  // turning about the axis itself: no sweep
        weights.table = reachFromLine(*side, axis);
      }
    }
    covers_.push_back(link);
    weights_.push_back(weights);
  }
}

double ChainLevers::wideMotion(double table_motion,
                               const Weights& weights,
                               const kinematics::JointVector& q0,
                               const kinematics::JointVector& q1) {
  double motion = table_motion;
  for (int k = 0; k < kinematics::kNumJoints; ++k) {
    motion += weights[static_cast<std::size_t>(k)] * detail::turn(q1(k), q0(k));
  }
  return motion;
}

}  // namespace scanplan::collision
