#include <scanplan/collision/sensors.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <stdexcept>
#include <utility>

#include <fcl/narrowphase/collision.h>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <scanplan/collision/fcl_geometry.h>
#include <scanplan/collision/primitive_distance.h>
#include <scanplan/kinematics/error.h>

namespace scanplan::collision {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Directions closer than this to parallel with a slab or the cylinder's axis are treated as
// parallel (unit directions; far below any length that matters, m).
constexpr double kParallel = 1e-15;

using detail::Primitive;

// The parameter interval [in, out] of the ray o + s·d (d unit) inside a convex solid, or none.
struct Interval {
  double in = 0.0;
  double out = 0.0;
};

std::optional<Interval> rayBox(const Eigen::Vector3d& o,
                               const Eigen::Vector3d& d,
                               const Eigen::Vector3d& half) {
  Interval r{-kInf, kInf};
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < kParallel) {
      if (std::abs(o[i]) > half[i]) return std::nullopt;
      continue;
    }
    double a = (-half[i] - o[i]) / d[i], b = (half[i] - o[i]) / d[i];
    if (a > b) std::swap(a, b);
    r.in = std::max(r.in, a);
    r.out = std::min(r.out, b);
    if (r.in > r.out) return std::nullopt;
  }
  return r;
}

std::optional<Interval> raySphere(const Eigen::Vector3d& o,
                                  const Eigen::Vector3d& d,
                                  const Eigen::Vector3d& c,
                                  double radius) {
  const Eigen::Vector3d oc = o - c;
  const double b = d.dot(oc);
  const double disc = b * b - (oc.squaredNorm() - radius * radius);
  if (disc < 0.0) return std::nullopt;
  const double root = std::sqrt(disc);
  return Interval{-b - root, -b + root};
}

// The infinite cylinder x² + y² ≤ r² (axis z) clipped to |z| ≤ h.
std::optional<Interval> rayCylinder(const Eigen::Vector3d& o,
                                    const Eigen::Vector3d& d,
                                    double radius,
                                    double h) {
  Interval r{-kInf, kInf};
  const double a = d.x() * d.x() + d.y() * d.y();
  const double c = o.x() * o.x() + o.y() * o.y() - radius * radius;
  if (a < kParallel) {
    if (c > 0.0) return std::nullopt;
  } else {
    const double b = o.x() * d.x() + o.y() * d.y();
    const double disc = b * b - a * c;
    if (disc < 0.0) return std::nullopt;
    const double root = std::sqrt(disc);
    r = {(-b - root) / a, (-b + root) / a};
  }
  const auto slab = rayBox(o, d, Eigen::Vector3d(kInf, kInf, h));
  if (!slab) return std::nullopt;
  r.in = std::max(r.in, slab->in);
  r.out = std::min(r.out, slab->out);
  if (r.in > r.out) return std::nullopt;
  return r;
}

// A primitive in its own frame (the ray given there).
std::optional<Interval> rayPrimitive(const Primitive& p,
                                     const Eigen::Vector3d& o,
                                     const Eigen::Vector3d& d) {
  switch (p.kind) {
    case Primitive::Kind::kBox:
      return rayBox(o, d, p.half);
    case Primitive::Kind::kCylinder:
      return rayCylinder(o, d, p.radius(), p.halfLength());
    case Primitive::Kind::kCapsule: {
      // Convex: the union of its cylinder and end spheres is one interval.
      std::optional<Interval> all;
      const auto join = [&all](const std::optional<Interval>& i) {
        if (!i) return;
        all = all ? Interval{std::min(all->in, i->in), std::max(all->out, i->out)} : *i;
      };
      if (p.halfLength() > 0.0) join(rayCylinder(o, d, p.radius(), p.halfLength()));
      join(raySphere(o, d, Eigen::Vector3d(0, 0, p.halfLength()), p.radius()));
      join(raySphere(o, d, Eigen::Vector3d(0, 0, -p.halfLength()), p.radius()));
      return all;
    }
  }
  return std::nullopt;
}

// Barycentric slack of the ray–triangle test: a ray through an edge or a vertex shared by two
// triangles must hit one of them whatever the rounding (a beam aimed along a mesh's symmetry
// plane slipped between two triangles at some table angles without it).
constexpr double kEdgeSlack = 1e-9;

// Möller–Trumbore, both sides: the ray parameter of the hit, or none.
std::optional<double> rayTriangle(const Eigen::Vector3d& o,
                                  const Eigen::Vector3d& d,
                                  const Eigen::Vector3d& a,
                                  const Eigen::Vector3d& b,
                                  const Eigen::Vector3d& c) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a;
  const Eigen::Vector3d p = d.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-300) return std::nullopt;
  const double inv = 1.0 / det;
  const Eigen::Vector3d s = o - a;
  const double u = s.dot(p) * inv;
  if (u < -kEdgeSlack || u > 1.0 + kEdgeSlack) return std::nullopt;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = d.dot(q) * inv;
  if (v < -kEdgeSlack || u + v > 1.0 + kEdgeSlack) return std::nullopt;
  return e2.dot(q) * inv;
}

// A bounding-volume hierarchy of a mesh's triangles (axis-aligned boxes, median splits), for
// ray casts: a part of 30 000 triangles is cast against at every pose of a trajectory.
class TriangleTree {
 public:
  TriangleTree() = default;
  explicit TriangleTree(kinematics::TriangleMesh mesh) : mesh_(std::move(mesh)) {
    order_.resize(mesh_.triangles.size());
    for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = i;
    if (order_.empty()) return;
    nodes_.resize(1);
    build(0, 0, order_.size());
  }

  // The least s in [near, far] where the ray o + s·d crosses a triangle.
  std::optional<double> cast(const Eigen::Vector3d& o,
                             const Eigen::Vector3d& d,
                             double near,
                             double far) const {
    std::optional<double> best;
    if (nodes_.empty()) return best;
    std::vector<std::size_t> stack{0};
    while (!stack.empty()) {
      const Node& n = nodes_[stack.back()];
      stack.pop_back();
      const auto hit = rayBox(o - n.box.center(), d, 0.5 * n.box.sizes());
      if (!hit || hit->out < near || hit->in > (best ? *best : far)) continue;
      if (n.left == 0) {
        for (std::size_t i = n.first; i < n.first + n.count; ++i) {
          const Eigen::Vector3i& t = mesh_.triangles[order_[i]];
          const auto& v = mesh_.vertices;
          const auto s =
              rayTriangle(o, d, v[static_cast<std::size_t>(t[0])],
                          v[static_cast<std::size_t>(t[1])], v[static_cast<std::size_t>(t[2])]);
          if (s && *s >= near && *s <= far && (!best || *s < *best)) best = s;
        }
        continue;
      }
      stack.push_back(n.left);
      stack.push_back(n.left + 1);
    }
    return best;
  }

 private:
  struct Node {
    Eigen::AlignedBox3d box;
    std::size_t left = 0;  // children at left and left + 1; 0: a leaf
    std::size_t first = 0;
    std::size_t count = 0;
  };
  static constexpr std::size_t kLeafSize = 8;

  Eigen::Vector3d vertex(std::size_t triangle, int corner) const {
    return mesh_.vertices[static_cast<std::size_t>(mesh_.triangles[triangle][corner])];
  }
  Eigen::Vector3d centroid(std::size_t triangle) const {
    return (vertex(triangle, 0) + vertex(triangle, 1) + vertex(triangle, 2)) / 3.0;
  }

  // Fills node `slot` with triangles order_[first, first + count), splitting at the median
  // centroid along the widest axis; children go side by side at the end.
  void build(std::size_t slot, std::size_t first, std::size_t count) {
    Eigen::AlignedBox3d box, centres;
    for (std::size_t i = first; i < first + count; ++i) {
      for (int c = 0; c < 3; ++c) box.extend(vertex(order_[i], c));
      centres.extend(centroid(order_[i]));
    }
    nodes_[slot] = Node{box, 0, first, count};
    if (count <= kLeafSize) return;
    int axis = 0;
    centres.sizes().maxCoeff(&axis);
    const std::size_t half = count / 2;
    const auto begin = order_.begin() + static_cast<std::ptrdiff_t>(first);
    std::nth_element(begin, begin + static_cast<std::ptrdiff_t>(half),
                     begin + static_cast<std::ptrdiff_t>(count), [&](std::size_t a, std::size_t b) {
                       return centroid(a)[axis] < centroid(b)[axis];
                     });
    const std::size_t left = nodes_.size();
    nodes_.resize(left + 2);
    nodes_[slot].left = left;
    build(left, first, half);
    build(left + 1, first + half, count - half);
  }

  kinematics::TriangleMesh mesh_;
  std::vector<std::size_t> order_;
  std::vector<Node> nodes_;
};

// One shape of a body as the beams see it: a primitive, or a mesh's triangles (shape frame).
struct RayShape {
  Eigen::Isometry3d X_BG = Eigen::Isometry3d::Identity();
  Eigen::Vector3d centre_G = Eigen::Vector3d::Zero();
  double radius = 0.0;  ///< bounding sphere about centre_G
  std::optional<Primitive> primitive;
  std::shared_ptr<const TriangleTree> mesh;
};

// The first s in [near, far] where the ray meets the shape (enters a primitive's solid, or
// crosses a mesh triangle), or none. The ray is in the world; X_WG the shape's world pose.
std::optional<double> firstHit(const RayShape& shape,
                               const Eigen::Isometry3d& X_WG,
                               const Eigen::Vector3d& o_W,
                               const Eigen::Vector3d& d_W,
                               double near,
                               double far) {
  // Broad phase: the bounding sphere against the segment [near, far] of the ray.
  const Eigen::Vector3d c_W = X_WG * shape.centre_G;
  const double s_closest = std::clamp(d_W.dot(c_W - o_W), near, far);
  if ((o_W + s_closest * d_W - c_W).norm() > shape.radius * (1.0 + 1e-12) + 1e-12) {
    return std::nullopt;
  }
  const Eigen::Vector3d o = X_WG.inverse() * o_W;
  const Eigen::Vector3d d = X_WG.linear().transpose() * d_W;
  if (shape.primitive) {
    const auto i = rayPrimitive(*shape.primitive, o, d);
    if (!i || i->out < near || i->in > far) return std::nullopt;
    return std::max(i->in, near);
  }
  if (!shape.mesh) return std::nullopt;
  return shape.mesh->cast(o, d, near, far);
}

RayShape rayShape(const detail::CollisionShape& shape) {
  RayShape out;
  out.X_BG = shape.X_BG;
  out.centre_G = shape.centre_G;
  out.radius = shape.radius;
  out.primitive = shape.primitive;
  if (!shape.primitive) {
    const auto* model = dynamic_cast<const detail::MeshModel*>(shape.geometry.get());
    if (model) out.mesh = std::make_shared<const TriangleTree>(detail::meshOf(*model));
  }
  return out;
}

}  // namespace

std::string_view beamStatusName(BeamStatus status) {
  switch (status) {
    case BeamStatus::kReading:
      return "reading";
    case BeamStatus::kNoTarget:
      return "no_target";
    case BeamStatus::kTooClose:
      return "too_close";
    case BeamStatus::kReceiverOccluded:
      return "receiver_occluded";
  }
  return "unknown";
}

std::string carrierChoices(const Scene& scene) {
  std::string out = "world";
  for (const BodyInfo& b : scene.bodies()) out += ", " + b.name;
  return out;
}

struct SensorEvaluator::Impl {
  const Scene* scene = nullptr;
  std::vector<int> carrier;                       // per sensor: body index, -1 world
  std::vector<detail::CollisionShape> volumes;    // per sensor: presence volume (else empty)
  std::vector<std::vector<RayShape>> ray_bodies;  // per body: its shapes (meshes' trees shared)
  std::vector<Eigen::Isometry3d> X_W;             // scratch: body poses
  std::vector<Eigen::Isometry3d> X_WS;            // sensor poses at the last evaluation
  bool any_distance = false;

  // The least s in [near, far] at which the ray meets a body other than `skip`, with the body.
  std::pair<double, int> cast(
      const Eigen::Vector3d& o, const Eigen::Vector3d& d, double near, double far, int skip) const {
    std::pair<double, int> best{kInf, -1};
    for (std::size_t b = 0; b < ray_bodies.size(); ++b) {
      if (static_cast<int>(b) == skip) continue;
      for (const RayShape& shape : ray_bodies[b]) {
        const auto s = firstHit(shape, X_W[b] * shape.X_BG, o, d, near, std::min(far, best.first));
        if (s && *s < best.first) best = {*s, static_cast<int>(b)};
      }
    }
    return best;
  }

  bool overlaps(const detail::CollisionShape& volume,
                const Eigen::Isometry3d& X_WV,
                std::size_t body) const {
    for (const detail::CollisionShape& shape : scene->geometry().bodies[body].shapes) {
      const Eigen::Isometry3d X_WG = X_W[body] * shape.X_BG;
      const double gap = ((X_WV * volume.centre_G) - (X_WG * shape.centre_G)).norm() -
                         volume.radius - shape.radius;
      if (gap > 1e-9) continue;
      // Then the separating-axis gap to a mesh's bounding box (or the primitive itself).
      if (volume.primitive && (shape.primitive || shape.bounding_box)) {
        Primitive a = *volume.primitive;
        Primitive b = shape.primitive ? *shape.primitive : *shape.bounding_box;
        a.X_W = X_WV * a.X_W;
        b.X_W = X_WG * b.X_W;
        if (detail::quickLowerBound(a, b) > 1e-9) continue;
      }
      if (volume.primitive && shape.primitive) {
        // Exact closed forms where they exist (FCL's GJK is good to 1e-6 m only).
        Primitive a = *volume.primitive, b = *shape.primitive;
        a.X_W = X_WV * a.X_W;
        b.X_W = X_WG * b.X_W;
        const detail::PrimitiveDistance d = detail::primitiveDistance(a, b);
        if (d.exact) {
          if (d.distance <= 0.0) return true;
          continue;
        }
      }
      // Solid against solid, or against a mesh's triangles (fcl::collide on geometry and
      // transforms: no CollisionObject, which would write the shared geometry's AABB).
      fcl::CollisionRequestd request;
      fcl::CollisionResultd result;
      fcl::collide(volume.geometry.get(), fcl::Transform3d(X_WV.matrix()), shape.geometry.get(),
                   fcl::Transform3d(X_WG.matrix()), request, result);
      if (result.isCollision()) return true;
    }
    return false;
  }

  SensorReading distance(const kinematics::Sensor& sensor,
                         const Eigen::Isometry3d& X_WE,  // the emitter: sensor frame, world
                         int skip) const {
    SensorReading r;
    const Eigen::Vector3d o = X_WE.translation();
    const Eigen::Vector3d d = X_WE.linear().col(2);
    const auto [s, body] = cast(o, d, 0.0, sensor.max_range, skip);
    if (body < 0) return r;  // kNoTarget
    r.distance = s;
    r.body = body;
    if (s < sensor.min_range) {
      r.beam = BeamStatus::kTooClose;
      return r;
    }
    if (sensor.p_SR) {
      // Seed §5.2: the reflected ray from the hit point through the receiver's lens must be free.
      const Eigen::Vector3d p = o + s * d;
      const Eigen::Vector3d to = X_WE * *sensor.p_SR - p;
      const double length = to.norm();
      if (length > 2.0 * kReceiverClearance) {
        const auto blocked =
            cast(p, to / length, kReceiverClearance, length - kReceiverClearance, skip);
        if (blocked.second >= 0) {
          r.beam = BeamStatus::kReceiverOccluded;
          return r;
        }
      }
    }
    r.beam = BeamStatus::kReading;
    r.fires = true;
    return r;
  }
};

SensorEvaluator::SensorEvaluator(const Scene& scene) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.scene = &scene;
  const auto& sensors = scene.cell().sensors;
  for (std::size_t i = 0; i < sensors.size(); ++i) {
    const kinematics::Sensor& s = sensors[i];
    int carrier = -1;
    if (!s.carrier.empty() && s.carrier != "world") {
      carrier = scene.bodyIndex(s.carrier);
      if (carrier < 0) {
        throw InputError(fmt::format(
            "sensors[{}].carrier: '{}' (sensor {}) is no body of the cell: expected one of {}", i,
            clipForMessage(s.carrier), s.name, carrierChoices(scene)));
      }
    }
    m.carrier.push_back(carrier);
    if (s.kind == kinematics::Sensor::Kind::kPresence) {
      m.volumes.push_back(detail::makeCollisionShape(s.volume));
    } else {
      m.volumes.emplace_back();
      m.any_distance = true;
    }
  }
  if (m.any_distance) {
    for (const detail::BodyGeometry& body : scene.geometry().bodies) {
      std::vector<RayShape> shapes;
      for (const detail::CollisionShape& shape : body.shapes) shapes.push_back(rayShape(shape));
      m.ray_bodies.push_back(std::move(shapes));
    }
  }
  m.X_WS.resize(sensors.size(), Eigen::Isometry3d::Identity());
}

SensorEvaluator::~SensorEvaluator() = default;
SensorEvaluator::SensorEvaluator(const SensorEvaluator& other)
    : impl_(std::make_unique<Impl>(*other.impl_)) {}
SensorEvaluator::SensorEvaluator(SensorEvaluator&&) noexcept = default;
SensorEvaluator& SensorEvaluator::operator=(SensorEvaluator&&) noexcept = default;

std::vector<SensorReading> SensorEvaluator::evaluate(double theta,
                                                     const kinematics::JointVector& q) {
  Impl& m = *impl_;
  m.scene->bodyPoses(theta, q, m.X_W);
  const auto& sensors = m.scene->cell().sensors;
  std::vector<SensorReading> out(sensors.size());
  for (std::size_t i = 0; i < sensors.size(); ++i) {
    const kinematics::Sensor& s = sensors[i];
    const int carrier = m.carrier[i];
    const Eigen::Isometry3d X_WC =
        carrier < 0 ? Eigen::Isometry3d::Identity() : m.X_W[static_cast<std::size_t>(carrier)];
    m.X_WS[i] = X_WC * s.X_CS;
    if (s.kind == kinematics::Sensor::Kind::kDistance) {
      out[i] = m.distance(s, m.X_WS[i], carrier);
      continue;
    }
    SensorReading& r = out[i];
    r.beam = BeamStatus::kNoTarget;
    const detail::CollisionShape& volume = m.volumes[i];
    const Eigen::Isometry3d X_WV = m.X_WS[i] * volume.X_BG;
    for (std::size_t b = 0; b < m.X_W.size(); ++b) {
      if (static_cast<int>(b) == carrier) continue;  // not its own carrier
      if (m.overlaps(volume, X_WV, b)) r.bodies.push_back(static_cast<int>(b));
    }
    r.fires = !r.bodies.empty();
  }
  return out;
}

const Eigen::Isometry3d& SensorEvaluator::sensorPose(std::size_t s) const {
  return impl_->X_WS.at(s);
}

int SensorEvaluator::carrierBody(std::size_t s) const { return impl_->carrier.at(s); }

SensorEvaluation evaluateSensors(const Scene& scene,
                                 const std::vector<kinematics::TrajectorySample>& samples) {
  SensorEvaluation out;
  const std::size_t n = scene.cell().sensors.size();
  out.readings.assign(n, {});
  if (n == 0) return out;
  if (samples.size() > kMaxSensorReadings / n) {
    throw InputError(fmt::format(
        "{} sensors at {} poses would be {} readings, more than {}: expected fewer sensors, a "
        "shorter trajectory or a lower rate (scanner.frame_rate_hz)",
        n, samples.size(), static_cast<double>(n) * static_cast<double>(samples.size()),
        kMaxSensorReadings));
  }
  // A presence reading lists the bodies it sees: at worst every body of the scene.
  double entries = 0.0;
  for (const kinematics::Sensor& sensor : scene.cell().sensors) {
    const bool presence = sensor.kind == kinematics::Sensor::Kind::kPresence;
    entries += static_cast<double>(samples.size()) *
               (presence ? static_cast<double>(scene.bodies().size()) : 1.0);
  }
  if (entries > static_cast<double>(kMaxSensorBodyEntries)) {
    throw InputError(fmt::format(
        "{} sensors at {} poses with {} bodies in the cell could list {} bodies, more than {}: "
        "expected fewer presence sensors, obstacles or poses (scanner.frame_rate_hz)",
        n, samples.size(), scene.bodies().size(), entries, kMaxSensorBodyEntries));
  }
  SensorEvaluator first(scene);  // resolves the carriers (and throws) before any thread starts
  out.t.reserve(samples.size());
  for (const kinematics::TrajectorySample& sample : samples) out.t.push_back(sample.t);
  for (auto& series : out.readings) series.resize(samples.size());
  // Poses are independent: evaluated in parallel, one evaluator per thread, each reading put at
  // its sample's place, so the result does not depend on the thread count.
  tbb::enumerable_thread_specific<std::optional<SensorEvaluator>> evaluators;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, samples.size(), 64),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      std::optional<SensorEvaluator>& evaluator = evaluators.local();
                      if (!evaluator) evaluator.emplace(first);
                      for (std::size_t k = range.begin(); k < range.end(); ++k) {
                        std::vector<SensorReading> at =
                            evaluator->evaluate(samples[k].theta, samples[k].q);
                        for (std::size_t s = 0; s < n; ++s) out.readings[s][k] = std::move(at[s]);
                      }
                    });
  return out;
}

namespace {

// The runs of samples where `pick(k)` holds, with the presence bodies seen in each.
template <class Pick>
std::vector<SensorSpan> runs(const SensorEvaluation& e, std::size_t s, const Pick& pick) {
  std::vector<SensorSpan> out;
  std::set<int> bodies;
  bool open = false;
  const auto& series = e.readings.at(s);
  for (std::size_t k = 0; k < e.t.size(); ++k) {
    if (!pick(k)) {
      if (open) out.back().bodies.assign(bodies.begin(), bodies.end());
      open = false;
      continue;
    }
    if (!open) {
      out.push_back({e.t[k], e.t[k], {}});
      bodies.clear();
      open = true;
    }
    out.back().t_end = e.t[k];
    bodies.insert(series[k].bodies.begin(), series[k].bodies.end());
  }
  if (open) out.back().bodies.assign(bodies.begin(), bodies.end());
  return out;
}

constexpr double kWindowTolerance = 1e-9;  // s: a window's ends count as inside it

// The parts of a `during` window outside the trajectory's samples: the sensor must fire there,
// and nothing shows it does (a window after the motion's end is never met, not met vacuously).
std::vector<SensorSpan> unobserved(const kinematics::SensorExpectation& x,
                                   const SensorEvaluation& evaluation) {
  std::vector<SensorSpan> out;
  if (x.kind != kinematics::SensorExpectation::Kind::kDuring) return out;
  if (evaluation.t.empty()) return {SensorSpan{x.t0, x.t1, {}}};
  const double first = evaluation.t.front(), last = evaluation.t.back();
  if (x.t0 < first - kWindowTolerance) out.push_back({x.t0, std::min(x.t1, first), {}});
  if (x.t1 > last + kWindowTolerance) out.push_back({std::max(x.t0, last), x.t1, {}});
  return out;
}

}  // namespace

std::vector<SensorSpan> firingSpans(const SensorEvaluation& evaluation, std::size_t s) {
  const auto& series = evaluation.readings.at(s);
  return runs(evaluation, s, [&](std::size_t k) { return series[k].fires; });
}

std::string describeExpectation(const kinematics::SensorExpectation& expect) {
  using Kind = kinematics::SensorExpectation::Kind;
  switch (expect.kind) {
    case Kind::kAny:
      return "any";
    case Kind::kNever:
      return "never";
    case Kind::kAlways:
      return "always";
    case Kind::kDuring:
      return fmt::format("during [{:.3f}, {:.3f}] s", expect.t0, expect.t1);
    case Kind::kNotDuring:
      return fmt::format("not during [{:.3f}, {:.3f}] s", expect.t0, expect.t1);
  }
  return "unknown";
}

std::vector<SensorRuleViolation> checkSensorRules(const std::vector<kinematics::Sensor>& sensors,
                                                  const SensorEvaluation& evaluation) {
  using Kind = kinematics::SensorExpectation::Kind;
  std::vector<SensorRuleViolation> out;
  for (std::size_t s = 0; s < sensors.size() && s < evaluation.readings.size(); ++s) {
    const kinematics::SensorExpectation& x = sensors[s].expect;
    const auto& series = evaluation.readings[s];
    const auto inside = [&](std::size_t k) {
      return evaluation.t[k] >= x.t0 - kWindowTolerance &&
             evaluation.t[k] <= x.t1 + kWindowTolerance;
    };
    // Whether the sensor must fire at sample k (true), must not (false), or either (nullopt).
    const auto must = [&](std::size_t k) -> std::optional<bool> {
      switch (x.kind) {
        case Kind::kAny:
          return std::nullopt;
        case Kind::kNever:
          return false;
        case Kind::kAlways:
          return true;
        case Kind::kDuring:
          return inside(k);
        case Kind::kNotDuring:
          return inside(k) ? std::optional<bool>(false) : std::nullopt;
      }
      return std::nullopt;
    };
    std::vector<SensorRuleViolation> found;
    for (const bool fired : {true, false}) {
      for (SensorSpan& span : runs(evaluation, s, [&](std::size_t k) {
             const auto m = must(k);
             return m && *m != series[k].fires && series[k].fires == fired;
           })) {
        found.push_back({s, fired, std::move(span)});
      }
    }
    for (SensorSpan& span : unobserved(x, evaluation)) found.push_back({s, false, std::move(span)});
    std::stable_sort(found.begin(), found.end(),
                     [](const auto& a, const auto& b) { return a.span.t_start < b.span.t_start; });
    out.insert(out.end(), found.begin(), found.end());
  }
  return out;
}

}  // namespace scanplan::collision
