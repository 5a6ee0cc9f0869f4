// The scanner sections of a job file: scanner (optics, noise, camera, laser), validation and
// simulation; their YAML keys (describe), the image mode's checks and the optics in SI
// (laserOptics).
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

#include <scanplan/config/detail/job_sections.h>
#include <scanplan/config/robot_urdf.h>
#include <scanplan/config/text.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/placement.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/programs/programs.h>

namespace scanplan::config {
namespace {

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

scanner::CameraRule cameraRule(const std::string& name) {
  if (name == "negative") return scanner::CameraRule::kNegative;
  if (name == "both") return scanner::CameraRule::kBoth;
  if (name == "either") return scanner::CameraRule::kEither;
  return scanner::CameraRule::kPositive;
}

}  // namespace

void describe(YamlIn& a, OpticsSpec& s) { describeOptics(a, s); }
void describe(YamlOut& a, OpticsSpec& s) { describeOptics(a, s); }
void describe(SchemaOut& a, OpticsSpec& s) { describeOptics(a, s); }
void describe(YamlIn& a, NoiseSpec& s) { describeNoise(a, s); }
void describe(YamlOut& a, NoiseSpec& s) { describeNoise(a, s); }
void describe(SchemaOut& a, NoiseSpec& s) { describeNoise(a, s); }
void describe(YamlIn& a, CameraSpec& s) { describeCamera(a, s); }
void describe(YamlOut& a, CameraSpec& s) { describeCamera(a, s); }
void describe(SchemaOut& a, CameraSpec& s) { describeCamera(a, s); }
void describe(YamlIn& a, LaserSpec& s) { describeLaser(a, s); }
void describe(YamlOut& a, LaserSpec& s) { describeLaser(a, s); }
void describe(SchemaOut& a, LaserSpec& s) { describeLaser(a, s); }
void describe(YamlIn& a, ScannerSpec& s) { describeScanner(a, s); }
void describe(YamlOut& a, ScannerSpec& s) { describeScanner(a, s); }
void describe(SchemaOut& a, ScannerSpec& s) { describeScanner(a, s); }
void describe(YamlIn& a, ValidationSpec& s) { describeValidation(a, s); }
void describe(YamlOut& a, ValidationSpec& s) { describeValidation(a, s); }
void describe(SchemaOut& a, ValidationSpec& s) { describeValidation(a, s); }
void describe(YamlIn& a, SimulationSpec& s) { describeSimulation(a, s); }
void describe(YamlOut& a, SimulationSpec& s) { describeSimulation(a, s); }
void describe(SchemaOut& a, SimulationSpec& s) { describeSimulation(a, s); }
void describe(YamlIn& a, SimulationSpec::Reflectance& s) { describeReflectance(a, s); }
void describe(YamlOut& a, SimulationSpec::Reflectance& s) { describeReflectance(a, s); }
void describe(SchemaOut& a, SimulationSpec::Reflectance& s) { describeReflectance(a, s); }

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

scanner::LaserOptics laserOptics(const JobSpec& job) {
  const OpticsSpec& o = job.scanner.optics;
  return {mm(o.a_mm), mm(o.b_mm), deg(o.phi_deg), deg(o.gamma_deg)};
}

planner::ValidationSettings validationSettings(const JobSpec& job) {
  planner::ValidationSettings s;
  s.sample_dt = 1.0 / job.scanner.frame_rate_hz;
  s.table_omega_max = deg(job.table.max_speed_deg_s);
  s.table_alpha_max = deg(job.table.max_accel_deg_s2);
  s.collision_resolution = job.validation.collision_resolution_mm * kMmToM;
  return s;
}

pipeline::SimulationSettings simulationSettings(const JobSpec& job,
                                                const kinematics::CellModel& cell) {
  pipeline::SimulationSettings s;
  s.frame_rate_hz = job.scanner.frame_rate_hz;
  s.scanner.rays_per_profile = job.scanner.rays_per_profile;
  s.scanner.cameras = cameraRule(job.scanner.cameras);
  s.scanner.sigma_longitudinal = job.scanner.noise.longitudinal_mm * kMmToM;
  s.scanner.sigma_orthogonal = job.scanner.noise.orthogonal_mm * kMmToM;
  s.scanner.seed = static_cast<std::uint64_t>(job.scanner.noise.seed);
  s.scanner.mode = job.simulation.mode == "image" ? scanner::SimulationMode::kImage
                                                  : scanner::SimulationMode::kGeometric;
  const CameraSpec& camera = job.scanner.camera;
  scanner::ImageSettings& image = s.scanner.image;
  image.rows = camera.rows;
  image.columns = camera.columns > 0 ? camera.columns : job.scanner.rays_per_profile;
  image.thickness = job.scanner.laser.thickness_mm * kMmToM;
  image.reflectance = {job.simulation.reflectance.lambert, job.simulation.reflectance.specular,
                       job.simulation.reflectance.shininess};
  image.ambient = camera.ambient_grey;
  image.noise = camera.noise_grey;
  image.threshold = camera.threshold_grey;
  image.method = camera.detection == "gauss" ? scanner::StripeMethod::kGaussian
                                             : scanner::StripeMethod::kCentreOfGravity;
  if (s.scanner.mode == scanner::SimulationMode::kImage)
    s.profile_images = static_cast<std::size_t>(job.simulation.profile_images);
  const auto& e = job.simulation.extra_eccentricity_mm;
  const auto& t = job.simulation.extra_tilt_deg;
  if (e[0] != 0.0 || e[1] != 0.0 || t[0] != 0.0 || t[1] != 0.0) {
    kinematics::RotaryTableModel real = cell.table;
    real.eccentricity += Eigen::Vector2d(e[0], e[1]) * kMmToM;
    real.tilt += Eigen::Vector2d(deg(t[0]), deg(t[1]));
    s.scanner.simulated_table = real;
  }
  s.coverage.min_points = static_cast<std::uint32_t>(job.simulation.coverage_min_points);
  return s;
}

}  // namespace scanplan::config
