#include "pipeline/simulation.h"

#include <chrono>
#include <vector>

#include "planner/validation.h"

namespace scanplan::pipeline {

SimulationRun simulateTrajectory(const kinematics::CellModel& cell,
                                 const kinematics::TriangleMesh& part,
                                 const scanner::LaserOptics& optics,
                                 const SimulationSettings& settings,
                                 const kinematics::Trajectory& trajectory) {
  const auto start = std::chrono::steady_clock::now();
  const kinematics::Trajectory dense = planner::densify(trajectory, 1.0 / settings.frame_rate_hz);
  std::vector<scanner::ScanFrame> frames;
  for (const auto& s : dense.samples) {
    if (s.scanning) frames.push_back({s.t, s.theta, s.q});
  }
  const scanner::ScanSimulator simulator(cell, part);
  SimulationRun run;
  run.frames = frames.size();
  run.cloud = simulator.simulate(frames, optics, settings.scanner);
  run.coverage = scanner::computeCoverage(part, run.cloud.points, settings.coverage);
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

}  // namespace scanplan::pipeline
