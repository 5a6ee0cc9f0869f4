#include <scanplan/pipeline/simulation.h>

#include <algorithm>
#include <chrono>
#include <vector>

#include <scanplan/pipeline/cancel.h>
#include <scanplan/planner/validation.h>

namespace scanplan::pipeline {

namespace {

// The distance between neighbouring points of one profile at the middle of the depth window.
double midDepthPitch(const scanner::LaserOptics& optics, int rays_per_profile) {
  const scanner::LaserWindow window = scanner::laserWindow(optics);
  const double width = 2.0 * window.halfWidth(0.5 * (window.z_min + window.z_max));
  return width / std::max(1, rays_per_profile - 1);
}

// The camera images of the settings' number of profiles: the profiles with the most points,
// greedily, each at least a tenth of the run from those already chosen (closer ones only when
// the run has too few far apart).
std::vector<std::pair<std::uint32_t, scanner::ProfileImage>> profileImages(
    const scanner::ScanSimulator& simulator,
    const std::vector<scanner::ScanFrame>& frames,
    const scanner::SimulatedCloud& cloud,
    const scanner::LaserOptics& optics,
    const SimulationSettings& settings) {
  std::vector<std::pair<std::uint32_t, scanner::ProfileImage>> images;
  const std::size_t wanted = std::min(settings.profile_images, frames.size());
  if (wanted == 0) return images;
  std::vector<std::size_t> points(frames.size(), 0);
  for (const auto& p : cloud.points) ++points[p.profile];
  std::vector<std::uint32_t> order(frames.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return points[a] > points[b]; });
  std::vector<std::uint32_t> chosen;
  for (std::size_t gap = std::max<std::size_t>(1, frames.size() / 10); chosen.size() < wanted;
       gap /= 2) {
    for (const std::uint32_t i : order) {
      if (chosen.size() == wanted) break;
      const bool apart = std::all_of(chosen.begin(), chosen.end(), [&](std::uint32_t c) {
        return (c > i ? c - i : i - c) >= std::max<std::size_t>(gap, 1);
      });
      if (apart) chosen.push_back(i);
    }
    if (gap <= 1) break;
  }
  std::sort(chosen.begin(), chosen.end());
  for (const std::uint32_t i : chosen) {
    scanner::ProfileImage image = simulator.renderImage(frames[i], i, optics, settings.scanner);
    std::vector<scanner::SceneHit>().swap(image.hit);  // the PNGs need the grey levels only
    images.emplace_back(i, std::move(image));
  }
  return images;
}

}  // namespace

double coverageSpacing(const SimulationSettings& settings, const scanner::LaserOptics& optics) {
  return settings.point_spacing > 0.0 ? settings.point_spacing
                                      : midDepthPitch(optics, settings.scanner.rays_per_profile);
}

SimulationRun simulateTrajectory(const kinematics::CellModel& cell,
                                 const kinematics::TriangleMesh& part,
                                 const scanner::LaserOptics& optics,
                                 const SimulationSettings& settings,
                                 const kinematics::Trajectory& trajectory,
                                 const std::atomic<bool>* cancel) {
  const auto start = std::chrono::steady_clock::now();
  const kinematics::Trajectory dense = planner::densify(trajectory, 1.0 / settings.frame_rate_hz);
  std::vector<scanner::ScanFrame> frames;
  for (const auto& s : dense.samples) {
    if (s.scanning) frames.push_back({s.t, s.theta, s.q});
  }
  const scanner::ScanSimulator simulator(cell, part);
  SimulationRun run;
  run.frames = frames.size();
  run.cloud =
      simulator.simulate(frames, optics, settings.scanner, [cancel] { pollCancel(cancel); });
  pollCancel(cancel);
  run.profile_images = profileImages(simulator, frames, run.cloud, optics, settings);
  run.coverage = scanner::computeCoverage(part, run.cloud.points, settings.coverage);
  run.point_spacing = coverageSpacing(settings, optics);
  run.sampling = scanner::sampleArea(part, 2.0 * run.point_spacing, settings.max_area_samples);
  const scanner::AreaSampling& sampling = run.sampling;
  // A point counts when it lies on the part and the laser met the surface within the limit.
  const scanner::PartPoints on_part =
      scanner::pointsOnPart(run.cloud.points, settings.max_incidence);
  run.area_samples = sampling.samples.size();
  run.area = scanner::areaCoverage(sampling, on_part.p, run.point_spacing, &on_part.t);
  const std::vector<std::uint8_t> facing = scanner::facesTable(
      sampling, cell.part.X_RP, settings.max_incidence, scanner::laserWindow(optics).z_max);
  if (!facing.empty()) {
    run.faces_table_fraction = static_cast<double>(std::count(facing.begin(), facing.end(), 1)) /
                               static_cast<double>(facing.size());
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

}  // namespace scanplan::pipeline
