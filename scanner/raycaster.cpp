#include <scanplan/scanner/raycaster.h>

#include <scanplan/scanner/embree_mesh.h>

#include <embree3/rtcore.h>

#include <cmath>
#include <stdexcept>

namespace scanplan::scanner {

namespace {
constexpr double kFarthest = 1e6;  // m: a ray origin farther out meets nothing
}  // namespace

struct Raycaster::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

Raycaster::Raycaster(const kinematics::TriangleMesh& mesh) : impl_(std::make_unique<Impl>()) {
  // No "threads=N" in the config: with it, Embree's TBB back end installs a process-wide
  // tbb::global_control for the device's lifetime, and every parallel loop of ours (the maps)
  // silently ran on one thread while a Raycaster existed.
  impl_->device = rtcNewDevice(nullptr);
  if (!impl_->device) throw std::runtime_error("Embree: cannot create a device");
  impl_->scene = rtcNewScene(impl_->device);
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
  RTCGeometry geometry = embreeTriangles(impl_->device, mesh);
  rtcAttachGeometry(impl_->scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(impl_->scene);
}

Raycaster::~Raycaster() = default;

std::optional<RayHit> Raycaster::cast(const Eigen::Vector3d& origin,
                                      const Eigen::Vector3d& direction,
                                      double t_near,
                                      double t_far) const {
  const Eigen::Vector3d d = direction.normalized();
  // Embree asserts a valid ray (finite, 0 ≤ t_near ≤ t_far) and works in float: anything else,
  // or an origin beyond any cell, meets nothing.
  if (!origin.allFinite() || !d.allFinite() || origin.cwiseAbs().maxCoeff() > kFarthest ||
      !(t_near >= 0.0) || !(t_far >= t_near)) {
    return std::nullopt;
  }
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh{};
  rh.ray.org_x = static_cast<float>(origin.x());
  rh.ray.org_y = static_cast<float>(origin.y());
  rh.ray.org_z = static_cast<float>(origin.z());
  rh.ray.dir_x = embreeDirection(d.x());
  rh.ray.dir_y = embreeDirection(d.y());
  rh.ray.dir_z = embreeDirection(d.z());
  rh.ray.tnear = static_cast<float>(t_near);
  rh.ray.tfar =
      std::isfinite(t_far) ? static_cast<float>(t_far) : std::numeric_limits<float>::infinity();
  rh.ray.mask = 0xFFFFFFFFu;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  RayHit hit;
  hit.distance = static_cast<double>(rh.ray.tfar);
  hit.normal = Eigen::Vector3d(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z).normalized();
  hit.triangle = rh.hit.primID;
  return hit;
}

}  // namespace scanplan::scanner
