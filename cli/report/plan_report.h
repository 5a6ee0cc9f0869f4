#pragma once

#include <string>

#include "cli/config/job.h"
#include "cli/io/json.h"
#include "kinematics/cell.h"
#include "pipeline/plan_scan.h"

namespace scanplan::cli {

/// report.json of `plan` (format "scanplan plan report 1"): lengths in mm, angles in degrees,
/// times in s. `times` are the stage times to report (the caller's total included); the keys of
/// `extra` (an object) are added at the top level (e.g. `setups`).
std::string planReportJson(const JobSpec& job,
                           const kinematics::CellModel& cell,
                           const pipeline::ScanPlan& plan,
                           const pipeline::StageTimes& times,
                           const Json& extra = Json::object());

}  // namespace scanplan::cli
