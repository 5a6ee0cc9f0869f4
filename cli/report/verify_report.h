#pragma once
// What `plan`, `validate` and `simulate` say about a trajectory's validation and its simulated
// scan: summary lines for the terminal and JSON objects for reports.

#include <cstddef>
#include <string>

#include <scanplan/pipeline/certificate.h>
#include <scanplan/pipeline/simulation.h>
#include <scanplan/planner/validation.h>
#include "cli/io/json.h"

namespace scanplan::cli {

/// Validation summary lines for stdout (every violation, at most `max_lines` of them).
std::string validationSummary(const planner::ValidationReport& report, std::size_t max_lines = 12);
/// The report as a JSON object (lengths in mm, angles in degrees, times in s).
Json validationJson(const planner::ValidationReport& report);

/// The simulation's counts and coverage, two lines.
std::string simulationSummary(const pipeline::SimulationRun& run);
/// The certificate's line: the scannable share of the area, how much of it is covered, and why
/// the rest cannot be scanned; with `suggest_setups`, notes on what another setup could add.
std::string certificateSummary(const pipeline::Certificate& certificate,
                               bool suggest_setups = true);
/// report.json's `coverage`: area_fraction, scannable_fraction, covered_of_scannable, by_reason.
Json certificateJson(const pipeline::SimulationRun& run, const pipeline::Certificate& certificate);
/// The run's counts and the coverage as a JSON object (areas in mm²).
Json simulationJson(const pipeline::SimulationRun& run);

}  // namespace scanplan::cli
