#pragma once

#include <filesystem>

#include <scanplan/config/job.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/pipeline/certificate.h>
#include <scanplan/pipeline/simulation.h>
#include "cli/io/write_settings.h"

namespace scanplan::cli {

/// cloud.ply, coverage.ply and cloud.png (the cloud and the coverage from three sides) in `dir`;
/// with the run's profile images (image mode), profiles/profile_NNNNNN.png (NNNNNN the profile
/// index): the camera image, and beside it the same with the detected stripe in red.
void writeSimulationOutputs(const std::filesystem::path& dir,
                            const config::JobSpec& job,
                            const kinematics::TriangleMesh& part,
                            const pipeline::SimulationRun& run,
                            const WriteSettings& settings = {});

/// The scannability certificate (scan.auto): uncovered.ply (the area samples not covered, each
/// with its reason) and certificate.png (the part's samples coloured by class, three sides).
/// coverage_time.png and .svg: the share of the scannable area covered against program time,
/// with the times to 95 % and 98 % and the program's end marked. Nothing without a curve.
void writeCoverageCurve(const std::filesystem::path& dir,
                        const pipeline::CoverageCurve& curve,
                        double program_s,
                        const WriteSettings& settings = {});

void writeCertificateOutputs(const std::filesystem::path& dir,
                             const kinematics::TriangleMesh& part,
                             const scanner::AreaSampling& sampling,
                             const pipeline::Certificate& certificate,
                             const WriteSettings& settings = {});

}  // namespace scanplan::cli
