#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/kinematics/cell.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/robot_model.h>
#include <scanplan/kinematics/rotary_table.h>
#include <scanplan/kinematics/shape.h>
#include <scanplan/scanner/camera_image.h>
#include <scanplan/scanner/laser_model.h>

namespace scanplan::scanner {

/// One profile acquisition: the time, the table angle and the arm joints at that instant.
struct ScanFrame {
  double t = 0.0;                                               ///< s
  double theta = 0.0;                                           ///< table angle, rad
  kinematics::JointVector q = kinematics::JointVector::Zero();  ///< arm joints, rad
};

/// Which camera(s) must see a lit point for it to be measured. The head's camera geometry
/// (docs/design.md §6, Eq. 4–5) in the scanner frame S: the laser leaves the origin in the plane
/// X = 0 (the fan spreads about +Z); a camera centre sits at C± = (±a, 0, b), its optical axis
/// in the XZ plane at the angle φ to the laser's +Z, looking back at the plane. A single-camera
/// head has only C+.
enum class CameraRule {
  kPositive,  ///< one camera, at C+ = (+a, 0, b)
  kNegative,  ///< one camera, at C− = (−a, 0, b)
  kBoth,      ///< two cameras; a point counts only when both see it
  kEither,    ///< two cameras; a point counts when at least one sees it
};

/// Image mode: the most memory the threads' images may hold together (bytes); fewer threads
/// render at once where the cores would hold more.
inline constexpr double kImageMemoryBudget = 4e9;

/// How the profiles are measured (seed §5.3).
enum class SimulationMode {
  /// The laser fan's hits are the points (Eq. 5 window, camera occlusion rays): fast.
  kGeometric,
  /// Each profile renders the camera image (camera_image.h), detects the stripe per column and
  /// triangulates it with Eq. 4: the image processing in the loop, ~100× the cost.
  kImage,
};

/// What one simulation run does (the job's scanner settings, SI).
struct SimulationSettings {
  SimulationMode mode = SimulationMode::kGeometric;
  /// Image mode: the camera image and its stripe detection (rows × columns, sheet thickness,
  /// reflectance, noise, threshold, method). The camera is the rule's: kPositive or kNegative
  /// (kBoth and kEither are refused in image mode).
  ImageSettings image;
  int rays_per_profile = 200;  ///< fan rays per profile, spread evenly in angle (≥ 1)
  CameraRule cameras = CameraRule::kPositive;
  /// Gaussian measurement noise (docs/design.md §6): along the ray (σ_l) and across it in the laser
  /// plane (σ_o), m. Zero: no noise.
  double sigma_longitudinal = 0.0;
  double sigma_orthogonal = 0.0;
  std::uint64_t seed = 1;  ///< noise seed; each profile draws from its own stream
  /// The table as it really is in the simulated cell (eccentricity, tilt, …), when it differs
  /// from the planner's model in the cell. The part scene is posed on this table, while points
  /// are mapped into the part frame with the planner's model, as the real system would: the
  /// difference shows in the cloud (seed §5.6).
  std::optional<kinematics::RotaryTableModel> simulated_table;
};

/// A measured point.
struct CloudPoint {
  Eigen::Vector3d p_P = Eigen::Vector3d::Zero();  ///< part frame, m (noise included)
  double t = 0.0;                                 ///< acquisition time, s
  std::uint32_t profile = 0;                      ///< index of the frame that took it
  std::uint32_t ray = 0;                          ///< fan ray index within the profile
  double range = 0.0;      ///< laser origin to the point along the ray (with σ_l noise), m
  double incidence = 0.0;  ///< angle between the ray and the surface normal, rad, [0, π/2]
  std::int32_t part_triangle = -1;  ///< hit triangle of the part mesh; −1 on another body
  /// the hit surface's unit normal, part frame, towards the laser (the side that was seen)
  Eigen::Vector3d n_P = Eigen::Vector3d::UnitZ();
};

/// Counters of one run; rays are counted once however many rigid groups they visit.
struct SimulationStats {
  std::size_t profiles = 0;
  std::size_t laser_rays = 0;      ///< fan rays cast
  std::size_t occlusion_rays = 0;  ///< hit → camera rays cast (image mode: laser-reach rays)
  /// fan rays with a hit before the far edge z_max (image mode: columns with a stripe)
  std::size_t hits = 0;
  std::size_t outside_window = 0;  ///< nearest hits outside the trapezoid (Eq. 5)
  std::size_t occluded = 0;        ///< in the trapezoid but not seen by the camera rule
  std::size_t points = 0;
  std::size_t pixel_rays = 0;  ///< image mode: camera rays, one per pixel
  std::size_t lit_pixels = 0;  ///< image mode: pixels the laser lit
};

struct SimulatedCloud {
  std::vector<CloudPoint> points;  ///< in profile order, then fan ray order
  SimulationStats stats;
};

/// The ray-casting back end.
enum class RayBackend {
  kEmbree,      ///< Embree 3 BVHs (the product)
  kBruteForce,  ///< every triangle for every ray, in double: the reference for tests and bench
};

struct SimulatorOptions {
  RayBackend backend = RayBackend::kEmbree;
  kinematics::TessellationOptions tessellation;  ///< for the primitives (table, links, …)
};

/// The fan of one profile (Eq. 5 window): ray k leaves the laser origin along
/// (0, sin α_k, cos α_k) in the scanner frame, α_k evenly spaced over [−α_max, α_max] where
/// α_max is the widest corner angle of the trapezoid, atan(y/z) over its corners (α = 0 for a
/// single ray).
std::vector<double> fanAngles(const LaserWindow& window, int rays_per_profile);

/// The camera centre(s) of the rule, scanner frame, m (see CameraRule).
std::vector<Eigen::Vector3d> cameraCentres(const LaserOptics& optics, CameraRule rule);

/// Geometric laser scanner simulation (docs/design.md §6, seed §5.2–5.6) of a whole cell.
///
/// The scene is built once, one rigid group at a time, and the rays are moved into each group's
/// frame instead of moving geometry: the table group (table cylinder, part, table-carried
/// obstacles; frame R), the world group (robot base, world obstacles; frame W) and one group
/// per moving arm link 1…6 (its DH frame). The scanner's own housing is not in the scene: the
/// laser leaves through it and the cameras look out of it. Per profile the fan is cast against
/// every group whose bounding sphere reaches the profile's rays; each ray keeps its nearest hit,
/// refined in double precision on the hit triangle's plane, and the hit becomes a point when it
/// lies in the trapezoid (LaserWindow::contains) and the camera rule is met: a camera sees the
/// hit when it is on the lit side of the hit triangle and nothing blocks the segment from the
/// hit to its centre. Noise is drawn after these decisions, so it never changes which rays
/// yield points.
///
/// In image mode (SimulationSettings::mode, seed §5.3) the same scene renders each profile's
/// camera image instead (camera_image.h: a camera ray per pixel against every group the
/// profile's rays can reach, a laser-reach ray per pixel in the sheet), the stripe is detected
/// per column and triangulated with Eq. 4, and the point goes to the part frame as above.
///
/// Immutable once built; simulate() is const, runs profiles in parallel (TBB) and returns the
/// same cloud for any thread count.
class ScanSimulator {
 public:
  /// `part` is the cell's part mesh, loaded (part frame P, m). Obstacle and link meshes are
  /// loaded here; throws InputError for a broken one.
  ScanSimulator(const kinematics::CellModel& cell,
                const kinematics::TriangleMesh& part,
                const SimulatorOptions& options = {});
  ~ScanSimulator();
  ScanSimulator(const ScanSimulator&) = delete;
  ScanSimulator& operator=(const ScanSimulator&) = delete;

  /// One profile per frame; profile i is frames[i]. Precondition: the optics are valid
  /// (LaserOptics); throws std::invalid_argument unless settings.rays_per_profile ≥ 1 and the
  /// sigmas are ≥ 0, and in image mode unless the image settings are valid (rows ≥ 2,
  /// columns ≥ 1, thickness > 0, noise, threshold and reflectance ≥ 0), the camera rule is
  /// kPositive or kNegative and the back end is Embree. In image mode point i of a profile
  /// comes from image column CloudPoint::ray; σ_l and σ_o are not applied (the image has its
  /// own noise). `poll`, when set, is called before each batch of profiles (a few thousand
  /// rays' worth); an exception it throws (a cancelled plan) leaves simulate().
  SimulatedCloud simulate(const std::vector<ScanFrame>& frames,
                          const LaserOptics& optics,
                          const SimulationSettings& settings,
                          const std::function<void()>& poll = {}) const;

  /// Image mode's camera image of one profile (`index` seeds its noise), as simulate() renders
  /// it with these settings (whatever settings.mode says), for a person to look at. Same
  /// preconditions as simulate().
  ProfileImage renderImage(const ScanFrame& frame,
                           std::uint32_t index,
                           const LaserOptics& optics,
                           const SimulationSettings& settings) const;

  /// Scene size: triangles over all groups.
  std::size_t triangleCount() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace scanplan::scanner
