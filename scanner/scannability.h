#pragma once
// The scannability certificate (docs/design.md §11): why each area sample of the part can
// or cannot be scanned on this setup, before any planning. A sample that no scanner pose could see
// is not a planner's failure; the classes say which limit stands in the way.

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <scanplan/scanner/area_coverage.h>
#include <scanplan/scanner/laser_model.h>
#include <scanplan/scanner/part_on_table.h>

namespace scanplan::scanner {

/// Why an area sample can or cannot be scanned on this setup (before any planning).
enum class SampleClass : std::uint8_t {
  kScannable = 0,   ///< some scanner pose sees it within the limits and fits
  kFacesTable = 1,  ///< faces the table or lies on it (facesTable())
  kOccluded = 2,    ///< no free line of sight for the laser and a camera within the incidence limit
  kNoStandoff = 3,  ///< lines of sight exist but the housing fits at no standoff in the window
  /// Scannable, but every pass the automatic scan found that sees it is out of the arm's reach
  /// (set by the automatic scan, never by classifyScannability()).
  kOutOfReach = 4,
};

/// "scannable", "faces_table", "occluded", "no_standoff" (the names reports use).
const char* sampleClassName(SampleClass c);

/// The head and the search, SI units. A scanner pose is the scanner frame S in R: the laser
/// leaves S's origin along +z_S (the measured line lies in the plane x_S = 0), so a sample is lit
/// by the ray's centre at the depth of its standoff.
struct ScannabilitySettings {
  /// Largest angle, rad, of the laser ray and of the camera ray (sample → camera centre) to the
  /// sample's normal; in [0, π/2].
  double max_incidence = 1.0471975511965976;  // 60°
  /// The laser's depth range z_min … z_max (m, 0 < z_min ≤ z_max); the widths are not used (the
  /// sample is on the fan's centre ray).
  LaserWindow window;
  /// Camera centres in S, m (cameraCentres()). A sample needs the laser and at least one of them:
  /// like CameraRule::kEither; pass one centre for a single-camera head. Not empty.
  std::vector<Eigen::Vector3d> cameras;
  /// The scanner body in S, m, already grown by the clearance the caller wants. Empty: no body
  /// (lines of sight only, no sample is kNoStandoff).
  std::vector<Eigen::AlignedBox3d> housing;
  int directions = 24;  ///< laser directions tried in the incidence cone (≥ 1)
  int rolls = 8;        ///< turns of the head about the laser ray tried per direction (≥ 1)
  int standoffs = 3;    ///< standoffs tried in the window (≥ 1): the middle first, then out
  /// Largest spacing of the test segments through a housing box, m (> 0): surface features
  /// smaller than this can slip between them.
  double housing_spacing = 0.005;
};

/// Classifies every sample of `sampling` (R frame, the same frame as `scene`), in sampling order.
///
/// 1. kFacesTable: facesTable(sampling, identity, max_incidence, window.z_max).
/// 2. The others try laser directions d (unit, from the sample p toward the scanner) on the
///    spherical cap of half-angle max_incidence about the sample normal n: `directions` of them
///    on a Fibonacci spiral, uniform in area, from d = n out to the rim. Per direction the head
///    turns by ψ = 2πj/rolls about d (ψ = 0: x_S along R's z projected off d, R's x when d is
///    vertical), and per turn the standoff L takes `standoffs` values evenly over the window,
///    the middle first. The pose: laser origin O = p + L·d, z_S = −d.
/// 3. A pose has free sight when nothing (part or table) is on the segment p → O and, for at
///    least one camera centre C (in R), the angle of C − p to n is within max_incidence and the
///    segment p → C is free. Segments start 10 µm off the surface along n.
/// 4. The housing fits when no box of it, placed at the pose, meets the part or the table. A box
///    meets them when a segment of a grid through its volume along each of its three axes
///    (spacing ≤ housing_spacing, its 12 edges among them) hits a surface, or when its centre is
///    inside the table or the part (the first part hit straight up from it is a back face:
///    reliable for closed, outward-wound parts). Features smaller than the spacing can slip
///    through the grid.
/// 5. kScannable at the first pose with free sight and a fitting housing; kNoStandoff when some
///    pose had free sight but none fitted; kOccluded when no pose had free sight.
///
/// kScannable comes with a pose that works (up to what the housing grid can miss); kOccluded and
/// kNoStandoff only say that none of the poses tried did better. Where only a narrow set of poses
/// works (the walls of a bore) a finer search (more directions, rolls or standoffs) moves some of
/// them to kScannable.
///
/// Deterministic (no random choices; parallel over samples, each written once). Throws
/// std::invalid_argument for directions, rolls or standoffs < 1; max_incidence not finite or
/// outside [0, π/2]; a window not finite or not 0 < z_min ≤ z_max; no cameras or a non-finite
/// one; an empty or non-finite housing box; housing_spacing not finite and > 0, or so small that
/// a box needs more than a million segments.
/// `witnesses`, when given, receives per sample the head pose X_RS (R frame) that showed it
/// scannable (identity for the other classes): a view the automatic scan can aim a pass from.
std::vector<SampleClass> classifyScannability(const AreaSampling& sampling,
                                              const PartOnTable& scene,
                                              const ScannabilitySettings& settings,
                                              std::vector<Eigen::Isometry3d>* witnesses = nullptr);

/// The scanner housing against the part and the table: its boxes (scanner frame S, m, already
/// grown by the clearance wanted) tested with ray segments on a grid no coarser than `spacing`
/// (the same test classifyScannability() uses; features smaller than the grid can slip through).
class HousingCheck {
 public:
  HousingCheck(const PartOnTable& scene,
               const std::vector<Eigen::AlignedBox3d>& housing,
               double spacing = 0.005);
  ~HousingCheck();
  HousingCheck(const HousingCheck&) = delete;
  HousingCheck& operator=(const HousingCheck&) = delete;
  /// No box of the housing at head pose X_RS (R frame) meets the part or the table.
  bool fits(const Eigen::Isometry3d& X_RS) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace scanplan::scanner
