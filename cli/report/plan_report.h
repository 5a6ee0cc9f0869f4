#pragma once

#include <string>

#include <scanplan/config/job.h>
#include <scanplan/kinematics/cell.h>
#include <scanplan/pipeline/plan_scan.h>
#include "cli/io/json.h"

namespace scanplan::cli {

/// report.json of `plan` (format "scanplan plan report 1"): lengths in mm, angles in degrees,
/// times in s. `times` are the stage times to report (the caller's total included); the keys of
/// `extra` (an object) are added at the top level (e.g. `setups`).
std::string planReportJson(const config::JobSpec& job,
                           const kinematics::CellModel& cell,
                           const pipeline::ScanPlan& plan,
                           const pipeline::StageTimes& times,
                           const Json& extra = Json::object());

}  // namespace scanplan::cli
