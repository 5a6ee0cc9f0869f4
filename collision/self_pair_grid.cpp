#include <scanplan/collision/self_pair_grid.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <scanplan/collision/fcl_geometry.h>

namespace scanplan::collision {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Bins along a joint of range `range` (rad) at `width` (rad), one spare for q at the top.
std::int64_t binsAlong(double range, double width) {
  return static_cast<std::int64_t>(std::ceil(range / width)) + 1;
}

// Where a stored key's probe starts in a table of mask + 1 slots.
std::size_t slotOf(std::uint64_t stored, std::size_t mask) {
  const std::uint64_t h = stored * 0x9E3779B97F4A7C15ull;
  return static_cast<std::size_t>(h ^ (h >> 32)) & mask;
}

// Whether the maps measure the pair as a stand-in: some shape of its bodies is a convex
// polytope (a link mesh's hull or pieces) and none a mesh (measured exactly, as asked).
bool standInPair(const Scene& scene, std::size_t p) {
  const auto& bodies = scene.geometry().map_bodies;
  bool convex = false, mesh = false;
  for (const int body : {scene.pairs()[p].a, scene.pairs()[p].b}) {
    for (const detail::CollisionShape& s : bodies[static_cast<std::size_t>(body)].shapes) {
      convex = convex || s.geometry->getNodeType() == fcl::GEOM_CONVEX;
      mesh = mesh || s.geometry->getObjectType() == fcl::OT_BVH;
    }
  }
  return convex && !mesh;
}

}  // namespace

SelfPairGrid::SelfPairGrid(const Scene& scene,
                           const ChainLevers& levers,
                           double erosion,
                           double fine_erosion)
    : scene_(&scene), grids_(scene.pairs().size()), coarse_(grids_.size()) {
  if (!(erosion > 0.0) || !std::isfinite(erosion) || !(fine_erosion >= 0.0) ||
      !std::isfinite(fine_erosion)) {
    throw std::invalid_argument("collision::SelfPairGrid: erosion must be positive");
  }
  const kinematics::RobotModel& robot = scene.cell().robot;
  for (std::size_t p = 0; p < grids_.size(); ++p) {
    if (!levers.covers(p) || !scene.armPair(p)) continue;
    const bool fine = fine_erosion > 0.0 && standInPair(scene, p);
    grids_[p] = gridOf(robot, levers.weights(p), scene.pairs()[p].thresholds.d_high,
                       fine ? fine_erosion : erosion);
    grids_[p].fine = fine && grids_[p].dims > 0;
    if (!grids_[p].fine) continue;
    grids_[p].max_bins = kMaxFineBins;
    coarse_[p] = gridOf(robot, levers.weights(p), scene.pairs()[p].thresholds.d_high, erosion);
  }
}

SelfPairGrid::Grid SelfPairGrid::gridOf(const kinematics::RobotModel& robot,
                                        const ChainLevers::Weights& w,
                                        double d_high,
                                        double erosion) {
  Grid grid;
  grid.dims = static_cast<int>(std::count_if(w.begin(), w.end(), [](double x) { return x > 0.0; }));
  if (grid.dims > kMaxJoints) grid.dims = 0;
  if (grid.dims == 0) return grid;
  // Widths sharing the erosion equally, doubled until the bins fit in a 63-bit key.
  for (double scale = 1.0;; scale *= 2.0) {
    double count = 1.0;
    for (std::size_t k = 0; k < w.size(); ++k) {
      if (w[k] <= 0.0) continue;
      const kinematics::DhJoint& joint = robot.joint(static_cast<int>(k));
      grid.width[k] = scale * 2.0 * erosion / (grid.dims * w[k]);
      grid.per_width[k] = 1.0 / grid.width[k];
      grid.origin[k] = joint.min;
      grid.weight[k] = w[k];
      grid.bins[k] = binsAlong(joint.max - joint.min, grid.width[k]);
      count *= static_cast<double>(grid.bins[k]);
    }
    if (count < 0x1p62) break;
  }
  double reach = 0.0;  // Σ w_k·h_k, the most a bin's centre takes off its bound
  for (std::size_t k = 0; k < w.size(); ++k) reach += w[k] * 0.5 * grid.width[k];
  grid.cap = d_high + reach * (1.0 + 1e-9) + 1e-6;
  grid.far = d_high + 1e-6;
  grid.keys.assign(1024, 0);
  grid.centre.assign(1024, 0.0);
  return grid;
}

bool SelfPairGrid::keyOf(const Grid& grid,
                         const kinematics::JointVector& q,
                         std::uint64_t& key,
                         double& offset) const {
  std::uint64_t out = 0;
  offset = 0.0;
  for (std::size_t k = 0; k < grid.width.size(); ++k) {
    if (grid.width[k] == 0.0) continue;
    const double b = (q(static_cast<int>(k)) - grid.origin[k]) * grid.per_width[k];
    if (!(b >= 0.0 && b < static_cast<double>(grid.bins[k]))) return false;
    // b ≥ 0: truncation is floor.
    const auto bin = static_cast<std::uint64_t>(b);
    out = out * static_cast<std::uint64_t>(grid.bins[k]) + bin;
    // The centre as measure() places it.
    const double c = grid.origin[k] + (static_cast<double>(bin) + 0.5) * grid.width[k];
    offset += grid.weight[k] * std::abs(q(static_cast<int>(k)) - c);
  }
  // The centre's rounding, and the bound's own (ChainLevers sums in another order).
  offset = offset * (1.0 + 1e-9) + 1e-12;
  key = out;
  return true;
}

double SelfPairGrid::measure(std::size_t p, const Grid& grid, std::uint64_t key) const {
  kinematics::JointVector q = kinematics::JointVector::Zero();
  // The bin's centre: the key's digits, last joint first. The other joints do not move the pair
  // (weight 0) and stay at 0, so that the bound does not depend on which q came first, not even
  // by a rounding.
  for (std::size_t k = grid.width.size(); k-- > 0;) {
    if (grid.width[k] == 0.0) continue;
    const auto bins = static_cast<std::uint64_t>(grid.bins[k]);
    const double b = static_cast<double>(key % bins);
    key /= bins;
    q(static_cast<int>(k)) = grid.origin[k] + (b + 0.5) * grid.width[k];
  }
  // Both bodies in the DH frame of the earlier link: the chain between them is all it takes.
  const kinematics::CellModel& cell = scene_->cell();
  const PairInfo& pair = scene_->pairs()[p];
  const BodyInfo &a = scene_->bodies()[static_cast<std::size_t>(pair.a)],
                 &b = scene_->bodies()[static_cast<std::size_t>(pair.b)];
  const int from = std::min(a.link, b.link);
  const auto place = [&](const BodyInfo& body) {
    const Eigen::Isometry3d X = cell.robot.chain(from, body.link, q);
    return body.motion == BodyMotion::kScanner ? Eigen::Isometry3d(X * cell.scanner.X_FS) : X;
  };
  const auto& bodies = scene_->geometry().map_bodies;
  const detail::ShapeDistance d = detail::bodyDistance(
      bodies[static_cast<std::size_t>(pair.a)], place(a), bodies[static_cast<std::size_t>(pair.b)],
      place(b), grid.cap, false, false);
  return d.lower;
}

void SelfPairGrid::grow(Grid& grid) {
  std::vector<std::uint64_t> keys(grid.keys.size() * 2, 0);
  std::vector<double> centre(keys.size(), 0.0);
  const std::size_t mask = keys.size() - 1;
  for (std::size_t i = 0; i < grid.keys.size(); ++i) {
    if (grid.keys[i] == 0) continue;
    std::size_t slot = slotOf(grid.keys[i], mask);
    while (keys[slot] != 0) slot = (slot + 1) & mask;
    keys[slot] = grid.keys[i];
    centre[slot] = grid.centre[i];
  }
  grid.keys = std::move(keys);
  grid.centre = std::move(centre);
}

double SelfPairGrid::lower(std::size_t p, const kinematics::JointVector& q) {
  Grid& grid = grids_[p];
  if (grid.fine) {  // far by the coarse bins: no fine bin measured
    const double far = binLower(p, coarse_[p], q);
    if (far >= coarse_[p].far) return far;
  }
  return binLower(p, grid, q);
}

double SelfPairGrid::binLower(std::size_t p, Grid& grid, const kinematics::JointVector& q) {
  std::uint64_t key = 0;
  double offset = 0.0;
  if (!keyOf(grid, q, key, offset)) return -kInf;
  const std::uint64_t stored = key + 1;
  const std::size_t mask = grid.keys.size() - 1;
  std::size_t slot = slotOf(stored, mask);
  for (; grid.keys[slot] != 0; slot = (slot + 1) & mask) {
    if (grid.keys[slot] == stored) return grid.centre[slot] - offset;
  }
  if (grid.used >= grid.max_bins && !grid.fine) return -kInf;
  const double centre = measure(p, grid, key);
  ++measured_;
  if (grid.used < grid.max_bins) {
    grid.keys[slot] = stored;
    grid.centre[slot] = centre;
    if (++grid.used * 2 > grid.keys.size()) grow(grid);
  }
  return centre - offset;
}

}  // namespace scanplan::collision
