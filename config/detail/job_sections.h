#pragma once
// The sections of a job file, each read, written and described as a schema in its own file
// (job_cell.cpp, job_scanner.cpp, job_scan.cpp, job_planner.cpp, job_outputs.cpp) beside its
// conversion to SI, and put together in job.cpp. Private to config/.

#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include <scanplan/config/detail/describe.h>
#include <scanplan/config/detail/schema_out.h>
#include <scanplan/config/detail/yaml_reader.h>
#include <scanplan/config/job.h>

namespace scanplan::config {

// describe(A&, Spec&) of each section's specs, A one of YamlIn (read), YamlOut (write) and
// SchemaOut (the JSON Schema); defined in the file named above each group.

// job_cell.cpp
void describe(YamlIn& a, TableSpec& s);
void describe(YamlOut& a, TableSpec& s);
void describe(SchemaOut& a, TableSpec& s);
void describe(YamlIn& a, PartSpec& s);
void describe(YamlOut& a, PartSpec& s);
void describe(SchemaOut& a, PartSpec& s);
void describe(YamlIn& a, ObstacleSpec& s);
void describe(YamlOut& a, ObstacleSpec& s);
void describe(SchemaOut& a, ObstacleSpec& s);
void describe(YamlIn& a, SensorSpec& s);
void describe(YamlOut& a, SensorSpec& s);
void describe(SchemaOut& a, SensorSpec& s);
void describe(YamlIn& a, RampSpec& s);
void describe(YamlOut& a, RampSpec& s);
void describe(SchemaOut& a, RampSpec& s);
void describe(YamlIn& a, LengthRampSpec& s);
void describe(YamlOut& a, LengthRampSpec& s);
void describe(SchemaOut& a, LengthRampSpec& s);
void describe(YamlIn& a, PairRuleSpec& s);
void describe(YamlOut& a, PairRuleSpec& s);
void describe(SchemaOut& a, PairRuleSpec& s);
void describe(YamlIn& a, ClearanceSpec& s);
void describe(YamlOut& a, ClearanceSpec& s);
void describe(SchemaOut& a, ClearanceSpec& s);
void describe(YamlIn& a, ConstraintsSpec& s);
void describe(YamlOut& a, ConstraintsSpec& s);
void describe(SchemaOut& a, ConstraintsSpec& s);

// job_scanner.cpp
void describe(YamlIn& a, OpticsSpec& s);
void describe(YamlOut& a, OpticsSpec& s);
void describe(SchemaOut& a, OpticsSpec& s);
void describe(YamlIn& a, NoiseSpec& s);
void describe(YamlOut& a, NoiseSpec& s);
void describe(SchemaOut& a, NoiseSpec& s);
void describe(YamlIn& a, CameraSpec& s);
void describe(YamlOut& a, CameraSpec& s);
void describe(SchemaOut& a, CameraSpec& s);
void describe(YamlIn& a, LaserSpec& s);
void describe(YamlOut& a, LaserSpec& s);
void describe(SchemaOut& a, LaserSpec& s);
void describe(YamlIn& a, ScannerSpec& s);
void describe(YamlOut& a, ScannerSpec& s);
void describe(SchemaOut& a, ScannerSpec& s);
void describe(YamlIn& a, ValidationSpec& s);
void describe(YamlOut& a, ValidationSpec& s);
void describe(SchemaOut& a, ValidationSpec& s);
void describe(YamlIn& a, SimulationSpec& s);
void describe(YamlOut& a, SimulationSpec& s);
void describe(SchemaOut& a, SimulationSpec& s);
void describe(YamlIn& a, SimulationSpec::Reflectance& s);
void describe(YamlOut& a, SimulationSpec::Reflectance& s);
void describe(SchemaOut& a, SimulationSpec::Reflectance& s);

// job_scan.cpp
void describe(YamlIn& a, WaypointSpec& s);
void describe(YamlOut& a, WaypointSpec& s);
void describe(SchemaOut& a, WaypointSpec& s);
void describe(YamlIn& a, PathElementSpec& s);
void describe(YamlOut& a, PathElementSpec& s);
void describe(SchemaOut& a, PathElementSpec& s);
void describe(YamlIn& a, AutoSpec& s);
void describe(YamlOut& a, AutoSpec& s);
void describe(SchemaOut& a, AutoSpec& s);
void describe(YamlIn& a, ScanSpec& s);
void describe(YamlOut& a, ScanSpec& s);
void describe(SchemaOut& a, ScanSpec& s);

// job_planner.cpp
void describe(YamlIn& a, MapSpec& s);
void describe(YamlOut& a, MapSpec& s);
void describe(SchemaOut& a, MapSpec& s);
void describe(YamlIn& a, RaySpec& s);
void describe(YamlOut& a, RaySpec& s);
void describe(SchemaOut& a, RaySpec& s);
void describe(YamlIn& a, DpSpec& s);
void describe(YamlOut& a, DpSpec& s);
void describe(SchemaOut& a, DpSpec& s);
void describe(YamlIn& a, OmplSpec& s);
void describe(YamlOut& a, OmplSpec& s);
void describe(SchemaOut& a, OmplSpec& s);
void describe(YamlIn& a, RefineSpec& s);
void describe(YamlOut& a, RefineSpec& s);
void describe(SchemaOut& a, RefineSpec& s);
void describe(YamlIn& a, PlannerSpec& s);
void describe(YamlOut& a, PlannerSpec& s);
void describe(SchemaOut& a, PlannerSpec& s);

// job_outputs.cpp
void describe(YamlIn& a, TriggerSpec& s);
void describe(YamlOut& a, TriggerSpec& s);
void describe(SchemaOut& a, TriggerSpec& s);
void describe(YamlIn& a, OutputsSpec& s);
void describe(YamlOut& a, OutputsSpec& s);
void describe(SchemaOut& a, OutputsSpec& s);

// The list items whose schema is the union of several variants (schema_out.h), declared before
// any schema is made of them.
template <>
std::vector<ShapeSpec> schemaVariants<ShapeSpec>();  // job_cell.cpp
template <>
std::vector<ObstacleSpec> schemaVariants<ObstacleSpec>();  // job_cell.cpp
template <>
std::vector<SensorSpec> schemaVariants<SensorSpec>();  // job_cell.cpp
template <>
std::vector<PathElementSpec> schemaVariants<PathElementSpec>();  // job_scan.cpp

/// simulation.mode image: one camera, and noise in the image rather than on the points; errors
/// name the scanner key at its place in the file (job_scanner.cpp).
void checkImageMode(const YamlIn& a, const JobSpec& s);

/// Applies `--set key.path=value` (`text`) to the job's YAML tree; the value, and every key and
/// mapping the override created, go into `origins`, so errors about them name the override
/// (overrides.cpp).
void applyOverride(YAML::Node root, const std::string& text, OverrideOrigins& origins);

}  // namespace scanplan::config
