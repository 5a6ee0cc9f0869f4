#include <scanplan/scanner/simulator.h>

#include <scanplan/scanner/detail/large_buffer.h>
#include <scanplan/scanner/detail/random.h>
#include <scanplan/scanner/embree_mesh.h>

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <utility>

namespace scanplan::scanner {
namespace {

using detail::gaussianPair;
using detail::mix;

// Occlusion rays start this far off the hit triangle, on the lit side, so that Embree's float
// arithmetic cannot report the hit triangle itself (coordinates are O(1 m): 1e-5 m is ~170
// float ulps there, and far below anything a camera resolves).
constexpr double kOcclusionOffset = 1e-5;  // m
// The profile's bounding box grows by this much before the groups' spheres are tested.
constexpr double kCullMargin = 1e-3;  // m

enum class GroupKind { kTable, kWorld, kLink };

// One triangle mesh of a rigid group, in the group's frame, in double: Embree finds the hit
// triangle, these give the exact hit point and normal.
struct GroupMesh {
  kinematics::TriangleMesh mesh;
  bool is_part = false;
  // Per triangle its plane n·p = w (n unit): one cache line per hit instead of four.
  std::vector<Eigen::Vector4d> planes;
};

// A rigid group: everything in it moves together.
struct Group {
  GroupKind kind = GroupKind::kWorld;
  int link = -1;  // arm link 1…6 for kLink
  std::vector<GroupMesh> meshes;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // bounding sphere, group frame, m
  double radius = 0.0;
  RTCScene scene = nullptr;  // Embree back end
  // Brute-force back end: per mesh, per triangle v0, e1 = v1 − v0, e2 = v2 − v0.
  std::vector<std::vector<std::array<Eigen::Vector3d, 3>>> edges;
};

// A fan ray's nearest hit so far.
struct Hit {
  int slot = -1;  // index into the profile's active groups
  unsigned mesh = 0;
  unsigned triangle = 0;
  double t = 0.0;  // as cast (Embree's float or brute force's): the next group's far limit
  Eigen::Vector4d plane = Eigen::Vector4d::Zero();  // the triangle's (GroupMesh::planes)
  Eigen::Vector3d d_G = Eigen::Vector3d::Zero();    // the ray's direction, group frame
};

// A fan ray's hit that lies in the trapezoid, waiting for the camera test.
struct Candidate {
  Eigen::Vector3d p_S = Eigen::Vector3d::Zero();
  Eigen::Vector3d n_S = Eigen::Vector3d::Zero();  // unit, towards the laser
  double t = 0.0;                                 // refined
  double cos_incidence = 1.0;
  std::uint32_t ray = 0;
  std::int32_t part_triangle = -1;  // as in CloudPoint
};

// A camera ray: from just off a candidate's hit to the camera centre, scanner frame.
struct CameraRay {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d towards = Eigen::Vector3d::Zero();  // unit
  double length = 0.0;
};

// A group taking part in one profile: the scanner frame in the group frame.
struct ActiveGroup {
  int index = 0;
  Eigen::Isometry3d X_GS = Eigen::Isometry3d::Identity();
};

// Embree packet width: the fan and the camera rays of a profile go to Embree in packets of
// this many (16: AVX-512's native width; on narrower CPUs Embree splits them). Packets of
// neighbouring rays measured 1.1–1.2x faster than the same rays as a coherent stream
// (rtcIntersect1M/rtcOccluded1M); 8-wide camera packets were no better.
constexpr std::size_t kPacket = 16;

// simulate() runs the profiles in batches of about this many fan rays (see there): the
// per-thread point buffers stay a few MB.
constexpr std::size_t kBatchRays = std::size_t{1} << 15;
// The most room (bytes) a run reserves for its cloud up front.
constexpr std::size_t kReserveBytes = std::size_t{1} << 30;

// The fields of a packet's rays that no cast changes (Embree writes only tfar and the hit):
// set once per packet, when the thread's scratch is made.
template <typename Packet>
void initLanes(Packet& ray) noexcept {
  for (std::size_t j = 0; j < kPacket; ++j) {
    ray.tnear[j] = 0.0f;
    ray.time[j] = 0.0f;
    ray.mask[j] = 0xFFFFFFFFu;
    ray.id[j] = 0;
    ray.flags[j] = 0;
  }
}

// An intersect context for packets of rays that run side by side (Embree's coherent hint).
RTCIntersectContext coherentContext() {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  return context;
}

// Lane j of a packet: the ray o + t·d, t in [0, t_far] (float, as Embree takes it).
template <typename Packet>
void fillLane(Packet& ray,
              std::size_t j,
              const Eigen::Vector3d& o,
              const Eigen::Vector3d& d,
              double t_far) noexcept {
  ray.org_x[j] = static_cast<float>(o.x());
  ray.org_y[j] = static_cast<float>(o.y());
  ray.org_z[j] = static_cast<float>(o.z());
  ray.dir_x[j] = embreeDirection(d.x());
  ray.dir_y[j] = embreeDirection(d.y());
  ray.dir_z[j] = embreeDirection(d.z());
  ray.tfar[j] = static_cast<float>(t_far);
}

// Per-thread buffers, reused profile after profile.
struct Scratch {
  Scratch() noexcept {
    initLanes(fan_packet.ray);
    initLanes(camera_packet);
    for (std::size_t j = 0; j < kPacket; ++j) fan_packet.hit.instID[0][j] = RTC_INVALID_GEOMETRY_ID;
  }

  RTCRayHit16 fan_packet;  // 64-byte aligned (the type says so; TBB's storage honours it)
  RTCRay16 camera_packet;
  std::vector<Hit> best;
  std::vector<Candidate> candidates;
  std::vector<std::uint32_t> pending;  // candidates with a camera ray in this pass
  std::vector<CameraRay> camera_rays;
  std::vector<char> blocked;
  std::vector<char> seen;
  std::vector<char> seen_other;
  std::vector<ActiveGroup> active;
  ProfileImage image;  // image mode
  RenderScratch render;
};

// Settings shared by every profile of a run.
struct RunSetup {
  LaserWindow window;
  std::vector<Eigen::Vector3d> directions;  // fan, scanner frame, unit
  std::vector<double> t_far;                // beyond it a hit cannot be in the trapezoid
  std::vector<Eigen::Vector3d> cameras;     // C+ first when present
  Eigen::AlignedBox3d reach;                // every ray of a profile lies in it, scanner frame
  kinematics::RotaryTableModel true_table;
  const SimulationSettings* settings = nullptr;
  CameraModel camera;  // image mode
};

// Möller–Trumbore in double, both faces; the hit distance in [t_near, t_far] or nothing.
std::optional<double> intersect(const std::array<Eigen::Vector3d, 3>& tri,
                                const Eigen::Vector3d& o,
                                const Eigen::Vector3d& d,
                                double t_far) noexcept {
  const Eigen::Vector3d p = d.cross(tri[2]);
  const double det = tri[1].dot(p);
  if (det == 0.0) return std::nullopt;
  const double inv = 1.0 / det;
  const Eigen::Vector3d s = o - tri[0];
  const double u = s.dot(p) * inv;
  if (u < 0.0 || u > 1.0) return std::nullopt;
  const Eigen::Vector3d q = s.cross(tri[1]);
  const double v = d.dot(q) * inv;
  if (v < 0.0 || u + v > 1.0) return std::nullopt;
  const double t = tri[2].dot(q) * inv;
  if (t < 0.0 || t > t_far) return std::nullopt;
  return t;
}

}  // namespace

struct ScanSimulator::Impl {
  const kinematics::CellModel cell;
  RayBackend backend = RayBackend::kEmbree;
  RTCDevice device = nullptr;
  std::vector<Group> groups;
  mutable tbb::enumerable_thread_specific<Scratch> scratch;

  explicit Impl(const kinematics::CellModel& c) : cell(c) {}
  ~Impl() {
    for (Group& g : groups) {
      if (g.scene) rtcReleaseScene(g.scene);
    }
    if (device) rtcReleaseDevice(device);
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  void addGroup(Group group);
  void castFan(const RunSetup& setup, Scratch& s) const;
  void cameraPass(const Eigen::Vector3d& camera,
                  Scratch& s,
                  std::vector<char>& test,
                  SimulationStats& stats) const;
  void profile(const ScanFrame& frame,
               std::uint32_t index,
               const RunSetup& setup,
               Scratch& s,
               std::vector<CloudPoint>& out,
               SimulationStats& stats) const;
  // Every frame's profile into `cloud`, in batches (in parallel when there are threads), in
  // profile order; `rays`: points per profile at most. Returns the stats summed over threads.
  SimulationStats profiles(const std::vector<ScanFrame>& frames,
                           const RunSetup& setup,
                           std::size_t rays,
                           const std::function<void()>& poll,
                           SimulatedCloud& cloud) const;
  // Image mode (camera_image.h): the posed cell as an ImageScene, one profile's image, and
  // its points.
  struct GroupScene;
  void renderImage(const ScanFrame& frame,
                   std::uint32_t index,
                   const RunSetup& setup,
                   Scratch& s,
                   Eigen::Isometry3d& X_WS,
                   Eigen::Isometry3d& X_WR) const;
  void imageProfile(const ScanFrame& frame,
                    std::uint32_t index,
                    const RunSetup& setup,
                    Scratch& s,
                    std::vector<CloudPoint>& out,
                    SimulationStats& stats) const;

  // The steps of profile().
  void cullGroups(const std::array<Eigen::Isometry3d, kinematics::kNumJoints + 1>& link_frames,
                  const Eigen::Isometry3d& X_WS,
                  const Eigen::Isometry3d& X_WR,
                  const RunSetup& setup,
                  Scratch& s) const;
  void collectCandidates(const RunSetup& setup, Scratch& s, SimulationStats& stats) const;
  void applyCameraRule(const RunSetup& setup, Scratch& s, SimulationStats& stats) const;
  void emitPoints(const ScanFrame& frame,
                  std::uint32_t index,
                  const RunSetup& setup,
                  const Scratch& s,
                  const Eigen::Isometry3d& X_WS,
                  const Eigen::Isometry3d& X_WR,
                  std::vector<CloudPoint>& out,
                  SimulationStats& stats) const;
};

void ScanSimulator::Impl::addGroup(Group group) {
  Eigen::AlignedBox3d box;
  std::size_t count = 0;
  for (const GroupMesh& m : group.meshes) {
    for (const Eigen::Vector3d& v : m.mesh.vertices) box.extend(v);
    count += m.mesh.triangles.size();
  }
  if (count == 0) return;
  for (GroupMesh& m : group.meshes) {
    m.planes.reserve(m.mesh.triangles.size());
    for (const Eigen::Vector3i& f : m.mesh.triangles) {
      const Eigen::Vector3d& v0 = m.mesh.vertices[static_cast<std::size_t>(f(0))];
      const Eigen::Vector3d n = (m.mesh.vertices[static_cast<std::size_t>(f(1))] - v0)
                                    .cross(m.mesh.vertices[static_cast<std::size_t>(f(2))] - v0)
                                    .normalized();
      m.planes.emplace_back(n.x(), n.y(), n.z(), n.dot(v0));
    }
  }
  group.centre = box.center();
  for (const GroupMesh& m : group.meshes) {
    for (const Eigen::Vector3d& v : m.mesh.vertices) {
      group.radius = std::max(group.radius, (v - group.centre).norm());
    }
  }
  if (backend == RayBackend::kEmbree) {
    group.scene = rtcNewScene(device);
    rtcSetSceneBuildQuality(group.scene, RTC_BUILD_QUALITY_HIGH);
    for (std::size_t i = 0; i < group.meshes.size(); ++i) {
      RTCGeometry geometry = embreeTriangles(device, group.meshes[i].mesh);
      rtcAttachGeometryByID(group.scene, geometry, static_cast<unsigned>(i));
      rtcReleaseGeometry(geometry);
    }
    rtcCommitScene(group.scene);
  } else {
    for (const GroupMesh& m : group.meshes) {
      auto& edges = group.edges.emplace_back();
      edges.reserve(m.mesh.triangles.size());
      for (const Eigen::Vector3i& f : m.mesh.triangles) {
        const Eigen::Vector3d& v0 = m.mesh.vertices[static_cast<std::size_t>(f(0))];
        edges.push_back({v0, m.mesh.vertices[static_cast<std::size_t>(f(1))] - v0,
                         m.mesh.vertices[static_cast<std::size_t>(f(2))] - v0});
      }
    }
  }
  groups.push_back(std::move(group));
}

// Every fan ray against every active group; s.best keeps the nearest hit so far, and each
// group's rays only reach as far as that hit.
void ScanSimulator::Impl::castFan(const RunSetup& setup, Scratch& s) const {
  const std::size_t n = setup.directions.size();
  for (int slot = 0; slot < static_cast<int>(s.active.size()); ++slot) {
    const ActiveGroup& a = s.active[static_cast<std::size_t>(slot)];
    const Group& g = groups[static_cast<std::size_t>(a.index)];
    const Eigen::Vector3d o = a.X_GS.translation();
    if (backend == RayBackend::kEmbree) {
      // Neighbouring fan rays share the origin and nearly the direction: one packet each.
      RTCIntersectContext context = coherentContext();
      RTCRayHit16& rh = s.fan_packet;
      assert(reinterpret_cast<std::uintptr_t>(&rh) % 64 == 0);
      alignas(64) std::array<int, kPacket> valid{};
      std::array<Eigen::Vector3d, kPacket> d_G;
      // The hit triangles' planes (for the refinement) are scattered over megabytes: each
      // packet's are prefetched as it returns and read after the next packet's traversal,
      // which hides the cache misses. A packet's hits are a bit mask (no branch per ray).
      std::uint32_t previous = 0;  // hits of the packet before
      const auto take_planes = [&](std::size_t base, std::uint32_t hits) {
        for (; hits != 0; hits &= hits - 1) {
          Hit& hit = s.best[base + static_cast<std::size_t>(std::countr_zero(hits))];
          hit.plane = g.meshes[hit.mesh].planes[hit.triangle];
        }
      };
      for (std::size_t base = 0; base < n; base += kPacket) {
        const std::size_t count = std::min(kPacket, n - base);
        for (std::size_t j = 0; j < kPacket; ++j) {
          valid[j] = j < count ? -1 : 0;
          if (j >= count) continue;
          d_G[j] = a.X_GS.linear() * setup.directions[base + j];
          fillLane(rh.ray, j, o, d_G[j], s.best[base + j].t);
          rh.hit.geomID[j] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect16(valid.data(), g.scene, &context, &rh);
        std::uint32_t hits = 0;
        for (std::size_t j = 0; j < count; ++j) {
          hits |= static_cast<std::uint32_t>(rh.hit.geomID[j] != RTC_INVALID_GEOMETRY_ID) << j;
        }
        for (std::uint32_t left = hits; left != 0; left &= left - 1) {
          const auto j = static_cast<std::size_t>(std::countr_zero(left));
          Hit& hit = s.best[base + j];
          hit.slot = slot;
          hit.mesh = rh.hit.geomID[j];
          hit.triangle = rh.hit.primID[j];
          hit.t = static_cast<double>(rh.ray.tfar[j]);
          hit.d_G = d_G[j];
          __builtin_prefetch(g.meshes[hit.mesh].planes.data() + hit.triangle);
        }
        if (base > 0) take_planes(base - kPacket, previous);
        previous = hits;
      }
      if (n > 0) take_planes((n - 1) / kPacket * kPacket, previous);
    } else {
      for (std::size_t k = 0; k < n; ++k) {
        const Eigen::Vector3d d = a.X_GS.linear() * setup.directions[k];
        for (std::size_t m = 0; m < g.edges.size(); ++m) {
          for (std::size_t t = 0; t < g.edges[m].size(); ++t) {
            if (const auto hit = intersect(g.edges[m][t], o, d, s.best[k].t)) {
              Hit& best = s.best[k];
              best.slot = slot;
              best.mesh = static_cast<unsigned>(m);
              best.triangle = static_cast<unsigned>(t);
              best.t = *hit;
              best.plane = g.meshes[m].planes[t];
              best.d_G = d;
            }
          }
        }
      }
    }
  }
}

// Which of the candidates flagged in `test` the camera sees; clears the flag of the others.
// A camera on the far side of the hit triangle's plane cannot see the point (the surface
// itself hides it); otherwise the segment from the hit to the camera centre must be clear.
void ScanSimulator::Impl::cameraPass(const Eigen::Vector3d& camera,
                                     Scratch& s,
                                     std::vector<char>& test,
                                     SimulationStats& stats) const {
  s.pending.clear();
  s.camera_rays.clear();
  for (std::size_t i = 0; i < s.candidates.size(); ++i) {
    if (!test[i]) continue;
    const Candidate& c = s.candidates[i];
    if (!(c.n_S.dot(camera - c.p_S) > 0.0)) {
      test[i] = 0;
      continue;
    }
    CameraRay& r = s.camera_rays.emplace_back();
    r.origin = c.p_S + kOcclusionOffset * c.n_S;
    const Eigen::Vector3d to_camera = camera - r.origin;
    r.length = to_camera.norm();
    r.towards = to_camera / r.length;
    s.pending.push_back(static_cast<std::uint32_t>(i));
  }
  const std::size_t n = s.pending.size();
  stats.occlusion_rays += n;
  s.blocked.assign(n, 0);
  for (const ActiveGroup& a : s.active) {
    const Group& g = groups[static_cast<std::size_t>(a.index)];
    if (backend == RayBackend::kEmbree) {
      // Rays of neighbouring candidates run side by side to the same camera centre: one packet
      // each; rays already blocked by an earlier group are masked out.
      RTCIntersectContext context = coherentContext();
      RTCRay16& ray = s.camera_packet;
      assert(reinterpret_cast<std::uintptr_t>(&ray) % 64 == 0);
      alignas(64) std::array<int, kPacket> valid{};
      for (std::size_t base = 0; base < n; base += kPacket) {
        const std::size_t count = std::min(kPacket, n - base);
        bool any = false;
        for (std::size_t j = 0; j < kPacket; ++j) {
          const std::size_t i = base + j;
          valid[j] = j < count && !s.blocked[i] ? -1 : 0;
          if (!valid[j]) continue;
          any = true;
          const CameraRay& r = s.camera_rays[i];
          fillLane(ray, j, a.X_GS * r.origin, a.X_GS.linear() * r.towards, r.length);
        }
        if (!any) continue;
        rtcOccluded16(valid.data(), g.scene, &context, &ray);
        for (std::size_t j = 0; j < count; ++j) {
          if (valid[j] && ray.tfar[j] < 0.0f) s.blocked[base + j] = 1;
        }
      }
    } else {
      for (std::size_t i = 0; i < n; ++i) {
        if (s.blocked[i]) continue;
        const CameraRay& r = s.camera_rays[i];
        const Eigen::Vector3d o = a.X_GS * r.origin;
        const Eigen::Vector3d d = a.X_GS.linear() * r.towards;
        for (std::size_t k = 0; k < g.edges.size() && !s.blocked[i]; ++k) {
          for (const auto& tri : g.edges[k]) {
            if (intersect(tri, o, d, r.length)) {
              s.blocked[i] = 1;
              break;
            }
          }
        }
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (s.blocked[i]) test[s.pending[i]] = 0;
  }
}

void ScanSimulator::Impl::profile(const ScanFrame& frame,
                                  std::uint32_t index,
                                  const RunSetup& setup,
                                  Scratch& s,
                                  std::vector<CloudPoint>& out,
                                  SimulationStats& stats) const {
  if (setup.settings->mode == SimulationMode::kImage) {
    imageProfile(frame, index, setup, s, out, stats);
    return;
  }
  const auto link_frames = cell.robot.linkFrames(frame.q);
  const Eigen::Isometry3d X_WS = cell.X_WB * link_frames[6] * cell.scanner.X_FS;
  const Eigen::Isometry3d X_WR = setup.true_table.X_WR(frame.theta);
  cullGroups(link_frames, X_WS, X_WR, setup, s);

  const std::size_t n = setup.directions.size();
  stats.laser_rays += n;
  s.best.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    s.best[k].slot = -1;
    s.best[k].t = setup.t_far[k];
  }
  castFan(setup, s);
  collectCandidates(setup, s, stats);
  applyCameraRule(setup, s, stats);
  emitPoints(frame, index, setup, s, X_WS, X_WR, out, stats);
}

// The profile's active groups as one scene in the scanner frame: each batch of rays goes to
// every group in packets (rays of neighbouring pixels side by side), as the fan does.
struct ScanSimulator::Impl::GroupScene final : ImageScene {
  const Impl& impl;
  Scratch& s;
  GroupScene(const Impl& i, Scratch& scratch) : impl(i), s(scratch) {}

  void nearest(std::span<const SceneRay> rays, std::span<SceneHit> hits) const override {
    const std::size_t n = rays.size();
    for (std::size_t i = 0; i < n; ++i) {
      hits[i].hit = false;
      hits[i].t = rays[i].t_far;
      hits[i].part_triangle = -1;
    }
    RTCIntersectContext context = coherentContext();
    RTCRayHit16& rh = s.fan_packet;
    alignas(64) std::array<int, kPacket> valid{};
    for (const ActiveGroup& a : s.active) {
      const Group& g = impl.groups[static_cast<std::size_t>(a.index)];
      const Eigen::Matrix3d R_GS = a.X_GS.linear();
      for (std::size_t base = 0; base < n; base += kPacket) {
        const std::size_t count = std::min(kPacket, n - base);
        for (std::size_t j = 0; j < kPacket; ++j) {
          valid[j] = j < count ? -1 : 0;
          if (j >= count) continue;
          const SceneRay& r = rays[base + j];
          fillLane(rh.ray, j, a.X_GS * r.origin, R_GS * r.direction, hits[base + j].t);
          rh.hit.geomID[j] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect16(valid.data(), g.scene, &context, &rh);
        for (std::size_t j = 0; j < count; ++j) {
          if (rh.hit.geomID[j] == RTC_INVALID_GEOMETRY_ID) continue;
          SceneHit& h = hits[base + j];
          const GroupMesh& m = g.meshes[rh.hit.geomID[j]];
          h.hit = true;
          h.t = static_cast<double>(rh.ray.tfar[j]);
          h.n_S = R_GS.transpose() * m.planes[rh.hit.primID[j]].head<3>();
          h.part_triangle = m.is_part ? static_cast<std::int32_t>(rh.hit.primID[j]) : -1;
        }
      }
    }
  }

  void occluded(std::span<const SceneRay> rays, std::span<char> blocked) const override {
    const std::size_t n = rays.size();
    std::fill(blocked.begin(), blocked.end(), 0);
    RTCIntersectContext context = coherentContext();
    RTCRay16& ray = s.camera_packet;
    alignas(64) std::array<int, kPacket> valid{};
    for (const ActiveGroup& a : s.active) {
      const Group& g = impl.groups[static_cast<std::size_t>(a.index)];
      for (std::size_t base = 0; base < n; base += kPacket) {
        const std::size_t count = std::min(kPacket, n - base);
        bool any = false;
        for (std::size_t j = 0; j < kPacket; ++j) {
          valid[j] = j < count && !blocked[base + j] ? -1 : 0;
          if (!valid[j]) continue;
          any = true;
          const SceneRay& r = rays[base + j];
          fillLane(ray, j, a.X_GS * r.origin, a.X_GS.linear() * r.direction, r.t_far);
        }
        if (!any) continue;
        rtcOccluded16(valid.data(), g.scene, &context, &ray);
        for (std::size_t j = 0; j < count; ++j) {
          if (valid[j] && ray.tfar[j] < 0.0f) blocked[base + j] = 1;
        }
      }
    }
  }
};

// The camera image of one profile into s.image; the scanner and real table poses of it.
void ScanSimulator::Impl::renderImage(const ScanFrame& frame,
                                      std::uint32_t index,
                                      const RunSetup& setup,
                                      Scratch& s,
                                      Eigen::Isometry3d& X_WS,
                                      Eigen::Isometry3d& X_WR) const {
  const auto link_frames = cell.robot.linkFrames(frame.q);
  X_WS = cell.X_WB * link_frames[6] * cell.scanner.X_FS;
  X_WR = setup.true_table.X_WR(frame.theta);
  cullGroups(link_frames, X_WS, X_WR, setup, s);
  const GroupScene scene(*this, s);
  renderProfileImage(setup.camera, setup.settings->image, scene,
                     setup.settings->seed ^ detail::mix(index), s.image, s.render);
}

// Image mode (seed §5.3): render, detect the stripe per column, triangulate it (Eq. 4) and map
// it to the part frame as the geometric points are.
void ScanSimulator::Impl::imageProfile(const ScanFrame& frame,
                                       std::uint32_t index,
                                       const RunSetup& setup,
                                       Scratch& s,
                                       std::vector<CloudPoint>& out,
                                       SimulationStats& stats) const {
  Eigen::Isometry3d X_WS, X_WR;
  renderImage(frame, index, setup, s, X_WS, X_WR);
  const ImageSettings& settings = setup.settings->image;
  const ProfileImage& image = s.image;
  stats.pixel_rays += image.grey.size();
  stats.occlusion_rays += image.laser_rays;
  stats.lit_pixels += image.lit;
  const Eigen::Isometry3d X_WR_model =
      setup.settings->simulated_table ? cell.table.X_WR(frame.theta) : X_WR;
  const Eigen::Isometry3d X_PS = (X_WR_model * cell.part.X_RP).inverse() * X_WS;
  const CameraModel& camera = setup.camera;
  const std::size_t first = out.size();
  for (int k = 0; k < image.columns; ++k) {
    const std::optional<double> row =
        detectPeak(image.grey.data() + k, image.rows, static_cast<std::size_t>(image.columns),
                   settings.threshold, settings.method);
    if (!row) continue;
    ++stats.hits;
    const Eigen::Vector2d p = camera.imagePlane(static_cast<double>(k), *row);
    const Eigen::Vector3d p_S = camera.triangulate(p.x(), p.y());
    // The surface the stripe's peak pixel saw gives the normal and the triangle.
    const int r = std::clamp(static_cast<int>(std::lround(*row)), 0, image.rows - 1);
    const SceneHit& h =
        image.hit[static_cast<std::size_t>(r) * static_cast<std::size_t>(image.columns) +
                  static_cast<std::size_t>(k)];
    const double range = p_S.norm();
    Eigen::Vector3d n_S = h.hit ? h.n_S : -p_S / range;
    if (n_S.dot(p_S) > 0.0) n_S = -n_S;  // towards the laser
    const double cos_incidence = std::abs(n_S.dot(p_S)) / range;
    out.push_back({X_PS * p_S, frame.t, index, static_cast<std::uint32_t>(k), range,
                   std::acos(std::min(1.0, cos_incidence)), h.hit ? h.part_triangle : -1,
                   X_PS.linear() * n_S});
  }
  stats.points += out.size() - first;
}

// Groups whose bounding sphere reaches the profile's rays, with the rays' frame in theirs, X_GS,
// worked out only for those. (A sphere this test passes or fails depending on the rounding of its
// centre lies kCullMargin from every ray: no ray can hit it either way.)
void ScanSimulator::Impl::cullGroups(
    const std::array<Eigen::Isometry3d, kinematics::kNumJoints + 1>& link_frames,
    const Eigen::Isometry3d& X_WS,
    const Eigen::Isometry3d& X_WR,
    const RunSetup& setup,
    Scratch& s) const {
  const Eigen::Isometry3d X_SW = X_WS.inverse();
  s.active.clear();
  for (std::size_t i = 0; i < groups.size(); ++i) {
    const Group& g = groups[i];
    Eigen::Isometry3d X_WG = Eigen::Isometry3d::Identity();  // the world group's
    if (g.kind == GroupKind::kTable) {
      X_WG = X_WR;
    } else if (g.kind == GroupKind::kLink) {
      X_WG = cell.X_WB * link_frames[static_cast<std::size_t>(g.link)];
    }
    if (setup.reach.exteriorDistance(X_SW * (X_WG * g.centre)) > g.radius) continue;
    s.active.push_back(
        {static_cast<int>(i), g.kind == GroupKind::kWorld ? X_WS : X_WG.inverse() * X_WS});
  }
}

// The fan's hits inside the laser window, as candidates for the cameras.
void ScanSimulator::Impl::collectCandidates(const RunSetup& setup,
                                            Scratch& s,
                                            SimulationStats& stats) const {
  s.candidates.clear();
  for (std::size_t k = 0; k < setup.directions.size(); ++k) {
    const Hit& hit = s.best[k];
    if (hit.slot < 0) continue;
    ++stats.hits;
    const ActiveGroup& a = s.active[static_cast<std::size_t>(hit.slot)];
    const Eigen::Vector4d& plane = hit.plane;
    // Embree's distance is float; the hit triangle's plane gives it in double (the point then
    // lies on the triangle to ~1e-16 relative, whatever the frames).
    const Eigen::Vector3d& d_S = setup.directions[k];
    const Eigen::Vector3d n_G = plane.head<3>();
    const double cos_nd = n_G.dot(hit.d_G);
    double t = hit.t;
    if (std::abs(cos_nd) > 1e-9) t = (plane.w() - n_G.dot(a.X_GS.translation())) / cos_nd;
    const Eigen::Vector3d p_S = t * d_S;
    if (!setup.window.contains(p_S.y(), p_S.z())) {
      ++stats.outside_window;
      continue;
    }
    Candidate& c = s.candidates.emplace_back();
    c.p_S = p_S;
    c.n_S = a.X_GS.linear().transpose() * n_G;
    if (c.n_S.dot(d_S) > 0.0) c.n_S = -c.n_S;
    c.t = t;
    c.cos_incidence = std::abs(cos_nd);
    c.ray = static_cast<std::uint32_t>(k);
    if (groups[static_cast<std::size_t>(a.index)].meshes[hit.mesh].is_part) {
      c.part_triangle = static_cast<std::int32_t>(hit.triangle);
    }
  }
}

// The camera rule (CameraRule): each pass tests the candidates still in question against one
// camera; s.seen says which candidates are seen.
void ScanSimulator::Impl::applyCameraRule(const RunSetup& setup,
                                          Scratch& s,
                                          SimulationStats& stats) const {
  const std::size_t m = s.candidates.size();
  switch (setup.settings->cameras) {
    case CameraRule::kPositive:
    case CameraRule::kNegative:
      s.seen.assign(m, 1);
      cameraPass(setup.cameras[0], s, s.seen, stats);
      break;
    case CameraRule::kBoth:
      s.seen.assign(m, 1);
      cameraPass(setup.cameras[0], s, s.seen, stats);
      cameraPass(setup.cameras[1], s, s.seen, stats);  // only those C+ sees
      break;
    case CameraRule::kEither:
      s.seen.assign(m, 1);
      cameraPass(setup.cameras[0], s, s.seen, stats);
      s.seen_other.resize(m);
      for (std::size_t i = 0; i < m; ++i) s.seen_other[i] = s.seen[i] ? 0 : 1;
      cameraPass(setup.cameras[1], s, s.seen_other, stats);  // only those C+ does not see
      for (std::size_t i = 0; i < m; ++i) s.seen[i] = s.seen[i] || s.seen_other[i];
      break;
  }
}

// The seen candidates as cloud points in the part frame, with the sensor noise.
void ScanSimulator::Impl::emitPoints(const ScanFrame& frame,
                                     std::uint32_t index,
                                     const RunSetup& setup,
                                     const Scratch& s,
                                     const Eigen::Isometry3d& X_WS,
                                     const Eigen::Isometry3d& X_WR,
                                     std::vector<CloudPoint>& out,
                                     SimulationStats& stats) const {
  const SimulationSettings& settings = *setup.settings;
  const bool noisy = settings.sigma_longitudinal > 0.0 || settings.sigma_orthogonal > 0.0;
  std::optional<std::mt19937_64> rng;  // seeding costs ~300 words: only when noisy
  if (noisy) rng.emplace(mix(settings.seed ^ mix(index)));
  // Points go to the part frame through the planner's table model (seed §5.6).
  const Eigen::Isometry3d X_WR_model =
      settings.simulated_table ? cell.table.X_WR(frame.theta) : X_WR;
  const Eigen::Isometry3d X_PS = (X_WR_model * cell.part.X_RP).inverse() * X_WS;
  const std::size_t first = out.size();
  for (std::size_t i = 0; i < s.candidates.size(); ++i) {
    if (!s.seen[i]) {
      ++stats.occluded;
      continue;
    }
    const Candidate& c = s.candidates[i];
    Eigen::Vector3d p_S = c.p_S;
    double range = c.t;
    if (noisy) {
      // Along the ray and across it within the laser plane (a triangulating head measures in
      // its plane): d = (0, sin α, cos α), u = (0, cos α, −sin α).
      const Eigen::Vector3d& d = setup.directions[c.ray];
      const Eigen::Vector3d u(0.0, d.z(), -d.y());
      const auto [g_l, g_o] = gaussianPair(*rng);
      const double e_l = settings.sigma_longitudinal * g_l;
      p_S += e_l * d + settings.sigma_orthogonal * g_o * u;
      range += e_l;
    }
    out.push_back({X_PS * p_S, frame.t, index, c.ray, range,
                   std::acos(std::min(1.0, c.cos_incidence)), c.part_triangle,
                   X_PS.linear() * c.n_S});
  }
  stats.points += out.size() - first;
}

std::vector<double> fanAngles(const LaserWindow& window, int rays_per_profile) {
  std::vector<double> angles;
  if (rays_per_profile <= 0) return angles;
  if (rays_per_profile == 1) return {0.0};
  const double alpha_max =
      std::max(std::atan2(window.y_near, window.z_min), std::atan2(window.y_far, window.z_max));
  angles.reserve(static_cast<std::size_t>(rays_per_profile));
  for (int k = 0; k < rays_per_profile; ++k) {
    angles.push_back(-alpha_max + 2.0 * alpha_max * k / (rays_per_profile - 1));
  }
  return angles;
}

std::vector<Eigen::Vector3d> cameraCentres(const LaserOptics& optics, CameraRule rule) {
  const Eigen::Vector3d plus(optics.a, 0.0, optics.b), minus(-optics.a, 0.0, optics.b);
  switch (rule) {
    case CameraRule::kPositive:
      return {plus};
    case CameraRule::kNegative:
      return {minus};
    case CameraRule::kBoth:
    case CameraRule::kEither:
      return {plus, minus};
  }
  return {};
}

ScanSimulator::ScanSimulator(const kinematics::CellModel& cell,
                             const kinematics::TriangleMesh& part,
                             const SimulatorOptions& options)
    : impl_(std::make_unique<Impl>(cell)) {
  impl_->backend = options.backend;
  if (options.backend == RayBackend::kEmbree) {
    // No "threads=N" in the config: with it, Embree's TBB back end installs a process-wide
    // tbb::global_control for the device's lifetime (see raycaster.cpp).
    impl_->device = rtcNewDevice(nullptr);
    if (!impl_->device) throw std::runtime_error("Embree: cannot create a device");
  }
  const auto surfaces = [&](const std::vector<kinematics::Shape>& shapes,
                            const Eigen::Isometry3d& X) {
    std::vector<GroupMesh> out;
    for (const kinematics::Shape& shape : shapes) {
      GroupMesh m{kinematics::shapeSurface(shape, options.tessellation), false, {}};
      for (Eigen::Vector3d& v : m.mesh.vertices) v = X * v;
      out.push_back(std::move(m));
    }
    return out;
  };

  // The table group (frame R): the part first, so that its geometry index is 0.
  Group table;
  table.kind = GroupKind::kTable;
  GroupMesh part_mesh{part, true, {}};
  for (Eigen::Vector3d& v : part_mesh.mesh.vertices) v = cell.part.X_RP * v;
  table.meshes.push_back(std::move(part_mesh));
  kinematics::Shape top;
  top.geometry = kinematics::Cylinder{cell.table.radius, cell.table.height};
  top.X_BG.translation() << 0.0, 0.0, -0.5 * cell.table.height;  // top face at z = 0
  for (GroupMesh& m : surfaces({top}, Eigen::Isometry3d::Identity())) {
    table.meshes.push_back(std::move(m));
  }
  Group world;
  world.kind = GroupKind::kWorld;
  world.meshes = surfaces(cell.robot.definition().links[0].shapes, cell.X_WB);
  for (const kinematics::Obstacle& o : cell.obstacles) {
    Group& g = o.carrier == kinematics::Carrier::kTable ? table : world;
    for (GroupMesh& m : surfaces(o.shapes, Eigen::Isometry3d::Identity())) {
      g.meshes.push_back(std::move(m));
    }
  }
  impl_->addGroup(std::move(table));
  impl_->addGroup(std::move(world));
  for (int k = 1; k <= kinematics::kNumJoints; ++k) {
    Group link;
    link.kind = GroupKind::kLink;
    link.link = k;
    link.meshes = surfaces(cell.robot.definition().links[static_cast<std::size_t>(k)].shapes,
                           Eigen::Isometry3d::Identity());
    impl_->addGroup(std::move(link));
  }
}

ScanSimulator::~ScanSimulator() = default;

std::size_t ScanSimulator::triangleCount() const {
  std::size_t count = 0;
  for (const Group& g : impl_->groups) {
    for (const GroupMesh& m : g.meshes) count += m.mesh.triangles.size();
  }
  return count;
}

namespace {

// What every profile of a run shares: the window, the fan, the cameras and the box the rays
// stay in. `cell_table` is the planner's table model, used unless the settings simulate another.
RunSetup makeRunSetup(const kinematics::RotaryTableModel& cell_table,
                      const LaserOptics& optics,
                      const SimulationSettings& settings) {
  RunSetup setup;
  setup.settings = &settings;
  setup.window = laserWindow(optics);
  setup.true_table = settings.simulated_table.value_or(cell_table);
  setup.cameras = cameraCentres(optics, settings.cameras);
  const std::vector<double> angles = fanAngles(setup.window, settings.rays_per_profile);
  for (const double alpha : angles) {
    setup.directions.emplace_back(0.0, std::sin(alpha), std::cos(alpha));
    // A hit beyond the far edge z_max cannot be in the trapezoid.
    setup.t_far.push_back(setup.window.z_max / std::cos(alpha));
  }
  // Fan rays end within z ≤ z_max, |y| ≤ z_max·tan α_max; camera rays run from there to the
  // camera centres: all inside this box (scanner frame).
  const double y_reach = setup.window.z_max * std::tan(std::abs(angles.front()));
  setup.reach.extend(Eigen::Vector3d(0.0, -y_reach, 0.0));
  setup.reach.extend(Eigen::Vector3d(0.0, y_reach, setup.window.z_max + kCullMargin));
  for (const Eigen::Vector3d& c : setup.cameras) setup.reach.extend(c);
  if (settings.mode == SimulationMode::kImage) {
    setup.camera.optics = optics;
    setup.camera.rows = settings.image.rows;
    setup.camera.columns = settings.image.columns;
    setup.camera.side = settings.cameras == CameraRule::kNegative ? -1 : 1;
    // Camera rays reach twice the distance to the laser plane (renderProfileImage): at most
    // 2Q − C for Q a corner of the field in the plane. The box of those and C holds them all.
    const CameraModel& camera = setup.camera;
    const double h = 0.5 * camera.rows;
    for (const double p_x : {-h, h}) {
      for (const double p_y : {-h, h}) {
        setup.reach.extend(2.0 * camera.triangulate(p_x, p_y) - camera.centre());
      }
    }
    setup.reach.extend(camera.centre());
  }
  setup.reach.min().array() -= kCullMargin;
  setup.reach.max().array() += kCullMargin;
  return setup;
}

// Image mode's preconditions (simulate() documents them).
void checkImageSettings(const SimulationSettings& settings, RayBackend backend) {
  if (settings.mode != SimulationMode::kImage) return;
  const ImageSettings& im = settings.image;
  const Reflectance& r = im.reflectance;
  if (im.rows < 2 || im.columns < 1 || !(im.thickness > 0.0) || !(im.noise >= 0.0) ||
      !(im.threshold >= 0.0) || !(im.ambient >= 0.0) || !(r.lambert >= 0.0) ||
      !(r.specular >= 0.0) || !(r.shininess >= 0.0)) {
    throw std::invalid_argument(
        "scanner simulation: image mode expects rows >= 2, columns >= 1, thickness > 0 and "
        "non-negative noise, threshold, ambient and reflectance");
  }
  if (settings.cameras != CameraRule::kPositive && settings.cameras != CameraRule::kNegative) {
    throw std::invalid_argument(
        "scanner simulation: image mode renders one camera (positive or negative)");
  }
  if (backend != RayBackend::kEmbree) {
    throw std::invalid_argument("scanner simulation: image mode needs the Embree back end");
  }
}

}  // namespace

ProfileImage ScanSimulator::renderImage(const ScanFrame& frame,
                                        std::uint32_t index,
                                        const LaserOptics& optics,
                                        const SimulationSettings& settings) const {
  SimulationSettings image_settings = settings;
  image_settings.mode = SimulationMode::kImage;
  checkImageSettings(image_settings, impl_->backend);
  const RunSetup setup = makeRunSetup(impl_->cell.table, optics, image_settings);
  Scratch& s = impl_->scratch.local();
  Eigen::Isometry3d X_WS, X_WR;
  impl_->renderImage(frame, index, setup, s, X_WS, X_WR);
  return s.image;
}

namespace {

void addStats(SimulationStats& total, const SimulationStats& st) {
  total.laser_rays += st.laser_rays;
  total.occlusion_rays += st.occlusion_rays;
  total.hits += st.hits;
  total.outside_window += st.outside_window;
  total.occluded += st.occluded;
  total.points += st.points;
  total.pixel_rays += st.pixel_rays;
  total.lit_pixels += st.lit_pixels;
}

}  // namespace

// The points reach fresh memory once. On one thread they go straight into the cloud; on more,
// each thread appends its profiles' points to its own buffer, reused batch after batch, and
// after each batch they move to the cloud in profile order. The cloud is sized for a point per
// ray of the first batch, then once for the rest of the run at the points per profile so far
// plus a quarter (it grows again only should a batch need more).
SimulationStats ScanSimulator::Impl::profiles(const std::vector<ScanFrame>& frames,
                                              const RunSetup& setup,
                                              std::size_t rays,
                                              const std::function<void()>& poll,
                                              SimulatedCloud& cloud) const {
  struct Output {
    std::vector<CloudPoint> points;
    SimulationStats stats;
  };
  struct Span {
    const std::vector<CloudPoint>* points = nullptr;
    std::size_t begin = 0;
    std::size_t end = 0;
    std::size_t offset = 0;  // where they go in the cloud
  };
  const std::size_t n = frames.size();
  const std::size_t batch = std::max<std::size_t>(1, kBatchRays / rays);
  const bool serial = tbb::this_task_arena::max_concurrency() == 1;
  tbb::enumerable_thread_specific<Output> outputs;
  std::vector<Span> spans(serial ? 0 : std::min(n, batch));
  // Room for every ray's point at once where that stays within kReserveBytes (untouched room
  // costs no memory): the cloud then never moves (each move copies it, serially).
  if (n * rays <= kReserveBytes / sizeof(CloudPoint)) detail::reserveLarge(cloud.points, n * rays);
  for (std::size_t from = 0; from < n; from += batch) {
    if (poll) poll();
    const std::size_t to = std::min(n, from + batch);
    const std::size_t size = cloud.points.size();
    if (size + (to - from) * rays > cloud.points.capacity()) {
      const std::size_t projected = from == 0 ? 0 : size + (n - from) * size / from * 5 / 4;
      detail::reserveLarge(cloud.points, std::max(size + (to - from) * rays, projected));
    }
    if (serial) {
      Scratch& s = scratch.local();
      SimulationStats& stats = outputs.local().stats;
      for (std::size_t i = from; i < to; ++i) {
        profile(frames[i], static_cast<std::uint32_t>(i), setup, s, cloud.points, stats);
      }
      continue;
    }
    // The room the batch may fill is touched by one thread while the rest cast.
    tbb::parallel_invoke([&] { detail::touchRoom(cloud.points, size, size + (to - from) * rays); },
                         [&] {
                           tbb::parallel_for(
                               tbb::blocked_range<std::size_t>(from, to),
                               [&](const tbb::blocked_range<std::size_t>& range) {
                                 Scratch& s = scratch.local();
                                 Output& out = outputs.local();
                                 for (std::size_t i = range.begin(); i != range.end(); ++i) {
                                   const std::size_t begin = out.points.size();
                                   profile(frames[i], static_cast<std::uint32_t>(i), setup, s,
                                           out.points, out.stats);
                                   spans[i - from] = {&out.points, begin, out.points.size()};
                                 }
                               });
                         });
    // The batch's points in frame order, each frame's copied in parallel to its own place.
    std::size_t total = cloud.points.size();
    for (std::size_t i = from; i < to; ++i) {
      spans[i - from].offset = total;
      total += spans[i - from].end - spans[i - from].begin;
    }
    cloud.points.resize(total);
    tbb::parallel_for(from, to, [&](std::size_t i) {
      const Span& span = spans[i - from];
      std::copy(span.points->data() + span.begin, span.points->data() + span.end,
                cloud.points.data() + span.offset);
    });
    for (Output& out : outputs) out.points.clear();
  }
  SimulationStats total;
  for (const Output& out : outputs) addStats(total, out.stats);
  return total;
}

SimulatedCloud ScanSimulator::simulate(const std::vector<ScanFrame>& frames,
                                       const LaserOptics& optics,
                                       const SimulationSettings& settings,
                                       const std::function<void()>& poll) const {
  // The job validates these; a caller that did not gets an exception, not garbage.
  if (settings.rays_per_profile < 1 || !(settings.sigma_longitudinal >= 0.0) ||
      !(settings.sigma_orthogonal >= 0.0)) {
    throw std::invalid_argument(
        "scanner simulation: expected rays_per_profile >= 1 and non-negative noise sigmas");
  }
  checkImageSettings(settings, impl_->backend);
  // Image mode: each thread holds one image with what every pixel saw (~100 bytes a pixel); on
  // many cores the threads rendering at once are fewer, so that together they stay within
  // kImageMemoryBudget. The cloud is the same on any number of threads.
  if (settings.mode == SimulationMode::kImage) {
    const double per_image = 100.0 * settings.image.rows * settings.image.columns;
    const int fit = static_cast<int>(std::max(1.0, kImageMemoryBudget / per_image));
    if (fit < tbb::this_task_arena::max_concurrency()) {
      tbb::task_arena arena(fit);
      return arena.execute([&] { return simulate(frames, optics, settings); });
    }
  }
  const RunSetup setup = makeRunSetup(impl_->cell.table, optics, settings);
  // Points per profile at most: one per fan ray, or per image column.
  const std::size_t rays = settings.mode == SimulationMode::kImage
                               ? static_cast<std::size_t>(settings.image.columns)
                               : setup.directions.size();
  SimulatedCloud cloud;
  cloud.stats = impl_->profiles(frames, setup, rays, poll, cloud);
  cloud.stats.profiles = frames.size();
  return cloud;
}

}  // namespace scanplan::scanner
