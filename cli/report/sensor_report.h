#pragma once
// What `plan`, `validate` and `simulate` write about the cell's sensors (seed §5.1–5.2) along a
// trajectory: sensors.csv, summary lines and report.json's `sensors` section.

#include <string>
#include <vector>

#include <scanplan/collision/scene.h>
#include <scanplan/collision/sensors.h>
#include "cli/io/json.h"

namespace scanplan::cli {

/// sensors.csv: a header, then one row per sample: `t_s`, then per sensor (job order) a
/// presence sensor's `<name>` (1 when it fires, else 0) and `<name>_bodies` (the overlapping
/// bodies, joined by ';'), or a distance sensor's `<name>_mm` (the range when it reads, else
/// empty), `<name>_status` (reading, no_target, too_close, receiver_occluded) and `<name>_body`
/// (the body hit, else empty). Times in s (9 decimals), ranges in mm (6 decimals).
std::string sensorsCsv(const collision::Scene& scene, const collision::SensorEvaluation& e);

/// One line per sensor, e.g. "sensor     light_curtain: fires 12.300–14.000 s (link6,
/// scanner); expect never: broken" or "sensor     part_present: reads 0.000–20.000 s,
/// 150.0–152.3 mm; expect always: met"; at most a few spans each.
std::string sensorsSummary(const collision::Scene& scene, const collision::SensorEvaluation& e);

/// report.json's `sensors`: per sensor its name, kind, carrier, rule, whether the rule held,
/// the spans where it fires (s, with the bodies) and, for distance sensors, the range read (mm).
Json sensorsJson(const collision::Scene& scene, const collision::SensorEvaluation& e);

/// `check`: each sensor at one pose, a line each: "sensor       light_curtain: fires (link6,
/// scanner)", "… : clear", "… : 100.000 mm (part)", "… : no reading, receiver_occluded (part
/// at 145.200 mm)". `readings` as SensorEvaluator::evaluate() returns them.
std::string sensorReadingsText(const collision::Scene& scene,
                               const std::vector<collision::SensorReading>& readings);
/// The same as JSON: per sensor name, fires, and the bodies (presence) or status, distance_mm
/// and body (distance).
Json sensorReadingsJson(const collision::Scene& scene,
                        const std::vector<collision::SensorReading>& readings);

}  // namespace scanplan::cli
