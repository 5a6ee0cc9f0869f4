#include <scanplan/collision/clearance.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include <scanplan/collision/fcl_geometry.h>
#include <scanplan/kinematics/ramp.h>

namespace scanplan::collision {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double bound(const PairInfo& pair, const ClearanceRequest& request) {
  return request.bound > 0.0 ? request.bound : pair.thresholds.d_high;
}

}  // namespace

namespace detail {

namespace {

// The least distance over the shape pairs measured so far (below the bound), and the least lower
// bound over the pairs found beyond it: what shapesDistance() and nearestFirstDistance() keep.
struct Nearest {
  ShapeDistance best;
  double lower = kInf;

  explicit Nearest(double bound) {
    best.distance = bound;
    best.beyond = true;
  }
  // Measures a pair below the best distance so far; true when the shapes touch (none is nearer).
  bool measure(const CollisionShape& sa,
               const Eigen::Isometry3d& X_Wsa,
               const CollisionShape& sb,
               const Eigen::Isometry3d& X_Wsb,
               bool witness,
               bool closed_forms) {
    const ShapeDistance d =
        shapeDistance(sa, X_Wsa, sb, X_Wsb, best.distance, witness, closed_forms);
    if (d.beyond)
      lower = std::min(lower, d.lower);
    else
      best = d;
    return best.penetrating;
  }
  ShapeDistance result(double bound) {
    best.lower = best.beyond ? std::max(bound, lower) : best.distance;
    return best;
  }
};

// Above this many shape pairs (a link as convex pieces), the pairs are measured nearest first.
constexpr std::size_t kSortedPairsAbove = 16;

// The shapes' bounding-sphere centres in the world, into `centres`; returns a sphere holding all
// their spheres (about the centres' mean).
std::pair<Eigen::Vector3d, double> shapeCentres(const std::vector<CollisionShape>& shapes,
                                                const Eigen::Isometry3d& X_W,
                                                std::vector<Eigen::Vector3d>& centres) {
  centres.resize(shapes.size());
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    centres[i] = X_W * (shapes[i].X_BG * shapes[i].centre_G);
    mean += centres[i];
  }
  mean /= static_cast<double>(std::max<std::size_t>(1, shapes.size()));
  double radius = 0.0;
  for (std::size_t i = 0; i < shapes.size(); ++i)
    radius = std::max(radius, (centres[i] - mean).norm() + shapes[i].radius);
  return {mean, radius};
}

// The shapes whose spheres come within `bound` of the sphere (centre, radius) holding the other
// side, into `near`; the least gap of the others lowers `lower`.
void shapesNear(const std::vector<CollisionShape>& shapes,
                const std::vector<Eigen::Vector3d>& centres,
                const std::pair<Eigen::Vector3d, double>& other,
                double bound,
                std::vector<std::uint32_t>& near,
                double& lower) {
  near.clear();
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    const double gap = (centres[i] - other.first).norm() - shapes[i].radius - other.second;
    if (gap >= bound)
      lower = std::min(lower, gap);
    else
      near.push_back(static_cast<std::uint32_t>(i));
  }
}

// shapesDistance() for many shape pairs: the pairs in the order of their bounding spheres' gap
// (nearest first; ties in list order), so that the best found so far bounds the rest early; at
// the first pair whose spheres lie at or beyond it, so do all the rest. A shape whose sphere lies
// beyond the bound from the sphere holding the other side's takes no pair. The buffers are kept
// per thread: a link of 150 pieces against one of 87 makes 13 050 pairs a query.
ShapeDistance nearestFirstDistance(const std::vector<CollisionShape>& a_shapes,
                                   const Eigen::Isometry3d& X_Wa,
                                   const std::vector<CollisionShape>& b_shapes,
                                   const Eigen::Isometry3d& X_Wb,
                                   double bound,
                                   bool witness,
                                   bool closed_forms) {
  struct Gap {
    double gap;
    std::uint32_t a, b;
  };
  thread_local std::vector<Eigen::Vector3d> c_a, c_b;
  thread_local std::vector<std::uint32_t> near_a, near_b;
  thread_local std::vector<Gap> gaps;
  Nearest nearest(bound);
  const auto ball_a = shapeCentres(a_shapes, X_Wa, c_a);
  const auto ball_b = shapeCentres(b_shapes, X_Wb, c_b);
  shapesNear(a_shapes, c_a, ball_b, bound, near_a, nearest.lower);
  shapesNear(b_shapes, c_b, ball_a, bound, near_b, nearest.lower);
  gaps.clear();
  for (const std::uint32_t i : near_a) {
    for (const std::uint32_t j : near_b) {
      const double gap = (c_a[i] - c_b[j]).norm() - a_shapes[i].radius - b_shapes[j].radius;
      if (gap >= bound)
        nearest.lower = std::min(nearest.lower, gap);
      else
        gaps.push_back({gap, i, j});
    }
  }
  std::sort(gaps.begin(), gaps.end(), [](const Gap& x, const Gap& y) {
    return x.gap != y.gap ? x.gap < y.gap : (x.a != y.a ? x.a < y.a : x.b < y.b);
  });
  for (const Gap& g : gaps) {
    if (g.gap >= nearest.best.distance) {
      nearest.lower = std::min(nearest.lower, g.gap);  // the least of the rest
      break;
    }
    const CollisionShape &sa = a_shapes[g.a], &sb = b_shapes[g.b];
    if (nearest.measure(sa, X_Wa * sa.X_BG, sb, X_Wb * sb.X_BG, witness, closed_forms))
      return nearest.best;
  }
  return nearest.result(bound);
}

// Minimum over the pairs of two shape lists. Bounded: each shape pair is asked only for
// distances below the best found so far (initially d_high), and a bounding-sphere test skips
// shape pairs that cannot come closer than that.
ShapeDistance shapesDistance(const std::vector<CollisionShape>& a_shapes,
                             const Eigen::Isometry3d& X_Wa,
                             const std::vector<CollisionShape>& b_shapes,
                             const Eigen::Isometry3d& X_Wb,
                             double bound,
                             bool exact,
                             bool witness,
                             bool closed_forms) {
  if (!exact && a_shapes.size() * b_shapes.size() > kSortedPairsAbove)
    return nearestFirstDistance(a_shapes, X_Wa, b_shapes, X_Wb, bound, witness, closed_forms);
  Nearest nearest(bound);
  ShapeDistance& best = nearest.best;
  for (const CollisionShape& sa : a_shapes) {
    // The shapes' poses only for the pairs that pass the broad phase (bounding spheres).
    std::optional<Eigen::Isometry3d> X_Wsa;
    const auto shape_a = [&]() -> const Eigen::Isometry3d& {
      if (!X_Wsa) X_Wsa = X_Wa * sa.X_BG;
      return *X_Wsa;
    };
    const Eigen::Vector3d c_a = X_Wa * (sa.X_BG * sa.centre_G);
    for (const CollisionShape& sb : b_shapes) {
      if (exact) {
        const ShapeDistance d = exactShapeDistance(sa, shape_a(), sb, X_Wb * sb.X_BG);
        if (best.beyond || d.distance < best.distance) best = d;
        continue;
      }
      const double spheres = (c_a - X_Wb * (sb.X_BG * sb.centre_G)).norm() - sa.radius - sb.radius;
      if (spheres >= best.distance) {
        nearest.lower = std::min(nearest.lower, spheres);
        continue;
      }
      if (nearest.measure(sa, shape_a(), sb, X_Wb * sb.X_BG, witness, closed_forms)) return best;
    }
  }
  return nearest.result(bound);
}

}  // namespace

// A body with a gate (convex pieces inside their hulls) is measured at its gate first: beyond
// the bound there, beyond it here too.
ShapeDistance bodyDistance(const BodyGeometry& a,
                           const Eigen::Isometry3d& X_Wa,
                           const BodyGeometry& b,
                           const Eigen::Isometry3d& X_Wb,
                           double bound,
                           bool exact,
                           bool witness,
                           bool closed_forms) {
  if (!exact && (!a.gate.empty() || !b.gate.empty())) {
    const ShapeDistance gate =
        shapesDistance(a.gate.empty() ? a.shapes : a.gate, X_Wa, b.gate.empty() ? b.shapes : b.gate,
                       X_Wb, bound, false, false, closed_forms);
    if (gate.beyond) return gate;
  }
  return shapesDistance(a.shapes, X_Wa, b.shapes, X_Wb, bound, exact, witness, closed_forms);
}

}  // namespace detail

ClearanceResult ClearanceEvaluator::evaluate(double theta,
                                             const kinematics::JointVector& q,
                                             const ClearanceRequest& request) {
  const Scene& scene = *scene_;
  scene.bodyPoses(theta, q, X_W_);
  const auto& bodies = scene.geometry().of(geometry_);
  ClearanceResult result;
  result.pairs.resize(scene.pairs().size());
  double worst_factor = 2.0, worst_distance = kInf;
  for (std::size_t i = 0; i < scene.pairs().size(); ++i) {
    const PairInfo& pair = scene.pairs()[i];
    const auto a = static_cast<std::size_t>(pair.a), b = static_cast<std::size_t>(pair.b);
    const detail::ShapeDistance d = detail::bodyDistance(
        bodies[a], X_W_[a], bodies[b], X_W_[b], !request.bounded ? kInf : bound(pair, request),
        !request.bounded, request.witness_points, closed_forms_);
    PairClearance& out = result.pairs[i];
    out.distance = d.distance;
    out.beyond_bound = d.beyond;
    out.penetrating = d.penetrating;
    out.factor = out.beyond_bound ? 1.0
                                  : rampFactor(d.distance, pair.thresholds.d_low,
                                               pair.thresholds.d_high, pair.thresholds.gamma);
    if (!out.beyond_bound && request.witness_points) {
      out.p_a = d.p_a;
      out.p_b = d.p_b;
    }
    result.factor *= out.factor;
    result.collision = result.collision || out.penetrating;
    if (!out.beyond_bound && (out.factor < worst_factor ||
                              (out.factor == worst_factor && out.distance < worst_distance))) {
      worst_factor = out.factor;
      worst_distance = out.distance;
      result.limiting_pair = static_cast<int>(i);
    }
  }
  return result;
}

double ClearanceEvaluator::factor(double theta, const kinematics::JointVector& q) {
  const Scene& scene = *scene_;
  scene.bodyPoses(theta, q, X_W_);
  const auto& bodies = scene.geometry().of(geometry_);
  double f = 1.0;
  for (const PairInfo& pair : scene.pairs()) {
    const auto a = static_cast<std::size_t>(pair.a), b = static_cast<std::size_t>(pair.b);
    const detail::ShapeDistance d =
        detail::bodyDistance(bodies[a], X_W_[a], bodies[b], X_W_[b], pair.thresholds.d_high, false,
                             false, closed_forms_);
    if (d.beyond) continue;
    f *= rampFactor(d.distance, pair.thresholds.d_low, pair.thresholds.d_high,
                    pair.thresholds.gamma);
    if (f == 0.0) return 0.0;
  }
  return f;
}

}  // namespace scanplan::collision
