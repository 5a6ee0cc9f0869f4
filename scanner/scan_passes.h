#pragma once
// Candidate laser-line passes for the automatic scan (docs/design.md §11) and what each one covers.
// Everything is in the table-top frame R at table angle 0 (scanner/part_on_table.h): the table
// turns about R's z axis, so a pass's azimuth around the part is free and the arm only has to
// reach its view elevation.
//
// Three families:
// - spins: the head holds a pose in the world while the table turns a full revolution; in R the
//   head circles the axis with its laser plane through the axis, at a view elevation and an
//   offset along the line (a band of the part's surface of revolution);
// - helices: spins whose line centre climbs one line spacing along the line direction per
//   revolution, over several revolutions: one continuous pass over the whole surface of
//   revolution at a view elevation (PassKind::kSpin: the table turns with them, their azimuth
//   grows past 2π; the pass ends elsewhere than it starts). At every azimuth their turns lie
//   one line spacing apart, so they cover the part's extent when they run from half a spacing
//   below it to half a spacing above, 1 + extent / spacing turns: up to a turn more than the
//   spins of that elevation, without the moves between those;
// - strips: straight passes across the part seen from a view direction sampled on the sphere,
//   the table standing still.
// Each follows the surface: per profile the standoff puts the depths seen under the whole line
// (several rays cast across it) in the middle of the depth window, never nearer than its near
// end, smoothed to the most conservative standoff nearby.
//
// Timing: candidatePasses() times its keys at the worst case (a surface at the incidence limit;
// for spins, at the largest radius), which keeps the point spacing without knowing what a pass
// sees. evaluatePass() then retimes each pass from what it measures (timePass()): on each stretch
// between keys as fast as keeps the profile lines on the surface it actually scans within
// point_spacing of each other, within the head's and the table's speeds and accelerations.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/scanner/area_coverage.h>
#include <scanplan/scanner/laser_model.h>
#include <scanplan/scanner/part_on_table.h>

namespace scanplan::scanner {

/// What a pass must respect and how finely candidates are evaluated, SI.
struct PassSettings {
  LaserWindow window;                         ///< the laser's depth window (Eq. 5)
  std::vector<Eigen::Vector3d> cameras;       ///< camera centres in S; a point needs one of them
  double max_incidence = 1.0471975511965976;  ///< rad, laser and camera ray vs the normal
  double point_spacing = 2.5e-4;              ///< m, the spacing the passes must achieve
  double frame_rate = 100.0;                  ///< Hz, profiles per second
  double max_spin_rate = 0.4;  ///< rad/s, the table's turning rate in a spin; 0: no spins
  /// rad/s², how fast a spin's table rate may change from key to key (the table drives it).
  double max_spin_accel = 0.5;
  /// m/s, the head's translation speed along a pass (strips: in R, the table standing still;
  /// spins: in the world, i.e. its standoff changes). About what a 6-axis arm of the demo's
  /// size follows smoothly while it carries a scanner.
  double max_head_speed = 0.25;
  double max_head_turn = 1.0;   ///< rad/s, the head's rotation along a pass (as max_head_speed)
  double max_head_accel = 1.0;  ///< m/s², how fast a strip's head speed may change key to key
  /// Of the speed that spaces the profile lines exactly point_spacing apart on what the
  /// evaluated profiles see: the margin for surface between them, (0, 1].
  double speed_safety = 0.9;
  double overlap = 0.25;  ///< of the line width between neighbouring passes
  double lead = 0.01;     ///< m, a strip runs on this far beyond the part
  /// The scanner housing in S (m), grown by the clearance to keep from the part and the table:
  /// strips are cut to the stretch where it fits, spins dropped where it does not, helices cut
  /// to the longest stretch where it fits (dropped below a whole turn). Empty: none.
  std::vector<Eigen::AlignedBox3d> housing;
  double housing_spacing = 0.015;  ///< m, the housing test's grid (HousingCheck)
  int eval_rays = 41;              ///< fan rays per evaluated profile
  double eval_step = 0.0015;       ///< m, scanner travel between evaluated profiles
  double eval_radius = 0.0012;     ///< m, a sample within this of an evaluated point is covered
};

enum class PassKind : std::uint8_t { kSpin, kStrip, kGiven };
const char* passKindName(PassKind kind);  ///< "spin", "strip", "given"

/// One pass: keyed scanner poses (R frame) with their times; scanning along all of it.
struct ScanPass {
  PassKind kind = PassKind::kStrip;
  /// e.g. "spin elevation 25 deg, line at 12 mm", "helix elevation 0 deg, 5.2 turns"
  std::string label;
  std::vector<double> t;                ///< s from the pass start, per key, increasing
  std::vector<Eigen::Isometry3d> X_RS;  ///< scanner frame S in R, per key
  /// Spins: the azimuth (rad, about R's z) the head has turned by at each key, increasing (past
  /// 2π for a helix); the pass can start at any azimuth (rotate every pose about z).
  std::vector<double> azimuth;
  std::vector<std::uint32_t> covers;  ///< evaluation samples it covers, ascending
  /// Per entry of `covers`: the first and the last stretch (k: from key k to key k + 1) whose
  /// evaluated profiles cover that sample (a profile at key k counts for stretch k, the one at
  /// the last key for the last stretch). What a part of the pass covers (trimmedPass()).
  std::vector<std::uint32_t> cover_first, cover_last;
  /// s, the scanning time (once evaluated, see evaluatePass()).
  double duration() const { return t.empty() ? 0.0 : t.back() - t.front(); }
  /// A spin over a whole turn or more: it sees the same whatever azimuth it starts at, so a
  /// tour may turn it (rotatedPass()). A shorter arc sees what it sees only where it is.
  bool turnable() const {
    return kind == PassKind::kSpin && azimuth.size() >= 2 &&
           azimuth.back() - azimuth.front() >= 2.0 * 3.141592653589793 - 1e-9;
  }
};

/// The strip stations candidatePasses() probes for a part with these vertices (R frame): the
/// work it grows with (the square of the part's size), to check before generating.
double candidateStations(const std::vector<Eigen::Vector3d>& part_R, const PassSettings& settings);

/// Every candidate pass over the part (spins first, then helices, then strips), keys only (not
/// evaluated),
/// timed at the worst case (see the top of this file). Spins need max_spin_rate > 0.
/// Deterministic.
std::vector<ScanPass> candidatePasses(const PartOnTable& scene, const PassSettings& settings);

/// A short straight pass through a head pose that sees a sample (a scannability witness, R
/// frame): the pose moved along its x_S by up to ±half_length at a constant standoff, cut to
/// where the housing fits. For the surfaces the general candidates miss (bore walls, pockets).
/// Empty keys when not even the witness fits.
ScanPass aimedPass(const PartOnTable& scene,
                   const PassSettings& settings,
                   const Eigen::Isometry3d& witness,
                   double half_length = 0.03);

/// An arc of the table under a head that holds a scannability witness's pose in the world (R
/// frame): the witness turned about R's z, for a band of the part at that view, such as a bore
/// on the axis or features repeated around it (PassKind::kSpin, not turnable() unless a whole
/// turn fits). The longest run of 2° stations holding the witness where the housing fits, a
/// whole turn when all do; empty keys when that is less than `min_arc` (rad).
ScanPass aimedSpin(const PartOnTable& scene,
                   const PassSettings& settings,
                   const Eigen::Isometry3d& witness,
                   double min_arc = 0.35,
                   double max_arc = 6.283185307179586);

/// Area samples and a spatial index over them, for evaluating many passes.
class SampleIndex {
 public:
  explicit SampleIndex(const AreaSampling& sampling);
  ~SampleIndex();
  SampleIndex(const SampleIndex&) = delete;
  SampleIndex& operator=(const SampleIndex&) = delete;
  const AreaSampling& sampling() const { return sampling_; }
  /// Samples within `radius` of `p` whose normal is within 60° of `n`, appended to `out`.
  void near(const Eigen::Vector3d& p,
            const Eigen::Vector3d& n,
            double radius,
            std::vector<std::uint32_t>& out) const;
  /// Samples within `radius` of `p`, whatever their normals, appended to `out`.
  void within(const Eigen::Vector3d& p, double radius, std::vector<std::uint32_t>& out) const;
  /// The sample nearest to `p`. Precondition: at least one sample.
  std::uint32_t nearest(const Eigen::Vector3d& p) const;

 private:
  struct Tree;
  const AreaSampling& sampling_;
  std::unique_ptr<Tree> tree_;
};

/// Times a pass's keys (sets `pass.t`, from 0; keeps its keys and azimuths) from how far the
/// laser line moves over the surface it scans on each stretch between keys: `line_travel[k]`
/// (m, 0 where the stretch sees nothing) between keys k and k + 1. Each stretch takes at least
/// line_travel / (speed_safety · point_spacing · frame_rate), so consecutive profiles lie at most
/// point_spacing apart on the surface, and no less than the head's limits allow: max_head_speed
/// and max_head_turn (strips: the motion in R; spins: in the world, the table turning the
/// azimuth away), and for spins max_spin_rate. Then the speed along the pass (strips: the head's
/// translation, m/s; spins: the table's rate, rad/s) is made to change by at most
/// max_head_accel / max_spin_accel: the time-optimal profile under those caps (a forward and a
/// backward pass; the pass may start and end at full speed, the moves between passes stop).
/// Between keys the speed is constant (keys are interpolated linearly in time). Consecutive keys
/// are at least 1 µs apart. A limit ≤ 0 is none. `line_travel` has an entry per stretch
/// (X_RS.size() − 1; missing ones count as seeing nothing).
void timePass(ScanPass& pass, const PassSettings& settings, const std::vector<double>& line_travel);

/// Fills `pass.covers`: the samples (of `index`, R frame) that a measured point of the pass
/// lands near. Profiles every eval_step of head travel, eval_rays fan rays each; a ray yields a
/// point when it hits the part first inside the window trapezoid, within max_incidence of the
/// normal, and a camera sees the point within max_incidence with nothing in between.
///
/// Also retimes the pass (timePass(); not a PassKind::kGiven pass, whose times are the user's):
/// a point p (normal n) measured between keys X_a and X_b moves across the laser plane by
/// Δx = |(X_b⁻¹p).x − (X_a⁻¹p).x|, so its profile line moves over the surface by
/// Δx / √(1 − (x_S·n)²); the stretch's line_travel is the largest of those. Afterwards
/// `pass.duration()` is the pass's scanning time.
void evaluatePass(ScanPass& pass,
                  const PartOnTable& scene,
                  const PassSettings& settings,
                  const SampleIndex& index);

/// evaluatePass() over all passes (covers and times), in parallel (TBB); the result does not
/// depend on threads.
/// `progress` (passes done, passes in all) is called from worker threads: serialise inside.
void evaluatePasses(std::vector<ScanPass>& passes,
                    const PartOnTable& scene,
                    const PassSettings& settings,
                    const SampleIndex& index,
                    const std::function<void(std::size_t, std::size_t)>& progress = {});

/// Fills `pass.covers`, `cover_first` and `cover_last` with what the scanner measures as it runs
/// the pass (keys and times unchanged): a profile every 1 / frame_rate s of the pass's time from
/// its start (keys interpolated linearly in time), `rays` fan rays each, points as evaluatePass()
/// finds them except that a camera need only see a point from its front (as the scanner
/// simulation has it, scanner/simulator.h); a sample of `index` is covered when a point lies within
/// `radius` of it (as the area coverage of a cloud counts it, scanner/area_coverage.h). A profile
/// on stretch k (keys k to k + 1) counts for that stretch. With the whole fan and the simulation's
/// area samples and radius, this is the coverage the simulated cloud will have, pass by pass,
/// before any motion is planned. Deterministic.
void measurePass(ScanPass& pass,
                 const PartOnTable& scene,
                 const PassSettings& settings,
                 const SampleIndex& index,
                 int rays,
                 double radius);

/// The pass turned about R's z by `angle` (rad): a spin started at another azimuth.
ScanPass rotatedPass(const ScanPass& pass, double angle);

/// The stretches `first`…`last` of an evaluated pass (keys first…last + 1, times from 0). It
/// covers the samples whose first or last covering stretch it keeps (the stretches between may
/// not see a sample: a spin's seam, a helix's neighbouring turns), renumbered. A spin cut to
/// less than a whole turn is no longer turnable(). With `pad` (s) it runs that much longer at
/// either end where the pass does (keys interpolated linearly in time, as the pass runs).
/// Precondition: first ≤ last < X_RS.size() − 1, a timed pass.
ScanPass trimmedPass(const ScanPass& pass, std::size_t first, std::size_t last, double pad = 0.0);

}  // namespace scanplan::scanner
