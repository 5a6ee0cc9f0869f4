#pragma once

#include <filesystem>

#include "cli/config/job.h"
#include "kinematics/mesh.h"
#include "pipeline/simulation.h"

namespace scanplan::cli {

/// cloud.ply, coverage.ply and cloud.png (the cloud and the coverage from three sides) in `dir`.
void writeSimulationOutputs(const std::filesystem::path& dir,
                            const JobSpec& job,
                            const kinematics::TriangleMesh& part,
                            const pipeline::SimulationRun& run);

}  // namespace scanplan::cli
