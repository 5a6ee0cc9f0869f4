#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <scanplan/collision/scene.h>
#include <scanplan/config/robot_file.h>
#include <scanplan/config/spec.h>
#include <scanplan/kinematics/cell.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/planner/constraints.h>
#include <scanplan/planner/objective.h>
#include <scanplan/scanner/laser_model.h>
#include <scanplan/scanner/path_generators.h>

namespace scanplan::config {

/// `table`: the rotary table. Axis frame A at θ = 0 (z = rotation axis, origin at the centre
/// of the table top), its size, travel, dynamics and calibration errors.
struct TableSpec {
  PoseSpec axis{{600.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
  double radius_mm = 200.0;
  double height_mm = 150.0;
  bool continuous = true;
  double min_deg = -180.0;
  double max_deg = 180.0;
  double max_speed_deg_s = 30.0;
  double max_accel_deg_s2 = 60.0;
  std::array<double, 2> eccentricity_mm{};
  std::array<double, 2> tilt_deg{};
};

/// `part`: the part mesh and its placement on the table top (X_RP).
struct PartSpec {
  FilePath mesh;
  std::string units = "mm";
  double scale = 1.0;
  std::string up_axis = "z";  ///< the file's up direction (x, y, z, -x, -y, -z), made +z
  /// "table": the part's lowest point on the table top, its bounding box centred on the axis
  /// (after units, scale, up_axis and the pose's rotation; pose.xyz_mm is then an offset from
  /// there), and ring heights count from the table top. "none": the pose as given.
  std::string place = "none";
  PoseSpec pose;
};

/// `scanner.optics`: Eq. 5 camera geometry (seed §5.3).
struct OpticsSpec {
  double a_mm = 100.0;
  double b_mm = 100.0;
  double phi_deg = 60.0;
  double gamma_deg = 10.0;
};

/// `scanner.noise`: Gaussian measurement noise of the simulated scanner (docs/design.md §6).
struct NoiseSpec {
  double longitudinal_mm = 0.0;  ///< σ_l, along the laser ray
  double orthogonal_mm = 0.0;    ///< σ_o, across it in the laser plane
  int seed = 1;
};

/// `scanner.camera`: the image of `simulation.mode: image` and how the stripe is read from it.
struct CameraSpec {
  int rows = 256;                 ///< H, pixels across the depth window (f = H / (2 tan γ), Eq. 4)
  int columns = 0;                ///< W, pixels along the line; 0: scanner.rays_per_profile
  double noise_grey = 0.0;        ///< σ of the sensor noise, grey levels (0…255)
  double ambient_grey = 12.0;     ///< ambient light on a surface facing the camera, grey levels
  double threshold_grey = 40.0;   ///< a stripe peak must exceed it, grey levels
  std::string detection = "cog";  ///< cog (centre of gravity) | gauss (3-point Gaussian fit)
};

/// `scanner.laser`: the laser sheet.
struct LaserSpec {
  double thickness_mm = 1.0;  ///< full 1/e² width of the sheet (Gaussian across it)
};

/// `scanner`: the laser frame on the flange (X_FS), the housing's shapes in that frame, optics,
/// and how it acquires (frame rate, fan, cameras, noise).
struct ScannerSpec {
  PoseSpec mount{{0.0, 0.0, 100.0}, {0.0, 0.0, 0.0}};
  std::vector<ShapeSpec> body;
  OpticsSpec optics;
  double frame_rate_hz = 100.0;      ///< profiles per second (also the validation step)
  int rays_per_profile = 200;        ///< laser fan rays per profile
  std::string cameras = "positive";  ///< positive | negative | both | either
  NoiseSpec noise;
  CameraSpec camera;
  LaserSpec laser;
  /// kg, the scanner's mass: the programs' payload. 0: not known (no payload is set).
  double mass_kg = 0.0;
  /// mm, its centre of gravity in the flange frame; when not given, the centre of the
  /// housing's (body's) bounding box, or the laser frame's origin without a body.
  std::array<double, 3> cog_mm{};
  bool cog_given = false;
};

/// `validation`: the check of the planned motion before it goes to the robot.
struct ValidationSpec {
  bool enabled = true;                   ///< `plan` validates the trajectory
  double collision_resolution_mm = 0.1;  ///< motion resolution of the continuous collision check
};

/// `simulation`: the scanner simulation along the planned motion.
struct SimulationSpec {
  bool enabled = true;  ///< `plan` simulates the scan
  /// The real table's calibration error on top of the planner's model (`table.eccentricity_mm`,
  /// `table.tilt_deg`): the part is posed on the erroneous table, the points are mapped with the
  /// model, as on the real cell.
  std::array<double, 2> extra_eccentricity_mm{};
  std::array<double, 2> extra_tilt_deg{};
  int coverage_min_points = 1;     ///< points on a triangle for it to count as covered
  std::string mode = "geometric";  ///< geometric (laser fan, Eq. 5) | image (camera image, Eq. 4)
  /// Image mode: surface reflectance of the simulated cell (grey levels per unit irradiance).
  struct Reflectance {
    double lambert = 0.8;
    double specular = 0.0;
    double shininess = 20.0;
  } reflectance;
  int profile_images = 4;  ///< image mode: profile images `plan`/`simulate` write as PNG
};

/// `scan.paths[].points[]`.
struct WaypointSpec {
  std::array<double, 3> xyz_mm{};
  std::array<double, 3> rpy_deg{};
  double speed_mm_s = 50.0;
  double rotation_speed_deg_s = 30.0;
  bool scanning = true;
};

/// `scan.paths[]`: one element of the scan path (ring, raster, waypoints or file).
struct PathElementSpec {
  std::string type = "ring";
  // ring
  double height_mm = 50.0;
  double tilt_deg = 20.0;
  double start_deg = 0.0;
  double extent_deg = 360.0;
  double speed_deg_s = 20.0;
  double distance_mm = -1.0;  ///< negative: auto (from the part mesh)
  bool has_axis = false;
  std::array<double, 2> axis_xy_mm{};
  // raster
  std::array<double, 3> view{0.0, 0.0, -1.0};
  std::array<double, 3> pass_direction{1.0, 0.0, 0.0};
  double overlap = 0.2;
  double lead_mm = 20.0;
  double speed_mm_s = 30.0;
  // waypoints
  std::vector<WaypointSpec> points;
  // file
  FilePath file;
};

/// `scan`: the scan path and its sampling.
/// `scan.auto`: the automatic, coverage-driven scan (present: enabled).
struct AutoSpec {
  bool enabled = false;  ///< the job has a `scan.auto` mapping
  double max_incidence_deg =
      60.0;                       ///< laser and camera ray against the normal, for a point to count
  double point_spacing_mm = 0.0;  ///< 0: the line's point pitch at mid depth
  double target_coverage = 0.98;  ///< of the scannable area
  int max_passes = 250;
  double time_budget_s = 60.0;     ///< for choosing the passes
  double max_program_s = 0.0;      ///< the program's time at most; 0: no limit
  double sample_spacing_mm = 3.0;  ///< area samples the passes are chosen on
};

struct ScanSpec {
  double dt_s = 0.1;
  double transfer_speed_mm_s = 100.0;
  double retreat_mm = 50.0;
  std::vector<PathElementSpec> paths;
  AutoSpec auto_scan;  ///< `scan.auto`
};

/// `map`: the configuration map grid.
struct MapSpec {
  double angle_step_deg = 1.0;
  std::string branch = "auto";
  double memory_limit_mb = 8192.0;
};

/// `planner.ray`: Ray Shooting (docs/design.md §5.1).
struct RaySpec {
  int rays = 21;
  int horizon = 5;
  int starts = 36;
  double blocked_penalty_s = 1000.0;
  bool cost_to_go = true;   ///< rays scored with the rest of the scan (false: the seed's rays)
  bool dp_fallback = true;  ///< DP's optimum when no ray run reaches the end
};

/// `planner.dp`: the exact baseline's angle grid.
struct DpSpec {
  int angle_subdivisions = 0;  ///< 0: auto (fine enough for 3 acceleration steps each way)
};

/// `planner.ompl`: the OMPL search.
struct OmplSpec {
  int max_iterations = 10000;  ///< ends the search: the same seed gives the same path
  double time_limit_s = 10.0;  ///< backstop per branch (a run it ends is not reproducible)
  int seed = 1;
};

/// `planner.refine`: NLopt smoothing of the chosen path.
struct RefineSpec {
  bool enabled = true;
  double time_limit_s = 2.0;
};

/// `planner`: which search, the objective's weights and the start. The table's speed and
/// acceleration bounds come from `table.max_speed_deg_s` / `table.max_accel_deg_s2`.
struct PlannerSpec {
  std::string method = "ray";      ///< ray | dp | ompl
  double k_omega = 1.0;            ///< s²/rad², weight of ω² in J
  double k_alpha = 0.1;            ///< s⁴/rad², weight of α² in J
  std::string start_deg = "auto";  ///< "auto" (search the first column) or a table angle
  bool dp_gap = true;  ///< also run DP on the chosen branch and report the gap to the optimum
  RaySpec ray;
  DpSpec dp;
  OmplSpec ompl;
  RefineSpec refine;
};

/// `obstacles[]`: a fixture or obstacle: a shape (as in robot files) carried by the world or
/// the table. Boxes may be given by `corner_mm` + `size_mm` instead of a centred pose (sizes
/// may then be negative, as workcell tools write them).
struct ObstacleSpec {
  std::string name;
  std::string carrier = "world";
  bool by_corner = false;
  std::array<double, 3> corner_mm{};
  ShapeSpec shape;
};

/// The most sensors a job may have.
inline constexpr std::size_t kMaxSensors = 64;

/// `sensors[]`: a presence or distance sensor in the cell (seed §5.1–5.2), on the world or a
/// body, with an optional rule on its output.
struct SensorSpec {
  std::string name;
  std::string kind = "presence";  ///< presence | distance
  std::string carrier = "world";  ///< world or a body: base, a link, scanner, table, part, obstacle
  PoseSpec pose;                  ///< the sensor frame in the carrier's frame
  // presence: the volume, centred on the sensor frame (a cylinder along its z)
  std::string shape = "box";  ///< box | sphere | cylinder
  std::array<double, 3> size_mm{100.0, 100.0, 100.0};
  double radius_mm = 50.0;
  double length_mm = 100.0;
  // distance: a beam along +z of the sensor frame
  double min_range_mm = 0.0;
  double max_range_mm = 1000.0;
  bool has_receiver = false;
  std::array<double, 3> receiver_mm{};  ///< the receiver in the sensor frame (triangulation)
  // the rule
  std::string expect = "any";  ///< any | never | always | during | not_during
  std::array<double, 2> window_s{};
};

/// A ramp on a unitless measure (Eq. 8 form).
struct RampSpec {
  double low = 0.0;
  double high = 1.0;
  double gamma = 1.0;
};

/// A ramp on a length, mm.
struct LengthRampSpec {
  double low_mm = 0.0;
  double high_mm = 1.0;
  double gamma = 1.0;
};

/// `constraints.clearance.pairs[]`: a rule for the pairs whose bodies match `a` and `b`.
struct PairRuleSpec {
  std::string a;
  std::string b;
  bool exclude = false;
  bool include = false;
  double d_low_mm = -1.0;   ///< negative: unchanged
  double d_high_mm = -1.0;  ///< negative: unchanged
  double gamma = -1.0;      ///< negative: unchanged
};

struct ClearanceSpec {
  double d_low_mm = 5.0;
  double d_high_mm = 30.0;
  double gamma = 1.0;
  std::vector<PairRuleSpec> pairs;
  /// How the maps measure robot link meshes: "auto" (a link's simplified convex hull where it
  /// lies within hull_margin_mm of the mesh, else its convex pieces where they fit
  /// piece_margin_mm and max_pieces, else the mesh), "pieces", "hull" or "exact".
  std::string link_meshes = "auto";
  int hull_vertices = 32;        ///< at most this many vertices per hull
  double hull_margin_mm = 2.0;   ///< "auto": the largest margin a hull may have
  double piece_margin_mm = 2.0;  ///< "auto", "pieces": the most the pieces may stand outside
  int max_pieces = 128;          ///< "auto": at most this many pieces per link mesh
};

/// `constraints`: the static constraints of a pose (Eq. 6–8).
struct ConstraintsSpec {
  std::array<double, 6> joint_limit_gamma{0.2, 0.2, 0.2, 0.2, 0.2, 0.2};
  RampSpec wrist{0.05, 0.25, 1.0};
  RampSpec elbow{0.05, 0.25, 1.0};
  LengthRampSpec shoulder{30.0, 120.0, 1.0};
  ClearanceSpec clearance;
};

/// `outputs.trigger`: the scanner's trigger, a digital output on during each scan pass.
struct TriggerSpec {
  std::string rapid_signal;      ///< RAPID's signal name; empty: "do<output>"
  int output = 0;                ///< the output's number; 0: none
  bool on_at_scan_start = true;  ///< false: off while scanning (an active-low input)
};

/// `outputs`: the robot programs `plan` writes.
struct OutputsSpec {
  TriggerSpec trigger;
  double servo_period_s = 0.008;  ///< URScript's servoj period (CB3 0.008, e-Series 0.002)
  /// Formats (programFormatNames()). When the job does not say: defaultPrograms(robot), the
  /// robot controller's language and the CSV.
  std::vector<std::string> programs;
  std::string program_name = "scan";  ///< made a valid identifier of each language
};

/// A whole job file, every default filled in.
struct JobSpec {
  std::string name = "job";
  FilePath robot_file;  ///< empty when the robot is given inline
  RobotSpec robot;
  PoseSpec robot_base;
  TableSpec table;
  PartSpec part;
  ScannerSpec scanner;
  std::vector<ObstacleSpec> obstacles;
  std::vector<SensorSpec> sensors;
  ConstraintsSpec constraints;
  ScanSpec scan;
  MapSpec map;
  PlannerSpec planner;
  ValidationSpec validation;
  SimulationSpec simulation;
  OutputsSpec outputs;
  std::filesystem::path source;  ///< the job file itself
};

/// Loads and validates a job file (and the robot file it names). Each override "key.path=value"
/// (e.g. "planner.ray.horizon=20", "scan.paths[0].height_mm=60") replaces or adds that value
/// before validation, as if the file said so; errors in it name the override.
JobSpec loadJob(const std::filesystem::path& file, const std::vector<std::string>& overrides = {});

/// Every file the job reads: the job file, the robot file, the part mesh, the mesh files of the
/// robot's links, the scanner's housing and the obstacles, and path files (resolved paths).
std::vector<std::filesystem::path> jobInputFiles(const JobSpec& job);
/// A JSON Schema (draft-07) of the job file: every key, its type, range and choices, and which
/// keys are required; unknown keys are refused (additionalProperties: false). For editors (VS
/// Code's YAML extension) and scripts; `scanplan job schema` prints it.
std::string jobSchema();
/// The fully resolved job as YAML (robot inline, paths absolute, every default present).
std::string jobToYaml(const JobSpec& job);
/// A stable identity of the job's content: a hash of the resolved job with file paths as
/// written (so it does not depend on where the files live), hex.
std::string jobHash(const JobSpec& job);
/// The part's mesh as the job loads it (units, scale, up axis): errors name the job file and
/// `part.mesh`; a part more than 1 000 000 mm across (lengths' bound) is refused naming
/// `part.scale`, the size and the limit.
kinematics::LoadedMesh loadPartMesh(const JobSpec& job, const kinematics::PartModel& part);
/// Builds the cell model: robot kinematics (OPW checked against DH), table, part, scanner,
/// obstacles.
kinematics::CellModel buildCell(const JobSpec& job);
/// The job's clearance thresholds and pair rules, SI.
collision::ClearanceConfig clearanceConfig(const JobSpec& job);
/// The job's pose constraints (Eq. 7, singularity ramps), SI.
planner::ConstraintSettings constraintSettings(const JobSpec& job);
/// "RIGHTY ABOVE NOFLIP" → branch; nullopt unless exactly one word of each pair is given.
std::optional<kinematics::IkBranch> parseBranch(const std::string& words);
/// The scanner optics, SI.
scanner::LaserOptics laserOptics(const JobSpec& job);
/// The table-angle problem's weights and bounds (planner section + table dynamics), SI.
planner::PlannerSettings plannerSettings(const JobSpec& job);
/// The fixed start angle (rad), or nullopt for "auto".
std::optional<double> startAngle(const JobSpec& job);
/// The scan path request (reads path files), SI.
scanner::PathRequest pathRequest(const JobSpec& job);

}  // namespace scanplan::config
