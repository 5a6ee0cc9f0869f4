#pragma once

#include <vector>

#include <Eigen/Geometry>

#include <scanplan/collision/scene.h>

namespace scanplan::collision {

struct ClearanceRequest {
  /// Only distances below each pair's d_high are computed exactly; farther pairs are reported
  /// as "at least d_high" (docs/design.md §9). False: plain fcl::distance on every shape pair.
  bool bounded = true;
  /// Bounded requests: when > 0, every pair is measured below this distance (m) instead of its
  /// own d_high (the collision watch asks for its warning distance).
  double bound = 0.0;
  /// Fill witness points (world frame) for pairs closer than their bound.
  bool witness_points = false;
};

struct PairClearance {
  double distance = 0.0;      ///< m; equals the pair's d_high when beyond_bound
  bool beyond_bound = false;  ///< only known to be ≥ d_high (bounded requests)
  bool penetrating = false;   ///< in contact or overlapping; distance is 0
  double factor = 1.0;        ///< f_C, Eq. 8 (monotone ramp)
  Eigen::Vector3d p_a = Eigen::Vector3d::Zero();  ///< witness point on body a, world, m
  Eigen::Vector3d p_b = Eigen::Vector3d::Zero();  ///< witness point on body b, world, m
};

struct ClearanceResult {
  std::vector<PairClearance> pairs;  ///< parallel to Scene::pairs()
  double factor = 1.0;               ///< product of the pair factors
  int limiting_pair = -1;            ///< pair with the lowest factor (then distance), -1: none
  bool collision = false;            ///< some pair penetrates
};

/// Evaluates clearance for poses of one scene. Holds per-thread scratch (body poses): make one
/// per thread; the Scene is shared.
class ClearanceEvaluator {
 public:
  /// `closed_forms` false: FCL alone, as before collision/primitive_distance (the map
  /// benchmark's old path). `geometry`: what is measured (kMap: as the maps do).
  explicit ClearanceEvaluator(const Scene& scene,
                              bool closed_forms = true,
                              Geometry geometry = Geometry::kExact)
      : scene_(&scene), closed_forms_(closed_forms), geometry_(geometry) {}

  ClearanceResult evaluate(double theta,
                           const kinematics::JointVector& q,
                           const ClearanceRequest& request = {});

  /// The product of the pair factors only, with the cheapest ordering and an early exit at
  /// 0: the hot path of the configuration maps.
  double factor(double theta, const kinematics::JointVector& q);

 private:
  const Scene* scene_;
  bool closed_forms_ = true;
  Geometry geometry_ = Geometry::kExact;
  std::vector<Eigen::Isometry3d> X_W_;
};

}  // namespace scanplan::collision
