#include "cli/config/job.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <regex>
#include <set>
#include <sstream>
#include <type_traits>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "cli/config/detail/describe.h"
#include "cli/config/detail/schema_out.h"
#include "cli/config/robot_urdf.h"
#include "cli/programs/programs.h"
#include "kinematics/error.h"
#include "kinematics/placement.h"
#include "kinematics/units.h"
#include "planner/planner.h"

namespace scanplan::cli {
namespace {

template <class A>
void describeTable(A& a, TableSpec& s) {
  a.section("axis", s.axis);
  a.field("radius_mm", s.radius_mm, Expect::positive());
  a.field("height_mm", s.height_mm, Expect::positive());
  a.field("continuous", s.continuous);
  a.field("min_deg", s.min_deg, Expect::range(-3600.0, 3600.0));
  a.field("max_deg", s.max_deg, Expect::range(-3600.0, 3600.0));
  a.field("max_speed_deg_s", s.max_speed_deg_s, Expect::positive());
  a.field("max_accel_deg_s2", s.max_accel_deg_s2, Expect::positive());
  a.field("eccentricity_mm", s.eccentricity_mm);
  a.field("tilt_deg", s.tilt_deg, Expect::range(-10.0, 10.0));
  if constexpr (A::kReading) {
    if (!(s.min_deg < s.max_deg)) {
      a.fail("max_deg", formatNumber(s.max_deg),
             fmt::format("a limit greater than min_deg ({})", formatNumber(s.min_deg)));
    }
  }
}

inline const std::vector<std::string> kUpAxes = {"z", "y", "x", "-z", "-y", "-x"};

// The rotation that turns the file's `up` direction into +z (a quarter or half turn).
Eigen::Matrix3d upRotation(const std::string& up) {
  using Eigen::AngleAxisd;
  using Eigen::Vector3d;
  const double q = std::numbers::pi / 2;
  if (up == "y") return AngleAxisd(q, Vector3d::UnitX()).matrix();    // +y → +z
  if (up == "-y") return AngleAxisd(-q, Vector3d::UnitX()).matrix();  // −y → +z
  if (up == "x") return AngleAxisd(-q, Vector3d::UnitY()).matrix();   // +x → +z
  if (up == "-x") return AngleAxisd(q, Vector3d::UnitY()).matrix();   // −x → +z
  if (up == "-z") return AngleAxisd(2 * q, Vector3d::UnitX()).matrix();
  return Eigen::Matrix3d::Identity();
}

inline const std::vector<std::string> kPlacements = {"none", "table"};

template <class A>
void describePart(A& a, PartSpec& s) {
  a.require("mesh");
  a.field("mesh", s.mesh);
  a.field("units", s.units, Expect::oneOf(kLengthUnits));
  a.field("scale", s.scale, Expect::positive());
  a.field("up_axis", s.up_axis, Expect::oneOf(kUpAxes));
  a.field("place", s.place, Expect::oneOf(kPlacements));
  a.section("pose", s.pose);
}

template <class A>
void describeOptics(A& a, OpticsSpec& s) {
  a.field("a_mm", s.a_mm, Expect::positive());
  a.field("b_mm", s.b_mm);
  a.field("phi_deg", s.phi_deg, Expect{0.0, 90.0, true, true, {}});
  a.field("gamma_deg", s.gamma_deg, Expect{0.0, 45.0, true, true, {}});
  if constexpr (A::kReading) {
    if (!(s.gamma_deg < s.phi_deg) || !(s.phi_deg + s.gamma_deg < 90.0)) {
      a.fail("gamma_deg", formatNumber(s.gamma_deg),
             "0 < gamma_deg < phi_deg and phi_deg + gamma_deg < 90 (Eq. 5 needs both view edges "
             "to cross the laser plane)");
    }
    const double z_min = s.a_mm / std::tan(deg(s.phi_deg + s.gamma_deg)) + s.b_mm;
    if (!(z_min > 0.0)) {
      a.fail("b_mm", formatNumber(s.b_mm),
             "a value that puts the depth window in front of the scanner (z_min > 0)");
    }
  }
}

template <class A>
void describeNoise(A& a, NoiseSpec& s) {
  a.field("longitudinal_mm", s.longitudinal_mm, Expect::range(0.0, 100.0));
  a.field("orthogonal_mm", s.orthogonal_mm, Expect::range(0.0, 100.0));
  a.field("seed", s.seed, Expect::range(0, 2147483647));
}

inline const std::vector<std::string> kDetections = {"cog", "gauss"};

template <class A>
void describeCamera(A& a, CameraSpec& s) {
  a.field("rows", s.rows, Expect::range(2, 16384));
  a.field("columns", s.columns, Expect::range(0, 16384));
  a.field("noise_grey", s.noise_grey, Expect::range(0.0, 255.0));
  a.field("ambient_grey", s.ambient_grey, Expect::range(0.0, 255.0));
  a.field("threshold_grey", s.threshold_grey, Expect::range(0.0, 254.0));
  a.field("detection", s.detection, Expect::oneOf(kDetections));
}

template <class A>
void describeLaser(A& a, LaserSpec& s) {
  a.field("thickness_mm", s.thickness_mm, Expect{0.0, 100.0, true, false, {}});
}

inline const std::vector<std::string> kCameraRules = {"positive", "negative", "both", "either"};

template <class A>
void describeScanner(A& a, ScannerSpec& s) {
  a.section("mount", s.mount);
  a.list("body", s.body, 0, 64);
  a.section("optics", s.optics);
  a.field("frame_rate_hz", s.frame_rate_hz, Expect{0.1, 100000.0, false, false, {}});
  a.field("rays_per_profile", s.rays_per_profile, Expect::range(1, 100000));
  a.field("cameras", s.cameras, Expect::oneOf(kCameraRules));
  a.section("noise", s.noise);
  a.section("camera", s.camera);
  a.section("laser", s.laser);
  a.field("mass_kg", s.mass_kg, Expect::range(0.0, 1000.0));
  if constexpr (A::kReading) s.cog_given = a.has("cog_mm");
  if (A::kReading || s.cog_given) a.field("cog_mm", s.cog_mm, Expect::range(-10000.0, 10000.0));
}

template <class A>
void describeValidation(A& a, ValidationSpec& s) {
  a.field("enabled", s.enabled);
  a.field("collision_resolution_mm", s.collision_resolution_mm,
          Expect{0.001, 100.0, false, false, {}});
}

inline const std::vector<std::string> kSimulationModes = {"geometric", "image"};

template <class A>
void describeReflectance(A& a, SimulationSpec::Reflectance& s);

template <class A>
void describeSimulation(A& a, SimulationSpec& s) {
  a.field("enabled", s.enabled);
  a.field("extra_eccentricity_mm", s.extra_eccentricity_mm, Expect::range(-1000.0, 1000.0));
  a.field("extra_tilt_deg", s.extra_tilt_deg, Expect::range(-10.0, 10.0));
  a.field("coverage_min_points", s.coverage_min_points, Expect::range(1, 1000000));
  a.field("mode", s.mode, Expect::oneOf(kSimulationModes));
  a.section("reflectance", s.reflectance);
  a.field("profile_images", s.profile_images, Expect::range(0, 1000));
}

template <class A>
void describeReflectance(A& a, SimulationSpec::Reflectance& s) {
  a.field("lambert", s.lambert, Expect::range(0.0, 100.0));
  a.field("specular", s.specular, Expect::range(0.0, 100.0));
  a.field("shininess", s.shininess, Expect::range(0.0, 10000.0));
}

// simulation.mode image: one camera, and noise in the image rather than on the points (the
// errors name the scanner key at its place in the file).
void checkImageMode(const YamlIn& a, const JobSpec& s) {
  if (s.simulation.mode != "image") return;
  const YAML::Node& root = a.node();
  const YAML::Node scanner = std::as_const(root)["scanner"];
  // Each thread holds one image with what every pixel saw: ~100 bytes a pixel.
  constexpr long long kMaxImagePixels = 4'194'304;  // 2048 × 2048, ~400 MB per thread
  const CameraSpec& camera = s.scanner.camera;
  const long long columns = camera.columns > 0 ? camera.columns : s.scanner.rays_per_profile;
  const long long pixels = static_cast<long long>(camera.rows) * columns;
  if (pixels > kMaxImagePixels) {
    const std::string value =
        fmt::format("{} rows x {} columns = {} pixels", camera.rows, columns, pixels);
    const std::string expected = fmt::format(
        "at most {} pixels per image with simulation.mode: image (each thread holds one, ~100 "
        "bytes a pixel)",
        kMaxImagePixels);
    const YAML::Node node = std::as_const(scanner)["camera"];
    if (node.IsDefined() && node.IsMap() &&
        (std::as_const(node)["columns"].IsDefined() || std::as_const(node)["rows"].IsDefined())) {
      YamlIn in(node, "scanner.camera", a.file(), a.overrides());
      in.fail(std::as_const(node)["columns"].IsDefined() ? "columns" : "rows", value, expected);
    }
    YamlIn in(scanner, "scanner", a.file(), a.overrides());
    in.fail("rays_per_profile", value, expected + " (columns default to rays_per_profile)");
  }
  // The kept profile images hold their grey levels (4 bytes a pixel) until they are written.
  constexpr long long kMaxKeptPixels = 67'108'864;  // 256 MB
  const long long kept = static_cast<long long>(s.simulation.profile_images) * pixels;
  if (kept > kMaxKeptPixels) {
    YamlIn in(std::as_const(root)["simulation"], "simulation", a.file(), a.overrides());
    in.fail("profile_images",
            fmt::format("{} images of {} pixels = {} pixels", s.simulation.profile_images, pixels,
                        kept),
            fmt::format("at most {} pixels kept for the profile PNGs: fewer images or a smaller "
                        "scanner.camera",
                        kMaxKeptPixels));
  }
  if (camera.ambient_grey >= camera.threshold_grey) {
    const YAML::Node node = std::as_const(scanner)["camera"];
    YamlIn in(node, "scanner.camera", a.file(), a.overrides());
    in.fail("threshold_grey", formatNumber(camera.threshold_grey),
            fmt::format("above scanner.camera.ambient_grey ({}) with simulation.mode: image: "
                        "else every lit surface reads as the stripe",
                        formatNumber(camera.ambient_grey)));
  }
  if (s.scanner.cameras == "both" || s.scanner.cameras == "either") {
    YamlIn in(scanner, "scanner", a.file(), a.overrides());
    in.fail("cameras", "'" + s.scanner.cameras + "'",
            "positive or negative with simulation.mode: image (it renders one camera)");
  }
  for (const auto& [key, value] : {std::pair{"longitudinal_mm", s.scanner.noise.longitudinal_mm},
                                   std::pair{"orthogonal_mm", s.scanner.noise.orthogonal_mm}}) {
    if (value == 0.0) continue;
    YamlIn in(std::as_const(scanner)["noise"], "scanner.noise", a.file(), a.overrides());
    in.fail(key, formatNumber(value),
            "0 with simulation.mode: image (its noise is scanner.camera.noise_grey, in the image)");
  }
}

inline const std::vector<std::string> kPathTypes = {"ring", "raster", "waypoints", "file"};

template <class A>
void describeWaypoint(A& a, WaypointSpec& s) {
  a.require("xyz_mm");
  a.field("xyz_mm", s.xyz_mm);
  a.field("rpy_deg", s.rpy_deg);
  a.field("speed_mm_s", s.speed_mm_s, Expect::positive());
  a.field("rotation_speed_deg_s", s.rotation_speed_deg_s, Expect::positive());
  a.field("scanning", s.scanning);
}

template <class A>
void describePathElement(A& a, PathElementSpec& s) {
  a.require("type");
  a.field("type", s.type, Expect::oneOf(kPathTypes));
  if (s.type == "ring") {
    a.require("height_mm");
    a.field("height_mm", s.height_mm);
    a.field("tilt_deg", s.tilt_deg, Expect::range(-80.0, 80.0));
    a.field("start_deg", s.start_deg);
    a.field("extent_deg", s.extent_deg, Expect::range(-3600.0, 3600.0));
    a.field("speed_deg_s", s.speed_deg_s, Expect::positive());
    if (A::kReading || s.distance_mm > 0.0)
      a.field("distance_mm", s.distance_mm, Expect::positive());
    if constexpr (A::kReading) {
      s.has_axis = a.has("axis_xy_mm");
      if (s.extent_deg == 0.0) a.fail("extent_deg", "0", "a non-zero angle");
    }
    if (s.has_axis) a.field("axis_xy_mm", s.axis_xy_mm);
  } else if (s.type == "raster") {
    a.field("view", s.view);
    a.field("pass_direction", s.pass_direction);
    a.field("overlap", s.overlap, Expect{0.0, 0.95, false, false, {}});
    a.field("lead_mm", s.lead_mm, Expect::nonNegative());
    a.field("speed_mm_s", s.speed_mm_s, Expect::positive());
    if constexpr (A::kReading) {
      if (Eigen::Vector3d(s.view.data()).norm() < 1e-9)
        a.fail("view", "[0, 0, 0]", "a non-zero direction");
    }
  } else if (s.type == "waypoints") {
    a.require("points");
    a.list("points", s.points, 2, 100000);
  } else {
    a.require("file");
    a.field("file", s.file);
  }
}

template <class A>
void describeAuto(A& a, AutoSpec& s) {
  a.field("max_incidence_deg", s.max_incidence_deg, Expect{1.0, 89.0, false, false, {}});
  a.field("point_spacing_mm", s.point_spacing_mm, Expect{0.0, 100.0, false, false, {}});
  if constexpr (A::kReading) {
    // Finer than any line scanner resolves: the passes, at spacing × frame rate, would crawl.
    constexpr double kFinest = 0.001;
    if (s.point_spacing_mm > 0.0 && s.point_spacing_mm < kFinest) {
      a.fail("point_spacing_mm", formatNumber(s.point_spacing_mm),
             fmt::format("0 (the line's point pitch at mid depth) or at least {} mm: the passes "
                         "scan at the spacing times the frame rate, and finer than a micrometre "
                         "no line scanner resolves",
                         kFinest));
    }
  }
  a.field("target_coverage", s.target_coverage, Expect{0.01, 1.0, false, false, {}});
  a.field("max_passes", s.max_passes, Expect::range(1, 1000));
  a.field("time_budget_s", s.time_budget_s, Expect{0.1, 86400.0, false, false, {}});
  a.field("max_program_s", s.max_program_s, Expect{0.0, 86400.0, false, false, {}});
  a.field("sample_spacing_mm", s.sample_spacing_mm, Expect{0.2, 100.0, false, false, {}});
}

template <class A>
void describeScan(A& a, ScanSpec& s) {
  a.field("dt_s", s.dt_s, Expect{0.001, 10.0, false, false, {}});
  a.field("transfer_speed_mm_s", s.transfer_speed_mm_s, Expect::positive());
  a.field("retreat_mm", s.retreat_mm, Expect::nonNegative());
  a.list("paths", s.paths, 0, 1000);
  // Present means enabled; a job without it writes none (jobToYaml reads back the same job).
  if constexpr (A::kReading) s.auto_scan.enabled = a.has("auto");
  if (s.auto_scan.enabled) a.section("auto", s.auto_scan);
}

template <class A>
void describeMap(A& a, MapSpec& s) {
  a.field("angle_step_deg", s.angle_step_deg, Expect{0.01, 90.0, false, false, {}});
  a.field("branch", s.branch);
  a.field("memory_limit_mb", s.memory_limit_mb, Expect::positive());
  if constexpr (A::kReading) {
    if (s.branch != "auto" && !parseBranch(s.branch)) {
      a.fail("branch", "'" + s.branch + "'",
             "auto or three V+ words, e.g. 'RIGHTY ABOVE NOFLIP' (LEFTY/RIGHTY, ABOVE/BELOW, "
             "FLIP/NOFLIP)");
    }
  }
}

std::optional<double> parseFiniteNumber(const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

const std::vector<std::string>& kPlannerMethods = planner::plannerNames();

template <class A>
void describeRay(A& a, RaySpec& s) {
  a.field("rays", s.rays, Expect::range(1, 401));
  a.field("horizon", s.horizon, Expect::range(1, 1000));
  a.field("starts", s.starts, Expect::range(1, 100000));
  a.field("blocked_penalty_s", s.blocked_penalty_s, Expect::nonNegative());
  a.field("cost_to_go", s.cost_to_go);
  a.field("dp_fallback", s.dp_fallback);
}

template <class A>
void describeDp(A& a, DpSpec& s) {
  a.field("angle_subdivisions", s.angle_subdivisions, Expect::range(0, 64));
}

template <class A>
void describeOmpl(A& a, OmplSpec& s) {
  a.field("max_iterations", s.max_iterations, Expect::range(1, 100000000));
  a.field("time_limit_s", s.time_limit_s, Expect{0.01, 3600.0, false, false, {}});
  a.field("seed", s.seed, Expect::range(0, 2147483647));
}

template <class A>
void describeRefine(A& a, RefineSpec& s) {
  a.field("enabled", s.enabled);
  a.field("time_limit_s", s.time_limit_s, Expect{0.01, 3600.0, false, false, {}});
}

template <class A>
void describePlanner(A& a, PlannerSpec& s) {
  a.field("method", s.method, Expect::oneOf(kPlannerMethods));
  a.field("k_omega", s.k_omega, Expect::nonNegative());
  a.field("k_alpha", s.k_alpha, Expect::nonNegative());
  a.field("start_deg", s.start_deg);
  a.field("dp_gap", s.dp_gap);
  a.section("ray", s.ray);
  a.section("dp", s.dp);
  a.section("ompl", s.ompl);
  a.section("refine", s.refine);
  if constexpr (A::kReading) {
    if (s.start_deg != "auto" && !parseFiniteNumber(s.start_deg)) {
      a.fail("start_deg", "'" + s.start_deg + "'", "auto or a table angle in degrees");
    }
  }
}

inline const std::vector<std::string> kCarriers = {"world", "table"};

// Names of the cell's own bodies and of the pair rules' groups (collision/scene.h).
inline const std::vector<std::string> kReservedBodyNames = {"base", "scanner", "table",
                                                            "part", "robot",   "obstacles"};

template <class A>
void describeObstacle(A& a, ObstacleSpec& s) {
  a.require("name");
  a.field("name", s.name);
  if constexpr (A::kReading) {
    // Pair rules address bodies by name, glob and group: an obstacle must be addressable.
    const bool link = s.name.size() > 4 && s.name.starts_with("link") &&
                      s.name.find_first_not_of("0123456789", 4) == std::string::npos;
    if (s.name.empty() || link || s.name.find_first_of("*?[]") != std::string::npos ||
        std::find(kReservedBodyNames.begin(), kReservedBodyNames.end(), s.name) !=
            kReservedBodyNames.end()) {
      a.fail("name", s.name,
             "a name of its own: not a body or group name (base, link1 … link6, scanner, table, "
             "part, robot, obstacles) and no glob characters (* ? [ ])");
    }
  }
  a.field("carrier", s.carrier, Expect::oneOf(kCarriers));
  if constexpr (A::kReading) s.by_corner = a.has("corner_mm");
  if (!s.by_corner) {
    describe(a, s.shape);
    return;
  }
  // Corner + size, as workcell tools write boxes: sizes may be negative (normalised later).
  a.require("type");
  a.require("size_mm");
  a.field("type", s.shape.type, Expect::oneOf({"box"}));
  a.field("corner_mm", s.corner_mm);
  a.field("size_mm", s.shape.size_mm);
  if constexpr (A::kReading) {
    for (double v : s.shape.size_mm) {
      if (v == 0.0)
        a.fail("size_mm", "a zero side",
               "non-zero sides (negative ones extend from the corner the other way)");
    }
    if (a.has("pose"))
      a.fail("pose", "given with corner_mm",
             "either corner_mm + size_mm or a centred box with pose");
  }
}

inline const std::vector<std::string> kSensorKinds = {"presence", "distance"};
inline const std::vector<std::string> kSensorShapes = {"box", "sphere", "cylinder"};
inline const std::vector<std::string> kSensorRules = {"any", "never", "always", "during",
                                                      "not_during"};
// A sensor's lengths: positive and at most a kilometre (as every length of a job).
inline const Expect kSensorLength{0.0, 1e6, true, false, {}};

template <class A>
void describeSensor(A& a, SensorSpec& s) {
  a.require("name");
  a.field("name", s.name);
  if constexpr (A::kReading) {
    // The name heads sensors.csv's columns and the report's lines.
    static const std::regex kName("[A-Za-z_][A-Za-z0-9_.-]{0,63}");
    if (!std::regex_match(s.name, kName)) {
      a.fail("name", "'" + clipForMessage(s.name) + "'",
             "a letter or _, then letters, digits, _, . or -, at most 64 characters");
    }
  }
  a.require("kind");
  a.field("kind", s.kind, Expect::oneOf(kSensorKinds));
  a.field("carrier", s.carrier);
  if constexpr (A::kReading) {
    if (s.carrier.empty()) a.fail("carrier", "''", "world or the name of a body of the cell");
  }
  a.section("pose", s.pose);
  if (s.kind == "presence") {
    a.require("shape");
    a.field("shape", s.shape, Expect::oneOf(kSensorShapes));
    if (s.shape == "box") {
      a.require("size_mm");
      a.field("size_mm", s.size_mm, kSensorLength);
    } else {
      a.require("radius_mm");
      a.field("radius_mm", s.radius_mm, kSensorLength);
      if (s.shape == "cylinder") {
        a.require("length_mm");
        a.field("length_mm", s.length_mm, kSensorLength);
      }
    }
  } else {
    a.require("max_range_mm");
    a.field("min_range_mm", s.min_range_mm, Expect::range(0.0, 1e6));
    a.field("max_range_mm", s.max_range_mm, kSensorLength);
    if constexpr (A::kReading) {
      s.has_receiver = a.has("receiver_mm");
      if (!(s.min_range_mm < s.max_range_mm)) {
        a.fail("max_range_mm", formatNumber(s.max_range_mm),
               "a range above min_range_mm (" + formatNumber(s.min_range_mm) + ")");
      }
    }
    if (s.has_receiver) a.field("receiver_mm", s.receiver_mm, Expect::range(-1e6, 1e6));
  }
  a.field("expect", s.expect, Expect::oneOf(kSensorRules));
  if (s.expect == "during" || s.expect == "not_during") {
    a.require("window_s");
    a.field("window_s", s.window_s, Expect::range(0.0, 1e9));
    if constexpr (A::kReading) {
      if (!(s.window_s[0] <= s.window_s[1])) {
        a.fail("window_s",
               "[" + formatNumber(s.window_s[0]) + ", " + formatNumber(s.window_s[1]) + "]",
               "[t0_s, t1_s] with t0_s <= t1_s");
      }
    }
  }
}

template <class A>
void describeRamp(A& a, RampSpec& s) {
  a.field("low", s.low, Expect::range(0.0, 1.0));
  a.field("high", s.high, Expect::range(0.0, 1.0));
  a.field("gamma", s.gamma, Expect::positive());
  if constexpr (A::kReading) {
    if (!(s.low < s.high))
      a.fail("high", formatNumber(s.high), "a value above low (" + formatNumber(s.low) + ")");
  }
}

template <class A>
void describeLengthRamp(A& a, LengthRampSpec& s) {
  a.field("low_mm", s.low_mm, Expect::nonNegative());
  a.field("high_mm", s.high_mm, Expect::positive());
  a.field("gamma", s.gamma, Expect::positive());
  if constexpr (A::kReading) {
    if (!(s.low_mm < s.high_mm))
      a.fail("high_mm", formatNumber(s.high_mm),
             "a value above low_mm (" + formatNumber(s.low_mm) + ")");
  }
}

template <class A>
void describePairRule(A& a, PairRuleSpec& s) {
  a.require("a");
  a.require("b");
  a.field("a", s.a);
  a.field("b", s.b);
  a.field("exclude", s.exclude);
  a.field("include", s.include);
  if constexpr (A::kReading) {
    if (s.exclude && s.include)
      a.fail("include", "true together with exclude", "at most one of exclude, include");
  }
  if (!A::kReading && s.d_low_mm < 0.0 && s.d_high_mm < 0.0 && s.gamma < 0.0) return;
  if (A::kReading || s.d_low_mm >= 0.0) a.field("d_low_mm", s.d_low_mm, Expect::nonNegative());
  if (A::kReading || s.d_high_mm >= 0.0) a.field("d_high_mm", s.d_high_mm, Expect::positive());
  if (A::kReading || s.gamma >= 0.0) a.field("gamma", s.gamma, Expect::positive());
}

template <class A>
void describeClearance(A& a, ClearanceSpec& s) {
  a.field("d_low_mm", s.d_low_mm, Expect::nonNegative());
  a.field("d_high_mm", s.d_high_mm, Expect::positive());
  a.field("gamma", s.gamma, Expect::positive());
  a.list("pairs", s.pairs, 0, 1000);
  a.field("link_meshes", s.link_meshes, Expect::oneOf({"auto", "hull", "exact"}));
  a.field("hull_vertices", s.hull_vertices, Expect::range(8, 1000));
  a.field("hull_margin_mm", s.hull_margin_mm, Expect::nonNegative());
  if constexpr (A::kReading) {
    if (!(s.d_low_mm < s.d_high_mm)) {
      a.fail("d_high_mm", formatNumber(s.d_high_mm),
             "a distance above d_low_mm (" + formatNumber(s.d_low_mm) + ")");
    }
  }
}

template <class A>
void describeConstraints(A& a, ConstraintsSpec& s) {
  a.field("joint_limit_gamma", s.joint_limit_gamma, Expect::positive());
  a.section("wrist", s.wrist);
  a.section("elbow", s.elbow);
  a.section("shoulder", s.shoulder);
  a.section("clearance", s.clearance);
}

template <class A>
void describeTrigger(A& a, TriggerSpec& s) {
  a.field("output", s.output, Expect::range(0, 4096));
  a.field("on_at_scan_start", s.on_at_scan_start);
  a.field("rapid_signal", s.rapid_signal);
  if constexpr (A::kReading) {
    static const std::regex kName("[A-Za-z][A-Za-z0-9_]{0,31}");
    if (!s.rapid_signal.empty() && !std::regex_match(s.rapid_signal, kName))
      a.fail("rapid_signal", "'" + clipForMessage(s.rapid_signal) + "'",
             "a RAPID identifier: a letter, then letters, digits or _, at most 32 characters");
  }
}

template <class A>
void describeOutputs(A& a, OutputsSpec& s) {
  a.field("programs", s.programs, Expect::oneOf(programFormatNames()));
  a.field("program_name", s.program_name);
  a.section("trigger", s.trigger);
  a.field("servo_period_s", s.servo_period_s, Expect::range(0.001, 0.1));
}

// The bodies of the collision scene a job makes (collision::Scene's names: links with shapes by
// name or base/linkN, the scanner when it has a housing, table, part, obstacles): a sensor's
// carrier must be one of them.
std::vector<std::string> sceneBodyNames(const JobSpec& s) {
  std::vector<std::string> names;
  for (std::size_t k = 0; k < s.robot.links.size() && k <= kinematics::kNumJoints; ++k) {
    const LinkSpec& link = s.robot.links[k];
    if (link.shapes.empty()) continue;
    names.push_back(!link.name.empty() ? link.name
                    : k == 0           ? std::string("base")
                                       : "link" + std::to_string(k));
  }
  if (!s.scanner.body.empty()) names.emplace_back("scanner");
  names.emplace_back("table");
  names.emplace_back("part");
  for (const ObstacleSpec& o : s.obstacles) names.push_back(o.name);
  return names;
}

void checkSensorCarriers(const YamlIn& a, const JobSpec& s) {
  const std::vector<std::string> bodies = sceneBodyNames(s);
  for (std::size_t i = 0; i < s.sensors.size(); ++i) {
    const std::string& carrier = s.sensors[i].carrier;
    if (carrier == "world" || std::find(bodies.begin(), bodies.end(), carrier) != bodies.end()) {
      continue;
    }
    const YamlIn sensor(a.node()["sensors"][i], "sensors[" + std::to_string(i) + "]", a.file(),
                        a.overrides());
    sensor.fail("carrier", "'" + clipForMessage(carrier) + "'",
                fmt::format("world or a body of the cell: {}", fmt::join(bodies, ", ")));
  }
}

template <class A>
void describeJob(A& a, JobSpec& s) {
  a.field("name", s.name);
  a.require("robot");
  if constexpr (A::kReading) {
    const YAML::Node robot = a.node()["robot"];
    if (!robot.IsDefined()) {
      // Missing next to a near miss (robto:): finish() says which.
    } else if (robot.IsScalar()) {
      a.field("robot", s.robot_file);
      s.robot = loadRobotOrUrdf(s.robot_file.resolved);
    } else if (robot.IsMap() && robot["urdf"].IsDefined()) {
      YamlIn urdf_robot(robot, "robot", a.file(), a.overrides());
      s.robot = readUrdfRobot(urdf_robot);
    } else if (robot.IsMap()) {
      YamlIn inline_robot(robot, "robot", a.file(), a.overrides());
      s.robot = readRobot(inline_robot);
    } else {
      a.fail("robot", "a list", "a robot file path or an inline robot mapping");
    }
  } else {
    a.section("robot", s.robot);
  }
  a.section("robot_base", s.robot_base);
  a.section("table", s.table);
  a.require("part");
  a.section("part", s.part);
  a.section("scanner", s.scanner);
  a.list("obstacles", s.obstacles, 0, 10000);
  if constexpr (A::kReading) {
    std::set<std::string> names;
    for (const ObstacleSpec& o : s.obstacles) {
      if (!names.insert(o.name).second) {
        a.fail("obstacles", "two obstacles named '" + o.name + "'", "a unique name per obstacle");
      }
    }
  }
  a.list("sensors", s.sensors, 0, kMaxSensors);
  if constexpr (A::kReading) {
    std::set<std::string> names;
    for (const SensorSpec& sensor : s.sensors) {
      if (!names.insert(sensor.name).second) {
        a.fail("sensors", "two sensors named '" + sensor.name + "'", "a unique name per sensor");
      }
    }
    // sensors.csv heads its columns with the names: t_s, then per presence sensor NAME and
    // NAME_bodies, per distance sensor NAME_mm, NAME_status and NAME_body.
    std::set<std::string> columns{"t_s"};
    for (const SensorSpec& sensor : s.sensors) {
      const bool distance = sensor.kind == "distance";
      for (const char* suffix : distance ? std::vector<const char*>{"_mm", "_status", "_body"}
                                         : std::vector<const char*>{"", "_bodies"}) {
        if (!columns.insert(sensor.name + suffix).second) {
          a.fail("sensors",
                 "sensor '" + sensor.name + "' gives sensors.csv a second column '" + sensor.name +
                     suffix + "'",
                 "names whose columns (t_s; NAME, NAME_bodies; NAME_mm, NAME_status, "
                 "NAME_body) differ");
        }
      }
    }
    if constexpr (std::is_same_v<A, YamlIn>) checkSensorCarriers(a, s);
  }
  a.section("constraints", s.constraints);
  a.section("scan", s.scan);
  a.section("map", s.map);
  a.section("planner", s.planner);
  a.section("validation", s.validation);
  a.section("simulation", s.simulation);
  if constexpr (std::is_same_v<A, YamlIn>) checkImageMode(a, s);
  if constexpr (A::kReading) s.outputs.programs = defaultPrograms(s.robot);
  a.section("outputs", s.outputs);
}

}  // namespace

void describe(YamlIn& a, TableSpec& s) { describeTable(a, s); }
void describe(YamlOut& a, TableSpec& s) { describeTable(a, s); }
void describe(YamlIn& a, PartSpec& s) { describePart(a, s); }
void describe(YamlOut& a, PartSpec& s) { describePart(a, s); }
void describe(YamlIn& a, ScannerSpec& s) { describeScanner(a, s); }
void describe(YamlOut& a, ScannerSpec& s) { describeScanner(a, s); }
void describe(YamlIn& a, ObstacleSpec& s) { describeObstacle(a, s); }
void describe(YamlOut& a, ObstacleSpec& s) { describeObstacle(a, s); }
void describe(YamlIn& a, SensorSpec& s) { describeSensor(a, s); }
void describe(YamlOut& a, SensorSpec& s) { describeSensor(a, s); }
void describe(YamlIn& a, RampSpec& s) { describeRamp(a, s); }
void describe(YamlOut& a, RampSpec& s) { describeRamp(a, s); }
void describe(YamlIn& a, LengthRampSpec& s) { describeLengthRamp(a, s); }
void describe(YamlOut& a, LengthRampSpec& s) { describeLengthRamp(a, s); }
void describe(YamlIn& a, PairRuleSpec& s) { describePairRule(a, s); }
void describe(YamlOut& a, PairRuleSpec& s) { describePairRule(a, s); }
void describe(YamlIn& a, ClearanceSpec& s) { describeClearance(a, s); }
void describe(YamlOut& a, ClearanceSpec& s) { describeClearance(a, s); }
void describe(YamlIn& a, ConstraintsSpec& s) { describeConstraints(a, s); }
void describe(YamlOut& a, ConstraintsSpec& s) { describeConstraints(a, s); }
void describe(YamlIn& a, OpticsSpec& s) { describeOptics(a, s); }
void describe(YamlOut& a, OpticsSpec& s) { describeOptics(a, s); }
void describe(YamlIn& a, WaypointSpec& s) { describeWaypoint(a, s); }
void describe(YamlOut& a, WaypointSpec& s) { describeWaypoint(a, s); }
void describe(YamlIn& a, PathElementSpec& s) { describePathElement(a, s); }
void describe(YamlOut& a, PathElementSpec& s) { describePathElement(a, s); }
void describe(YamlIn& a, AutoSpec& s) { describeAuto(a, s); }
void describe(YamlOut& a, AutoSpec& s) { describeAuto(a, s); }
void describe(YamlIn& a, ScanSpec& s) { describeScan(a, s); }
void describe(YamlOut& a, ScanSpec& s) { describeScan(a, s); }
void describe(YamlIn& a, MapSpec& s) { describeMap(a, s); }
void describe(YamlIn& a, RaySpec& s) { describeRay(a, s); }
void describe(YamlOut& a, RaySpec& s) { describeRay(a, s); }
void describe(YamlIn& a, DpSpec& s) { describeDp(a, s); }
void describe(YamlOut& a, DpSpec& s) { describeDp(a, s); }
void describe(YamlIn& a, OmplSpec& s) { describeOmpl(a, s); }
void describe(YamlOut& a, OmplSpec& s) { describeOmpl(a, s); }
void describe(YamlIn& a, RefineSpec& s) { describeRefine(a, s); }
void describe(YamlOut& a, RefineSpec& s) { describeRefine(a, s); }
void describe(YamlIn& a, PlannerSpec& s) { describePlanner(a, s); }
void describe(YamlIn& a, TriggerSpec& s) { describeTrigger(a, s); }
void describe(YamlOut& a, TriggerSpec& s) { describeTrigger(a, s); }
void describe(YamlIn& a, OutputsSpec& s) { describeOutputs(a, s); }
void describe(YamlOut& a, OutputsSpec& s) { describeOutputs(a, s); }
void describe(YamlIn& a, NoiseSpec& s) { describeNoise(a, s); }
void describe(YamlOut& a, NoiseSpec& s) { describeNoise(a, s); }
void describe(YamlIn& a, CameraSpec& s) { describeCamera(a, s); }
void describe(YamlOut& a, CameraSpec& s) { describeCamera(a, s); }
void describe(YamlIn& a, LaserSpec& s) { describeLaser(a, s); }
void describe(YamlOut& a, LaserSpec& s) { describeLaser(a, s); }
void describe(YamlIn& a, SimulationSpec::Reflectance& s) { describeReflectance(a, s); }
void describe(YamlOut& a, SimulationSpec::Reflectance& s) { describeReflectance(a, s); }
void describe(YamlIn& a, ValidationSpec& s) { describeValidation(a, s); }
void describe(YamlOut& a, ValidationSpec& s) { describeValidation(a, s); }
void describe(YamlIn& a, SimulationSpec& s) { describeSimulation(a, s); }
void describe(YamlOut& a, SimulationSpec& s) { describeSimulation(a, s); }
void describe(YamlOut& a, PlannerSpec& s) { describePlanner(a, s); }
void describe(YamlOut& a, MapSpec& s) { describeMap(a, s); }

// The job's JSON Schema (jobSchema): the same describe() functions, written by SchemaOut.
template <>
std::vector<ShapeSpec> schemaVariants<ShapeSpec>() {
  std::vector<ShapeSpec> out;
  for (const std::string& type : kShapeTypes) {
    ShapeSpec s;
    s.type = type;
    out.push_back(s);
    if (type == "cylinder" || type == "capsule") {
      s.by_end_points = true;
      out.push_back(s);
    }
  }
  return out;
}

template <>
std::vector<PathElementSpec> schemaVariants<PathElementSpec>() {
  std::vector<PathElementSpec> out;
  for (const std::string& type : kPathTypes) {
    PathElementSpec s;
    s.type = type;
    out.push_back(s);
  }
  return out;
}

template <>
std::vector<ObstacleSpec> schemaVariants<ObstacleSpec>() {
  std::vector<ObstacleSpec> out;
  for (const ShapeSpec& shape : schemaVariants<ShapeSpec>()) {
    ObstacleSpec s;
    s.shape = shape;
    out.push_back(s);
  }
  return out;
}

template <>
std::vector<SensorSpec> schemaVariants<SensorSpec>() {
  std::vector<SensorSpec> out;
  for (const char* rule : {"any", "during"}) {
    SensorSpec s;
    s.expect = rule;
    for (const std::string& shape : kSensorShapes) {
      s.kind = "presence";
      s.shape = shape;
      out.push_back(s);
    }
    s.kind = "distance";
    out.push_back(s);
  }
  return out;
}

void describe(SchemaOut& a, TableSpec& s) { describeTable(a, s); }
void describe(SchemaOut& a, PartSpec& s) { describePart(a, s); }
void describe(SchemaOut& a, ScannerSpec& s) { describeScanner(a, s); }
void describe(SchemaOut& a, ObstacleSpec& s) { describeObstacle(a, s); }
void describe(SchemaOut& a, SensorSpec& s) { describeSensor(a, s); }
void describe(SchemaOut& a, RampSpec& s) { describeRamp(a, s); }
void describe(SchemaOut& a, LengthRampSpec& s) { describeLengthRamp(a, s); }
void describe(SchemaOut& a, PairRuleSpec& s) { describePairRule(a, s); }
void describe(SchemaOut& a, ClearanceSpec& s) { describeClearance(a, s); }
void describe(SchemaOut& a, ConstraintsSpec& s) { describeConstraints(a, s); }
void describe(SchemaOut& a, OpticsSpec& s) { describeOptics(a, s); }
void describe(SchemaOut& a, WaypointSpec& s) { describeWaypoint(a, s); }
void describe(SchemaOut& a, PathElementSpec& s) { describePathElement(a, s); }
void describe(SchemaOut& a, AutoSpec& s) { describeAuto(a, s); }
void describe(SchemaOut& a, ScanSpec& s) { describeScan(a, s); }
void describe(SchemaOut& a, MapSpec& s) { describeMap(a, s); }
void describe(SchemaOut& a, RaySpec& s) { describeRay(a, s); }
void describe(SchemaOut& a, DpSpec& s) { describeDp(a, s); }
void describe(SchemaOut& a, OmplSpec& s) { describeOmpl(a, s); }
void describe(SchemaOut& a, RefineSpec& s) { describeRefine(a, s); }
void describe(SchemaOut& a, PlannerSpec& s) { describePlanner(a, s); }
void describe(SchemaOut& a, TriggerSpec& s) { describeTrigger(a, s); }
void describe(SchemaOut& a, OutputsSpec& s) { describeOutputs(a, s); }
void describe(SchemaOut& a, NoiseSpec& s) { describeNoise(a, s); }
void describe(SchemaOut& a, CameraSpec& s) { describeCamera(a, s); }
void describe(SchemaOut& a, LaserSpec& s) { describeLaser(a, s); }
void describe(SchemaOut& a, SimulationSpec::Reflectance& s) { describeReflectance(a, s); }
void describe(SchemaOut& a, ValidationSpec& s) { describeValidation(a, s); }
void describe(SchemaOut& a, SimulationSpec& s) { describeSimulation(a, s); }
void describe(SchemaOut& a, JobSpec& s) { describeJob(a, s); }

std::string jobSchema() {
  SchemaOut::Json schema = {
      {"$schema", "http://json-schema.org/draft-07/schema#"},
      {"$id", "https://scanplan.invalid/job.schema.json"},
      {"title", "scanplan job file"},
      {"description",
       "A scanplan job: robot, table, part, scanner, constraints, scan, map, planner, "
       "validation, simulation, outputs. Every key is documented in README.md (Job file); "
       "scanplan job show prints the defaults."}};
  const JobSpec defaults;
  schema.update(SchemaOut::ofAll(defaults));
  schema["properties"]["robot"] = {
      {"description",
       "a robot file (.yaml, or .urdf with base_link and tip_link) relative to this "
       "file, or an inline robot mapping (README.md: Robot file)"},
      {"type", {"string", "object"}}};
  return schema.dump(2) + "\n";
}

namespace {

[[noreturn]] void badOverride(const std::string& text, const std::string& why) {
  const std::string quoted = clipForMessage(text);  // a hostile value is not echoed whole
  throw InputError(
      fmt::format("--set '{}': {}: expected key.path=value, e.g. "
                  "planner.ray.horizon=20 or scan.paths[0].height_mm=60",
                  quoted, why));
}

// The key node of `key` in `map`, recorded as the override's when the override created it.
void recordOverrideKey(const YAML::Node& map,
                       const std::string& key,
                       const std::string& text,
                       OverrideOrigins& origins) {
  for (auto it = map.begin(); it != map.end(); ++it) {
    if (it->first.IsScalar() && it->first.Scalar() == key) origins.add(it->first, text);
  }
}

// A step of an override's key path: a key, or a list index (key empty).
using OverrideStep = std::pair<std::string, int>;

// The steps of one '.'-separated segment of the key path: "paths[0]" → paths, [0].
void appendSegmentSteps(const std::string& text,
                        std::size_t eq,
                        const std::string& segment,
                        std::vector<OverrideStep>& steps) {
  std::string key = segment;
  std::vector<int> indices;
  const std::size_t bracket = segment.find('[');
  if (bracket != std::string::npos) {
    key = segment.substr(0, bracket);
    std::string rest = segment.substr(bracket);
    while (!rest.empty()) {
      const std::size_t close = rest.find(']');
      if (rest[0] != '[' || close == std::string::npos) {
        badOverride(text, "'" + segment + "' is malformed");
      }
      const auto index = parseFiniteNumber(rest.substr(1, close - 1));
      if (!index || *index < 0 || *index != std::floor(*index)) {
        badOverride(text, "'" + segment + "' has a bad list index");
      }
      indices.push_back(static_cast<int>(*index));
      rest = rest.substr(close + 1);
    }
  }
  if (key.empty()) badOverride(text, "an empty key in '" + text.substr(0, eq) + "'");
  steps.emplace_back(key, -1);
  for (int i : indices) steps.emplace_back("", i);
}

// The node an override sets a value in, and its path as the messages print it.
struct OverrideParent {
  YAML::Node node;
  std::string where;
};

// Walks all steps but the last from `root`, creating the mappings on the way.
OverrideParent overrideParent(YAML::Node root,
                              const std::vector<OverrideStep>& steps,
                              const std::string& text,
                              OverrideOrigins& origins) {
  YAML::Node node = root;
  std::string where;
  for (std::size_t i = 0; i + 1 < steps.size(); ++i) {
    const auto& [key, index] = steps[i];
    YAML::Node next;
    if (key.empty()) {
      if (!node.IsSequence() || static_cast<std::size_t>(index) >= node.size()) {
        badOverride(text, fmt::format("{} has no item [{}]", where, index));
      }
      next.reset(node[static_cast<std::size_t>(index)]);
      where += fmt::format("[{}]", index);
    } else {
      if (node.IsDefined() && !node.IsNull() && !node.IsMap()) {
        badOverride(text, where + " is not a mapping");
      }
      if (!node[key].IsDefined()) {
        node[key] = YAML::Node(YAML::NodeType::Map);
        recordOverrideKey(node, key, text, origins);
        origins.add(node[key], text);
      }
      next.reset(node[key]);
      where += (where.empty() ? "" : ".") + key;
    }
    node.reset(next);
  }
  return {node, where};
}

// The override's value: a flow sequence or mapping is YAML, anything else a scalar.
YAML::Node overrideValue(const std::string& text, const std::string& value) {
  const bool yaml = !value.empty() && (value[0] == '[' || value[0] == '{');
  YAML::Node v;
  try {
    if (yaml) {
      std::istringstream in(value);
      if (const auto second = secondDocumentStart(in)) {
        badOverride(text, fmt::format("the value holds a second YAML document at its line {}: "
                                      "expected one value (the rest would be dropped)",
                                      second->line + 1));
      }
    }
    v = yaml ? YAML::Load(value) : YAML::Node(value);
  } catch (const YAML::Exception& e) {
    badOverride(text, "the value is malformed YAML: " + e.msg);
  }
  try {
    checkYamlSize(v, "the value");
  } catch (const InputError& e) {
    badOverride(text, e.what());
  }
  return v;
}

// "planner.ray.horizon=20", "scan.paths[0].height_mm=60": sets that value in the YAML tree
// (creating mappings on the way), so the reader validates it like any value of the file. The
// value, and every key and mapping the override created, go into `origins`, so errors about
// them name the override.
void applyOverride(YAML::Node root, const std::string& text, OverrideOrigins& origins) {
  const std::size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0) badOverride(text, "no key");
  const std::string value = text.substr(eq + 1);
  std::vector<OverrideStep> steps;
  std::stringstream keys(text.substr(0, eq));
  for (std::string segment; std::getline(keys, segment, '.');) {
    appendSegmentSteps(text, eq, segment, steps);
  }
  OverrideParent parent = overrideParent(root, steps, text, origins);
  YAML::Node& node = parent.node;
  const std::string& where = parent.where;
  const auto& [key, index] = steps.back();
  YAML::Node v = overrideValue(text, value);
  if (key.empty()) {
    if (!node.IsSequence() || static_cast<std::size_t>(index) >= node.size()) {
      badOverride(text, fmt::format("{} has no item [{}]", where, index));
    }
    node[static_cast<std::size_t>(index)] = v;
  } else {
    if (node.IsDefined() && !node.IsNull() && !node.IsMap()) {
      badOverride(text, where + " is not a mapping");
    }
    const bool created = !node[key].IsDefined();
    node[key] = v;
    if (created) recordOverrideKey(node, key, text, origins);
  }
  origins.add(v, text);
}

}  // namespace

JobSpec loadJob(const std::filesystem::path& file, const std::vector<std::string>& overrides) {
  JobSpec job;
  // As the user gave it, like every other message about the file.
  job.source = file.lexically_normal();
  YAML::Node root = loadYamlFile(file);
  auto origins = std::make_shared<OverrideOrigins>();
  for (const std::string& o : overrides) applyOverride(root, o, *origins);
  YamlIn in(root, "", file, origins);
  describeJob(in, job);
  in.finish();
  spdlog::debug("job {} ({}): robot {} ({}), part {}", job.name, file.string(), job.robot.name,
                job.robot_file.resolved.empty() ? "inline" : job.robot_file.resolved.string(),
                job.part.mesh.resolved.string());
  for (const std::string& o : overrides) spdlog::debug("job {}: --set {}", job.name, o);
  return job;
}

std::string jobToYaml(const JobSpec& job) {
  JobSpec copy = job;
  YAML::Emitter out;
  out.SetIndent(2);
  out << YAML::Comment(
      fmt::format("scanplan job, fully resolved from {}",
                  std::filesystem::absolute(job.source).lexically_normal().string()));
  out << YAML::BeginMap;
  YamlOut writer(out);
  describeJob(writer, copy);
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

std::string jobHash(const JobSpec& job) {
  JobSpec copy = job;
  YAML::Emitter out;
  out << YAML::BeginMap;
  YamlOut writer(out, true);
  describeJob(writer, copy);
  out << YAML::EndMap;
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a
  for (const char c : std::string(out.c_str())) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ull;
  }
  return fmt::format("{:016x}", h);
}

namespace {

// The job's part placed on the table (kinematics::placedOnTable); errors name the job file.
Eigen::Isometry3d placedPart(const JobSpec& job, const kinematics::PartModel& part) {
  return kinematics::placedOnTable(loadPartMesh(job, part).mesh, toIsometry(job.part.pose));
}

// A part larger than any length a job may hold (lengths within ±1e6 mm, the reader's bound)
// cannot be scanned in any cell; refused here, at load, its probes and maps would otherwise
// grow with it before anything said why.
constexpr double kMaxPartSizeMm = 1e6;

void checkPartSize(const JobSpec& job, const kinematics::TriangleMesh& mesh) {
  const double size_mm = toMm(mesh.bounds().sizes().maxCoeff());
  if (size_mm <= kMaxPartSizeMm) return;
  throw InputError(fmt::format(
      "{}: part.scale: {}: the part is {:.6g} mm across (part.units {} × part.scale): expected "
      "a part at most {:.0f} mm across; check part.units and part.scale",
      job.source.string(), formatNumber(job.part.scale), size_mm, job.part.units, kMaxPartSizeMm));
}

}  // namespace

kinematics::LoadedMesh loadPartMesh(const JobSpec& job, const kinematics::PartModel& part) {
  kinematics::LoadedMesh mesh;
  try {
    mesh = kinematics::loadMesh(part.mesh.path, part.mesh.options);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: part.mesh: {}", job.source.string(), e.what()));
  }
  checkPartSize(job, mesh.mesh);
  return mesh;
}

namespace {

kinematics::Sensor toSensor(const SensorSpec& spec) {
  using kinematics::Sensor;
  using Rule = kinematics::SensorExpectation::Kind;
  Sensor sensor;
  sensor.name = spec.name;
  sensor.kind = spec.kind == "distance" ? Sensor::Kind::kDistance : Sensor::Kind::kPresence;
  sensor.carrier = spec.carrier;
  sensor.X_CS = toIsometry(spec.pose);
  if (spec.shape == "sphere") {
    sensor.volume.geometry = kinematics::Sphere{mm(spec.radius_mm)};
  } else if (spec.shape == "cylinder") {
    sensor.volume.geometry = kinematics::Cylinder{mm(spec.radius_mm), mm(spec.length_mm)};
  } else {
    sensor.volume.geometry = kinematics::Box{Eigen::Vector3d(spec.size_mm.data()) * kMmToM};
  }
  sensor.min_range = mm(spec.min_range_mm);
  sensor.max_range = mm(spec.max_range_mm);
  if (spec.has_receiver) sensor.p_SR = Eigen::Vector3d(spec.receiver_mm.data()) * kMmToM;
  const std::vector<std::pair<std::string, Rule>> rules = {{"any", Rule::kAny},
                                                           {"never", Rule::kNever},
                                                           {"always", Rule::kAlways},
                                                           {"during", Rule::kDuring},
                                                           {"not_during", Rule::kNotDuring}};
  for (const auto& [name, rule] : rules) {
    if (spec.expect == name) sensor.expect.kind = rule;
  }
  sensor.expect.t0 = spec.window_s[0];
  sensor.expect.t1 = spec.window_s[1];
  return sensor;
}

}  // namespace

kinematics::CellModel buildCell(const JobSpec& job) {
  const std::string robot_source =
      job.robot_file.resolved.empty() ? job.source.string() : job.robot_file.resolved.string();
  kinematics::CellModel cell(job.name, buildRobotModel(job.robot, robot_source));
  cell.X_WB = toIsometry(job.robot_base);

  const TableSpec& t = job.table;
  cell.table.X_WA = toIsometry(t.axis);
  cell.table.eccentricity = Eigen::Vector2d(t.eccentricity_mm[0], t.eccentricity_mm[1]) * kMmToM;
  cell.table.tilt = Eigen::Vector2d(t.tilt_deg[0], t.tilt_deg[1]) * kDegToRad;
  cell.table.radius = mm(t.radius_mm);
  cell.table.height = mm(t.height_mm);
  cell.table.continuous = t.continuous;
  cell.table.min = deg(t.min_deg);
  cell.table.max = deg(t.max_deg);
  cell.table.max_speed = deg(t.max_speed_deg_s);
  cell.table.max_accel = deg(t.max_accel_deg_s2);

  cell.part.mesh = {job.part.mesh.resolved,
                    {toLengthUnit(job.part.units), job.part.scale, upRotation(job.part.up_axis)}};
  cell.part.X_RP = toIsometry(job.part.pose);
  if (job.part.place == "table") cell.part.X_RP = placedPart(job, cell.part);

  cell.scanner.X_FS = toIsometry(job.scanner.mount);
  for (const ShapeSpec& shape : job.scanner.body) cell.scanner.body.push_back(toShape(shape));

  for (const ObstacleSpec& o : job.obstacles) {
    kinematics::Obstacle obstacle;
    obstacle.name = o.name;
    obstacle.carrier =
        o.carrier == "table" ? kinematics::Carrier::kTable : kinematics::Carrier::kWorld;
    if (o.by_corner) {
      const Eigen::Vector3d corner = Eigen::Vector3d(o.corner_mm.data()) * kMmToM;
      const Eigen::Vector3d size = Eigen::Vector3d(o.shape.size_mm.data()) * kMmToM;
      kinematics::Shape box;
      box.geometry = kinematics::Box{size.cwiseAbs()};
      box.X_BG.translation() = corner + 0.5 * size;  // the centre, whichever way sizes point
      obstacle.shapes.push_back(box);
    } else {
      obstacle.shapes.push_back(toShape(o.shape));
    }
    cell.obstacles.push_back(std::move(obstacle));
  }
  for (const SensorSpec& spec : job.sensors) cell.sensors.push_back(toSensor(spec));
  return cell;
}

collision::ClearanceConfig clearanceConfig(const JobSpec& job) {
  const ClearanceSpec& c = job.constraints.clearance;
  collision::ClearanceConfig config;
  config.defaults = {mm(c.d_low_mm), mm(c.d_high_mm), c.gamma};
  config.link_meshes = c.link_meshes == "exact"  ? collision::LinkMeshes::kExact
                       : c.link_meshes == "hull" ? collision::LinkMeshes::kHull
                                                 : collision::LinkMeshes::kAuto;
  config.max_hull_margin = mm(c.hull_margin_mm);
  config.hull_vertices = static_cast<std::size_t>(c.hull_vertices);
  for (const PairRuleSpec& r : c.pairs) {
    collision::PairRule rule;
    rule.a = r.a;
    rule.b = r.b;
    rule.action = r.exclude   ? collision::PairRule::Action::kExclude
                  : r.include ? collision::PairRule::Action::kInclude
                              : collision::PairRule::Action::kSet;
    rule.d_low = r.d_low_mm >= 0.0 ? mm(r.d_low_mm) : -1.0;
    rule.d_high = r.d_high_mm >= 0.0 ? mm(r.d_high_mm) : -1.0;
    rule.gamma = r.gamma > 0.0 ? r.gamma : -1.0;
    config.rules.push_back(rule);
  }
  return config;
}

planner::ConstraintSettings constraintSettings(const JobSpec& job) {
  const ConstraintsSpec& c = job.constraints;
  planner::ConstraintSettings s;
  s.joint_gamma = c.joint_limit_gamma;
  s.wrist = {c.wrist.low, c.wrist.high, c.wrist.gamma};
  s.elbow = {c.elbow.low, c.elbow.high, c.elbow.gamma};
  s.shoulder = {mm(c.shoulder.low_mm), mm(c.shoulder.high_mm), c.shoulder.gamma};
  return s;
}

}  // namespace scanplan::cli

namespace scanplan::cli {

std::optional<kinematics::IkBranch> parseBranch(const std::string& words) {
  std::istringstream in(words);
  std::string w;
  kinematics::IkBranch b;
  int seen = 0;
  while (in >> w) {
    int bit = 0;
    if (w == "LEFTY" || w == "RIGHTY") {
      b.lefty = w == "LEFTY";
      bit = 1;
    } else if (w == "ABOVE" || w == "BELOW") {
      b.below = w == "BELOW";
      bit = 2;
    } else if (w == "FLIP" || w == "NOFLIP") {
      b.flip = w == "FLIP";
      bit = 4;
    } else {
      return std::nullopt;
    }
    if (seen & bit) return std::nullopt;  // two words of one pair
    seen |= bit;
  }
  if (seen != 7) return std::nullopt;
  return b;
}

scanner::LaserOptics laserOptics(const JobSpec& job) {
  const OpticsSpec& o = job.scanner.optics;
  return {mm(o.a_mm), mm(o.b_mm), deg(o.phi_deg), deg(o.gamma_deg)};
}

scanner::PathRequest pathRequest(const JobSpec& job) {
  scanner::PathRequest request;
  request.dt = job.scan.dt_s;
  request.transfer_speed = mm(job.scan.transfer_speed_mm_s);
  request.retreat = mm(job.scan.retreat_mm);
  for (const PathElementSpec& e : job.scan.paths) {
    if (e.type == "ring") {
      scanner::RingSpec ring;
      ring.height = mm(e.height_mm);
      ring.tilt = deg(e.tilt_deg);
      ring.start = deg(e.start_deg);
      ring.extent = deg(e.extent_deg);
      ring.speed = deg(e.speed_deg_s);
      if (e.distance_mm > 0.0) ring.distance = mm(e.distance_mm);
      if (e.has_axis) ring.axis_xy = Eigen::Vector2d(e.axis_xy_mm[0], e.axis_xy_mm[1]) * kMmToM;
      request.elements.emplace_back(ring);
    } else if (e.type == "raster") {
      scanner::RasterSpec raster;
      raster.view = Eigen::Vector3d(e.view.data());
      raster.pass_direction = Eigen::Vector3d(e.pass_direction.data());
      raster.overlap = e.overlap;
      raster.lead = mm(e.lead_mm);
      raster.speed = mm(e.speed_mm_s);
      request.elements.emplace_back(raster);
    } else if (e.type == "waypoints") {
      scanner::WaypointSpec points;
      for (const WaypointSpec& w : e.points) {
        scanner::Waypoint p;
        p.X_PS = toIsometry({w.xyz_mm, w.rpy_deg});
        p.speed = mm(w.speed_mm_s);
        p.rotation_speed = deg(w.rotation_speed_deg_s);
        p.scanning = w.scanning;
        points.points.push_back(p);
      }
      request.elements.emplace_back(points);
    } else {
      std::ifstream in(e.file.resolved, std::ios::binary);
      std::ostringstream text;
      text << in.rdbuf();
      request.elements.emplace_back(scanner::parsePathCsv(text.str(), e.file.resolved.string()));
    }
  }
  return request;
}

planner::PlannerSettings plannerSettings(const JobSpec& job) {
  planner::PlannerSettings p;
  p.k_omega = job.planner.k_omega;
  p.k_alpha = job.planner.k_alpha;
  p.omega_max = deg(job.table.max_speed_deg_s);
  p.alpha_max = deg(job.table.max_accel_deg_s2);
  return p;
}

std::optional<double> startAngle(const JobSpec& job) {
  if (job.planner.start_deg == "auto") return std::nullopt;
  return deg(*parseFiniteNumber(job.planner.start_deg));
}

std::vector<std::filesystem::path> jobInputFiles(const JobSpec& job) {
  std::vector<std::filesystem::path> files{job.source};
  const auto add = [&](const FilePath& f) {
    if (!f.resolved.empty()) files.push_back(f.resolved);
  };
  add(job.robot_file);
  add(job.part.mesh);
  for (const LinkSpec& link : job.robot.links) {
    for (const ShapeSpec& shape : link.shapes) add(shape.file);
  }
  for (const ShapeSpec& shape : job.scanner.body) add(shape.file);
  for (const ObstacleSpec& obstacle : job.obstacles) add(obstacle.shape.file);
  for (const PathElementSpec& path : job.scan.paths) add(path.file);
  return files;
}

}  // namespace scanplan::cli
