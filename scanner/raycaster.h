#pragma once

#include <limits>
#include <memory>
#include <optional>

#include <Eigen/Geometry>

#include <scanplan/kinematics/mesh.h>

namespace scanplan::scanner {

struct RayHit {
  double distance = 0.0;                             ///< along the ray, m
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  ///< geometric normal, unit, mesh frame
  unsigned triangle = 0;
};

/// Embree 3 ray casting against one triangle mesh (its own frame, m). The scene is built once;
/// cast() is const and safe to call from many threads.
class Raycaster {
 public:
  explicit Raycaster(const kinematics::TriangleMesh& mesh);
  ~Raycaster();
  Raycaster(const Raycaster&) = delete;
  Raycaster& operator=(const Raycaster&) = delete;

  /// Nearest hit along origin + s·d̂ for s in [t_near, t_far] (m), d̂ = direction normalised.
  /// No hit for a non-finite ray, an origin beyond 1000 km or not 0 ≤ t_near ≤ t_far.
  std::optional<RayHit> cast(const Eigen::Vector3d& origin,
                             const Eigen::Vector3d& direction,
                             double t_near = 0.0,
                             double t_far = std::numeric_limits<double>::infinity()) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace scanplan::scanner
