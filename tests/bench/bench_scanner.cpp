// Scanner simulation throughput: rays per second per thread (fan rays + hit → camera rays) on the
// shared Stanford bunny (69 451 triangles; a generated bumpy sphere of similar size when the
// shared data is absent) on the demo cell's table, Embree vs the brute-force loop in one run,
// plus the 2-thread speed-up and a check that both back ends give the same points.
// Usage (from the repository root):
//   build/tests/bench/bench_scanner [PROFILES] [RAYS] [embree|single|hash]
// "embree": skip the brute-force runs; "single": only the one-thread runs (for a profiler or
// callgrind); "hash": no timing, a hash of every point field and counter per camera rule, with
// and without noise, on the scene as it is and with two obstacles added, each checked equal on
// one thread (a change that must not alter results leaves them all the same).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <tbb/task_arena.h>
#include <time.h>

#include <scanplan/config/job.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/shape.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/scanner/laser_model.h>
#include <scanplan/scanner/raycaster.h>
#include <scanplan/scanner/simulator.h>

using namespace scanplan;
using Clock = std::chrono::steady_clock;

namespace {

double seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// CPU time of the calling thread: on a shared machine the honest per-thread measure (a task
// arena of one runs its work in the calling thread).
double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// A closed sphere of radius ~70 mm with bumps, `rings` × `segments` quads: 2·rings·segments − 2
// segments triangles.
kinematics::TriangleMesh bumpySphere(int rings, int segments) {
  kinematics::TriangleMesh mesh;
  for (int r = 0; r <= rings; ++r) {
    const double polar = std::numbers::pi * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double azimuth = 2.0 * std::numbers::pi * s / segments;
      const double radius = 0.07 * (1.0 + 0.12 * std::sin(5.0 * polar) * std::sin(4.0 * azimuth));
      mesh.vertices.push_back(radius * Eigen::Vector3d(std::sin(polar) * std::cos(azimuth),
                                                       std::sin(polar) * std::sin(azimuth),
                                                       std::cos(polar)));
    }
  }
  const auto at = [&](int r, int s) { return r * segments + (s % segments); };
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      if (r > 0) mesh.triangles.emplace_back(at(r, s), at(r + 1, s), at(r, s + 1));
      if (r + 1 < rings) mesh.triangles.emplace_back(at(r, s + 1), at(r + 1, s), at(r + 1, s + 1));
    }
  }
  return mesh;
}

// Ring frames around `aim` (part frame): scanner `distance` away, tilted down, the table turned
// as near as the arm allows to putting the scanner between part and robot.
std::vector<scanner::ScanFrame> ringFrames(const kinematics::CellModel& cell,
                                           const Eigen::Vector3d& aim,
                                           double distance,
                                           double tilt,
                                           int count,
                                           double t0) {
  std::vector<scanner::ScanFrame> frames;
  std::optional<kinematics::JointVector> last;
  kinematics::IkRequest request;
  request.within_limits_only = true;
  for (int i = 0; i < count; ++i) {
    const double beta = 2.0 * std::numbers::pi * i / count;
    const Eigen::Vector3d radial(std::cos(beta), std::sin(beta), 0.0);
    const Eigen::Vector3d z = -std::cos(tilt) * radial - std::sin(tilt) * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d x(-std::sin(beta), std::cos(beta), 0.0);
    Eigen::Isometry3d X_PS = Eigen::Isometry3d::Identity();
    X_PS.linear().col(0) = x;
    X_PS.linear().col(1) = z.cross(x);
    X_PS.linear().col(2) = z;
    X_PS.translation() = aim - distance * z;
    for (int step = 0; step <= 36; ++step) {
      const double turn = deg(5.0) * ((step + 1) / 2) * (step % 2 ? 1.0 : -1.0);
      const double theta = kinematics::wrapToPi(std::numbers::pi - beta + turn);
      const auto solutions = cell.robot.ik(cell.flangeTarget(theta, X_PS), request);
      if (solutions.empty()) continue;
      const kinematics::IkSolution* best = &solutions.front();
      if (last) {
        for (const auto& s : solutions) {
          if ((s.q - *last).norm() < (best->q - *last).norm()) best = &s;
        }
      }
      frames.push_back({t0 + 0.01 * i, theta, best->q});
      last = best->q;
      break;
    }
  }
  return frames;
}

struct Timing {
  scanner::SimulatedCloud cloud;
  double seconds = 0.0;
  double cpu_seconds = 0.0;  // calling thread
  double rays() const {
    return static_cast<double>(cloud.stats.laser_rays + cloud.stats.occlusion_rays);
  }
  double raysPerSecond() const { return rays() / seconds; }
  double raysPerCpuSecond() const { return rays() / cpu_seconds; }
};

Timing timed(const scanner::ScanSimulator& sim,
             const std::vector<scanner::ScanFrame>& frames,
             const scanner::LaserOptics& optics,
             const scanner::SimulationSettings& settings,
             int threads,
             int repeats) {
  Timing best;
  tbb::task_arena arena(threads);
  for (int r = 0; r < repeats; ++r) {
    Timing t;
    arena.execute([&] {
      const auto start = Clock::now();
      const double cpu = threadCpuSeconds();
      t.cloud = sim.simulate(frames, optics, settings);
      t.cpu_seconds = threadCpuSeconds() - cpu;
      t.seconds = seconds(start);
    });
    if (r == 0 || t.seconds < best.seconds) best = std::move(t);
  }
  return best;
}

bool sameCloud(const scanner::SimulatedCloud& a, const scanner::SimulatedCloud& b) {
  if (a.points.size() != b.points.size()) return false;
  for (std::size_t i = 0; i < a.points.size(); ++i) {
    const auto &p = a.points[i], &q = b.points[i];
    if (p.profile != q.profile || p.ray != q.ray || p.part_triangle != q.part_triangle ||
        (p.p_P - q.p_P).norm() > 1e-9) {
      return false;
    }
  }
  return true;
}

// FNV-1a over the bytes of every point field and every counter: equal hashes, equal clouds to
// the last bit.
class Fnv1a {
 public:
  template <typename T>
  void add(const T& value) {
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    for (const unsigned char b : bytes) hash_ = (hash_ ^ b) * 0x100000001B3ull;
  }
  std::uint64_t value() const { return hash_; }

 private:
  std::uint64_t hash_ = 0xCBF29CE484222325ull;
};

std::uint64_t cloudHash(const scanner::SimulatedCloud& cloud) {
  Fnv1a h;
  for (const scanner::CloudPoint& p : cloud.points) {
    h.add(p.p_P.x());
    h.add(p.p_P.y());
    h.add(p.p_P.z());
    h.add(p.t);
    h.add(p.profile);
    h.add(p.ray);
    h.add(p.range);
    h.add(p.incidence);
    h.add(p.part_triangle);
  }
  const scanner::SimulationStats& s = cloud.stats;
  for (const std::size_t c : {s.profiles, s.laser_rays, s.occlusion_rays, s.hits, s.outside_window,
                              s.occluded, s.points}) {
    h.add(c);
  }
  return h.value();
}

}  // namespace

int main(int argc, char** argv) {
  const int profiles = argc > 1 ? std::max(10, std::atoi(argv[1])) : 3000;
  const int rays = argc > 2 ? std::max(1, std::atoi(argv[2])) : 200;
  const std::string mode = argc > 3 ? argv[3] : "";
  const bool single = mode == "single";
  const bool with_brute_force = mode.empty();

  const config::JobSpec job = config::loadJob("data/jobs/demo_rings.yaml");
  kinematics::CellModel cell = config::buildCell(job);
  const scanner::LaserOptics optics = config::laserOptics(job);

  const std::filesystem::path bunny_file =
      std::filesystem::path(SCANPLAN_SHARED_DATA_DIR) / "meshes/stlmodels_bunny.bin.stl";
  kinematics::TriangleMesh part;
  std::string part_name;
  if (std::filesystem::exists(bunny_file)) {
    kinematics::MeshLoadOptions options;
    options.units = kinematics::LengthUnit::kMetre;
    part = kinematics::loadMesh(bunny_file, options).mesh;
    part_name = "Stanford bunny";
  } else {
    part = bumpySphere(186, 187);
    part_name = "generated bumpy sphere (shared bunny absent)";
  }
  const Eigen::AlignedBox3d box = part.bounds();
  cell.part.X_RP = Eigen::Isometry3d::Identity();
  cell.part.X_RP.translation() << -box.center().x(), -box.center().y(), -box.min().z();

  // Rings at three heights and tilts, repeated up to the profile count.
  std::vector<scanner::ScanFrame> ring;
  for (const auto& [dz, tilt] : {std::pair{-0.02, 15.0}, {0.0, 30.0}, {0.02, 55.0}}) {
    const auto r = ringFrames(cell, box.center() + Eigen::Vector3d(0, 0, dz), 0.22, deg(tilt), 120,
                              static_cast<double>(ring.size()));
    ring.insert(ring.end(), r.begin(), r.end());
  }
  std::vector<scanner::ScanFrame> frames;
  while (static_cast<int>(frames.size()) < profiles) {
    for (const auto& f : ring) {
      if (static_cast<int>(frames.size()) == profiles) break;
      frames.push_back(f);
    }
  }

  auto start = Clock::now();
  const scanner::ScanSimulator embree(cell, part);
  const double build_embree = seconds(start);
  scanner::SimulatorOptions brute_options;
  brute_options.backend = scanner::RayBackend::kBruteForce;
  start = Clock::now();
  const scanner::ScanSimulator brute(cell, part, brute_options);
  const double build_brute = seconds(start);

  std::printf("bench_scanner: %s, %zu part triangles (%zu in the scene), %d profiles x %d rays\n",
              part_name.c_str(), part.triangles.size(), embree.triangleCount(), profiles, rays);
  std::printf("scene build: Embree %.1f ms, brute force %.1f ms\n", 1e3 * build_embree,
              1e3 * build_brute);

  if (mode == "hash") {
    // The scene as it is (only the table group in reach), then with a post beside the part on
    // the robot's side, where the scanner looks from (world group), and a block on the table (a
    // third mesh in the table group), so that rays meet several groups and meshes.
    kinematics::CellModel cluttered = cell;
    kinematics::Shape post;
    post.geometry = kinematics::Box{Eigen::Vector3d(0.015, 0.015, 0.2)};
    Eigen::Vector3d to_robot = cell.table.X_WA.inverse() * cell.X_WB.translation();  // A frame
    to_robot.z() = 0.0;
    post.X_BG = cell.table.X_WA;
    post.X_BG.translation() += cell.table.X_WA.linear() *
                               (0.085 * to_robot.normalized() + Eigen::Vector3d(0.02, 0.0, 0.1));
    cluttered.obstacles.push_back({"post", kinematics::Carrier::kWorld, {post}});
    kinematics::Shape block;
    block.geometry = kinematics::Box{Eigen::Vector3d(0.04, 0.04, 0.04)};
    block.X_BG.translation() << -0.07, -0.06, 0.02;
    cluttered.obstacles.push_back({"block", kinematics::Carrier::kTable, {block}});
    const scanner::ScanSimulator cluttered_sim(cluttered, part);
    for (const scanner::ScanSimulator* sim : {&embree, &cluttered_sim}) {
      for (const scanner::CameraRule rule :
           {scanner::CameraRule::kPositive, scanner::CameraRule::kNegative,
            scanner::CameraRule::kBoth, scanner::CameraRule::kEither}) {
        for (const double sigma : {0.0, 5e-5}) {
          scanner::SimulationSettings settings;
          settings.rays_per_profile = rays;
          settings.cameras = rule;
          settings.sigma_longitudinal = sigma;
          settings.sigma_orthogonal = 0.5 * sigma;
          const scanner::SimulatedCloud cloud = sim->simulate(frames, optics, settings);
          scanner::SimulatedCloud serial;
          tbb::task_arena(1).execute([&] { serial = sim->simulate(frames, optics, settings); });
          std::printf("hash %s rule %d sigma %g: %zu points (%zu not on the part), %016llx%s\n",
                      sim == &embree ? "plain" : "cluttered", static_cast<int>(rule), sigma,
                      cloud.points.size(),
                      static_cast<std::size_t>(std::count_if(
                          cloud.points.begin(), cloud.points.end(),
                          [](const scanner::CloudPoint& q) { return q.part_triangle < 0; })),
                      static_cast<unsigned long long>(cloudHash(cloud)),
                      cloudHash(serial) == cloudHash(cloud) ? "" : " (1 thread: DIFFERENT)");
        }
      }
    }
    return 0;
  }

  // Reference, same machine state: the bare Embree single-ray cast (scanner::Raycaster, one
  // rtcIntersect1 per ray) of the same fans against the part alone, one thread.
  if (!single) {
    const scanner::Raycaster raycaster(part);
    const auto angles = scanner::fanAngles(scanner::laserWindow(optics), rays);
    std::size_t count = 0, hits = 0;
    const double cpu = threadCpuSeconds();
    const auto begin = Clock::now();
    for (const scanner::ScanFrame& f : frames) {
      const Eigen::Isometry3d X_PS = (cell.table.X_WR(f.theta) * cell.part.X_RP).inverse() *
                                     cell.X_WB * cell.robot.fk(f.q) * cell.scanner.X_FS;
      for (const double a : angles) {
        const Eigen::Vector3d d = X_PS.linear() * Eigen::Vector3d(0.0, std::sin(a), std::cos(a));
        if (raycaster.cast(X_PS.translation(), d, 0.0, 0.2)) ++hits;
        ++count;
      }
    }
    const double wall = seconds(begin), used = threadCpuSeconds() - cpu;
    std::printf(
        "reference: bare Embree rtcIntersect1, part only: %zu rays (%zu hits), %.2f M "
        "rays/s wall, %.2f M per CPU-second\n",
        count, hits, static_cast<double>(count) / wall / 1e6,
        static_cast<double>(count) / used / 1e6);

    // The kind of rays docs/design.md §6's throughput anchor was measured with: random rays from a
    // box twice the part's size through random points of the part's box (many miss).
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const Eigen::AlignedBox3d part_box = part.bounds();
    const Eigen::Vector3d size = part_box.sizes();
    std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> random_rays;
    for (int i = 0; i < 600000; ++i) {
      const Eigen::Vector3d a(unit(rng), unit(rng), unit(rng)), b(unit(rng), unit(rng), unit(rng));
      const Eigen::Vector3d from = part_box.min() - 0.5 * size + 2.0 * a.cwiseProduct(size);
      const Eigen::Vector3d to = part_box.min() + b.cwiseProduct(size);
      random_rays.emplace_back(from, to - from);
    }
    hits = 0;
    const double cpu2 = threadCpuSeconds();
    for (const auto& [o, d] : random_rays) {
      if (raycaster.cast(o, d)) ++hits;
    }
    const double used2 = threadCpuSeconds() - cpu2;
    std::printf(
        "reference: bare Embree rtcIntersect1, random rays through the part's box: %zu "
        "hits of %zu, %.2f M per CPU-second\n",
        hits, random_rays.size(), static_cast<double>(random_rays.size()) / used2 / 1e6);
  }

  for (const scanner::CameraRule rule :
       {scanner::CameraRule::kPositive, scanner::CameraRule::kBoth}) {
    scanner::SimulationSettings settings;
    settings.rays_per_profile = rays;
    settings.cameras = rule;
    const char* name = rule == scanner::CameraRule::kPositive ? "one camera" : "both cameras";
    const Timing one = timed(embree, frames, optics, settings, 1, 3);
    const Timing two = single ? Timing{} : timed(embree, frames, optics, settings, 2, 3);
    const auto& s = one.cloud.stats;
    std::printf(
        "\n[%s] %zu fan rays + %zu camera rays; %zu hits, %zu outside the window, %zu occluded, "
        "%zu points\n",
        name, s.laser_rays, s.occlusion_rays, s.hits, s.outside_window, s.occluded, s.points);
    std::printf(
        "Embree, 1 thread : %.3f s wall, %.3f s CPU = %.2f M rays/s per thread wall, %.2f M per "
        "CPU-second (%.1f k profiles/s)  target >= 10 M: %s\n",
        one.seconds, one.cpu_seconds, one.raysPerSecond() / 1e6, one.raysPerCpuSecond() / 1e6,
        static_cast<double>(frames.size()) / one.seconds / 1e3,
        std::max(one.raysPerSecond(), one.raysPerCpuSecond()) >= 1e7 ? "met" : "MISSED");
    if (!single) {
      std::printf("Embree, 2 threads: %.3f s = %.2f M rays/s (%.2fx)\n", two.seconds,
                  two.raysPerSecond() / 1e6, one.seconds / two.seconds);
    }

    if (!with_brute_force) continue;
    // Brute force on a few profiles spread over the run, compared with Embree on the same.
    std::vector<scanner::ScanFrame> few;
    for (std::size_t i = 0; i < frames.size() && few.size() < 12; i += frames.size() / 12) {
      few.push_back(frames[i]);
    }
    const Timing slow = timed(brute, few, optics, settings, 1, 1);
    const Timing fast = timed(embree, few, optics, settings, 1, 1);
    std::printf(
        "brute force, 1 thread: %zu profiles, %.3f s CPU = %.4f M rays/s per CPU-second; "
        "Embree is %.0fx faster (CPU time); same points: %s\n",
        few.size(), slow.cpu_seconds, slow.raysPerCpuSecond() / 1e6,
        one.raysPerCpuSecond() / slow.raysPerCpuSecond(),
        sameCloud(slow.cloud, fast.cloud) ? "yes" : "NO");
  }
  return 0;
}
