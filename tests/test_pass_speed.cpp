// The speed of each candidate pass (scanner/scan_passes.h, evaluatePass() and timePass()) on
// synthetic parts with known answers: the speed follows from the point spacing, the frame rate
// and how the laser plane meets the surface, and the spacing the timed pass achieves is measured
// independently — the head interpolated at every profile time, the laser plane intersected with
// the part's faces analytically.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "geometry_support.h"
#include "pass_support.h"

#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/scan_path.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/scanner/area_coverage.h>
#include <scanplan/scanner/laser_model.h>
#include <scanplan/scanner/part_on_table.h>
#include <scanplan/scanner/pass_selection.h>
#include <scanplan/scanner/scan_passes.h>
#include <scanplan/scanner/simulator.h>

namespace {

using Eigen::Isometry3d;
using Eigen::Vector3d;
using scanplan::deg;
using scanplan::kinematics::TriangleMesh;
using scanplan::scanner::PartOnTable;
using scanplan::scanner::PassKind;
using scanplan::scanner::PassSettings;
using scanplan::scanner::SampleIndex;
using scanplan::scanner::ScanPass;

constexpr double kPi = std::numbers::pi;
constexpr scanplan::scanner::TableTop kTable = scanplan::test::kDemoTable;
// Relative tolerance of speeds computed in closed form from exact geometry (a flat face, a pure
// translation): only rounding separates the two.
constexpr double kExact = 1e-9;

using scanplan::test::demoHead;

// A box of half extents `half` placed by X_RB (R frame, m).
struct Box {
  Isometry3d X_RB = Isometry3d::Identity();
  Vector3d half = Vector3d::Ones();

  TriangleMesh mesh() const {
    TriangleMesh m = scanplan::test::centredCube(1.0);
    for (Vector3d& v : m.vertices) v = X_RB * (2.0 * half.cwiseProduct(v));
    return m;
  }
  // The first hit of the ray o + s·d (s > 0) and the outward normal there, R frame (slabs).
  std::optional<std::pair<Vector3d, Vector3d>> hit(const Vector3d& o, const Vector3d& d) const {
    const Isometry3d X_BR = X_RB.inverse();
    const Vector3d ob = X_BR * o, db = X_BR.linear() * d;
    double enter = 0.0, leave = 1e30;
    int axis = -1;
    for (int i = 0; i < 3; ++i) {
      if (std::abs(db[i]) < 1e-15) {
        if (std::abs(ob[i]) > half[i]) return std::nullopt;
        continue;
      }
      double a = (-half[i] - ob[i]) / db[i], b = (half[i] - ob[i]) / db[i];
      if (a > b) std::swap(a, b);
      if (a > enter) {
        enter = a;
        axis = i;
      }
      leave = std::min(leave, b);
    }
    if (axis < 0 || enter > leave) return std::nullopt;
    Vector3d n = Vector3d::Zero();
    n[axis] = db[axis] > 0.0 ? -1.0 : 1.0;
    return std::pair{X_RB * (ob + enter * db), X_RB.linear() * n};
  }
  bool onSurface(const Vector3d& p, double tol = 1e-9) const {
    const Vector3d q = X_RB.inverse() * p;
    return (q.cwiseAbs() - half).maxCoeff() <= tol;
  }
};

// A closed cylinder of `radius` and `height` standing on the table on its axis, `sides` facets.
TriangleMesh cylinder(double radius, double height, int sides) {
  TriangleMesh m;
  for (int i = 0; i < sides; ++i) {
    const double a = 2.0 * kPi * i / sides;
    m.vertices.emplace_back(radius * std::cos(a), radius * std::sin(a), 0.0);
    m.vertices.emplace_back(radius * std::cos(a), radius * std::sin(a), height);
  }
  const int bottom = static_cast<int>(m.vertices.size());
  m.vertices.emplace_back(0.0, 0.0, 0.0);
  m.vertices.emplace_back(0.0, 0.0, height);
  for (int i = 0; i < sides; ++i) {
    const int j = (i + 1) % sides;
    m.triangles.emplace_back(2 * i, 2 * j, 2 * j + 1);  // outward: counter-clockwise seen outside
    m.triangles.emplace_back(2 * i, 2 * j + 1, 2 * i + 1);
    m.triangles.emplace_back(bottom, 2 * j, 2 * i);
    m.triangles.emplace_back(bottom + 1, 2 * i + 1, 2 * j + 1);
  }
  return m;
}

// The head at p looking down (z_S = −z), moving along x_S = `along` (horizontal).
Isometry3d lookingDown(const Vector3d& p, const Vector3d& along) {
  return scanplan::kinematics::frameFromAxes(p, -Vector3d::UnitZ(), along);
}

// A strip of keys every `step` m from `from` to `to` (R frame), the head looking down along it.
ScanPass strip(const Vector3d& from, const Vector3d& to, double step) {
  ScanPass pass;
  pass.kind = PassKind::kStrip;
  const int n = static_cast<int>(std::ceil((to - from).norm() / step));
  for (int i = 0; i <= n; ++i) {
    pass.X_RS.push_back(lookingDown(from + (to - from) * i / n, (to - from).normalized()));
    pass.t.push_back(i);  // provisional, replaced by the evaluation
  }
  return pass;
}

// Covers and times `pass` over `scene` (area samples every 3 mm).
void evaluate(ScanPass& pass, const PartOnTable& scene, const PassSettings& s) {
  const auto sampling = scanplan::scanner::sampleArea(scene.part(), 0.003);
  const SampleIndex index(sampling);
  scanplan::scanner::evaluatePass(pass, scene, s, index);
}

// The head at time t of the timed pass: keys interpolated linearly in time, as the program runs
// them.
Isometry3d headAt(const ScanPass& pass, double t) {
  std::size_t k = 0;
  while (k + 2 < pass.t.size() && pass.t[k + 1] < t) ++k;
  const double s = std::clamp((t - pass.t[k]) / (pass.t[k + 1] - pass.t[k]), 0.0, 1.0);
  return scanplan::kinematics::interpolatePose(pass.X_RS[k], pass.X_RS[k + 1], s);
}

// Speed along stretch k: the head's translation (m/s) or, for a spin, the table's rate (rad/s).
double speed(const ScanPass& pass, std::size_t k) {
  const double dt = pass.t[k + 1] - pass.t[k];
  if (pass.kind == PassKind::kSpin) return std::abs(pass.azimuth[k + 1] - pass.azimuth[k]) / dt;
  return (pass.X_RS[k + 1].translation() - pass.X_RS[k].translation()).norm() / dt;
}

// Would the head at X measure the surface point q (normal n) on its laser ray d? Inside the
// window, within max_incidence of the laser and of a camera (convex parts: nothing occludes).
bool measured(const PassSettings& s,
              const Isometry3d& X,
              const Vector3d& q,
              const Vector3d& n,
              const Vector3d& d) {
  const double cos_max = std::cos(s.max_incidence);
  const Vector3d q_S = X.inverse() * q;
  if (!s.window.contains(q_S.y(), q_S.z()) || -n.dot(d) < cos_max) return false;
  for (const Vector3d& c : s.cameras)
    if (n.dot((X * c - q).normalized()) >= cos_max) return true;
  return false;
}

// The spacing the timed pass achieves on a box: for every profile (every 1/frame_rate s) and
// each of `rays` fan rays measuring a point q on a face, the distance on that face from q to the
// next profile's line, i.e. to the intersection of the next laser plane (x_S = 0) with the face's
// plane. The largest, and how many were measured.
struct Achieved {
  double worst = 0.0;
  int checked = 0;
};
Achieved achievedOnBox(const ScanPass& pass, const Box& box, const PassSettings& s, int rays = 9) {
  Achieved a;
  const std::vector<double> fan = scanplan::scanner::fanAngles(s.window, rays);
  const int frames = static_cast<int>(std::floor(pass.duration() * s.frame_rate));
  for (int j = 0; j < frames; ++j) {
    const Isometry3d Xa = headAt(pass, j / s.frame_rate), Xb = headAt(pass, (j + 1) / s.frame_rate);
    for (const double alpha : fan) {
      const Vector3d d = Xa.linear() * Vector3d(0.0, std::sin(alpha), std::cos(alpha));
      const auto hit = box.hit(Xa.translation(), d);
      if (!hit || !measured(s, Xa, hit->first, hit->second, d)) continue;
      const auto& [q, n] = *hit;
      const Vector3d x_b = Xb.linear().col(0);
      const Vector3d line = n.cross(x_b);  // the next line's direction in the face
      if (line.norm() < 1e-9) continue;
      const Vector3d across = line.cross(n).normalized();  // in the face, across the line
      // q + λ·across on the next laser plane: the nearest point of the next line to q.
      const double lambda = x_b.dot(Xb.translation() - q) / x_b.dot(across);
      if (!box.onSurface(q + lambda * across, 1e-6)) continue;  // it crossed onto another face
      a.worst = std::max(a.worst, std::abs(lambda));
      ++a.checked;
    }
  }
  return a;
}

// A 80 × 60 × 10 mm plate, its top's centre 60 mm above the table, tilted by `tilt` about y
// (towards +x), the whole scene turned by `yaw` about the table axis.
Box plate(double tilt, double yaw) {
  Box b;
  b.half = Vector3d(0.04, 0.03, 0.005);
  b.X_RB = Eigen::AngleAxisd(yaw, Vector3d::UnitZ()) * Eigen::Translation3d(0.0, 0.0, 0.06) *
           Eigen::AngleAxisd(tilt, Vector3d::UnitY()) * Eigen::Translation3d(0.0, 0.0, -0.005);
  return b;
}

// A strip along x over the plate (turned by yaw), the head 150 mm above the top's centre
// (the middle of the depth window), 6 mm between keys, `reach` either side of the centre.
ScanPass stripOverPlate(double yaw, double reach) {
  const Eigen::AngleAxisd turn(yaw, Vector3d::UnitZ());
  return strip(turn * Vector3d(-reach, 0.0, 0.21), turn * Vector3d(reach, 0.0, 0.21), 0.006);
}

// The stretches whose both keys see the plate's top with the central ray: the strip is over it.
std::vector<std::size_t> overPlate(const ScanPass& pass, const Box& box) {
  std::vector<std::size_t> out;
  const auto sees = [&](const Isometry3d& X) {
    const auto hit = box.hit(X.translation(), X.linear().col(2));
    return hit && hit->second.dot(box.X_RB.linear().col(2)) > 0.99;
  };
  for (std::size_t k = 0; k + 1 < pass.X_RS.size(); ++k)
    if (sees(pass.X_RS[k]) && sees(pass.X_RS[k + 1])) out.push_back(k);
  return out;
}

// Head-on (the plate's normal is z_S, across the laser plane's normal x_S) the profile lines
// move on the plate as fast as the head: one point spacing per profile, less the safety margin —
// about twice the old worst-case speed (spacing · cos 60° · frame rate).
TEST(StripSpeed, AHeadOnPlateIsScannedAtOneSpacingPerProfileLessTheMargin) {
  const PassSettings s = demoHead();
  const Box box = plate(0.0, 0.0);
  const PartOnTable scene(box.mesh(), Isometry3d::Identity(), kTable);
  ScanPass pass = stripOverPlate(0.0, 0.07);
  evaluate(pass, scene, s);
  ASSERT_FALSE(pass.covers.empty());
  const std::vector<std::size_t> over = overPlate(pass, box);
  ASSERT_GE(over.size(), 8u);
  const double expected = s.point_spacing * s.frame_rate * s.speed_safety;
  for (std::size_t k : over) EXPECT_NEAR(speed(pass, k), expected, kExact * expected) << k;
  EXPECT_GT(speed(pass, over.front()),
            1.5 * s.point_spacing * std::cos(s.max_incidence) * s.frame_rate);
  const Achieved a = achievedOnBox(pass, box, s);
  EXPECT_GT(a.checked, 1000);
  EXPECT_LE(a.worst, s.point_spacing * (1.0 + 1e-6));
}

// Tilted by θ about the strip's cross axis, the plate's normal n makes x_S·n = sin θ: the lines
// on it are the plane's level lines in the plate, 1/√(1 − (x_S·n)²) farther apart than the
// head's steps, so the head slows by √(1 − (x_S·n)²) = cos θ. The same under any turn of the
// whole scene about the table axis. Timed without that stretch the lines would lie
// speed_safety / cos 45° ≈ 1.27 spacings apart: the measured spacing catches it.
TEST(StripSpeed, APlateTiltedAcrossTheStripSlowsItByTheStretch) {
  const PassSettings s = demoHead();
  for (const double yaw : {0.0, deg(35.0), deg(-120.0)}) {
    const Box box = plate(deg(45.0), yaw);
    const PartOnTable scene(box.mesh(), Isometry3d::Identity(), kTable);
    ScanPass pass = stripOverPlate(yaw, 0.07);
    evaluate(pass, scene, s);
    const std::vector<std::size_t> over = overPlate(pass, box);
    ASSERT_GE(over.size(), 5u) << yaw;
    const Vector3d n = box.X_RB.linear().col(2), x_S = pass.X_RS.front().linear().col(0);
    const double expected =
        s.point_spacing * s.frame_rate * s.speed_safety * std::sqrt(1.0 - x_S.dot(n) * x_S.dot(n));
    EXPECT_NEAR(expected, s.point_spacing * s.frame_rate * s.speed_safety * std::cos(deg(45.0)),
                kExact);
    for (std::size_t k : over) EXPECT_NEAR(speed(pass, k), expected, kExact * expected) << k;
    const Achieved a = achievedOnBox(pass, box, s);
    EXPECT_GT(a.checked, 500) << yaw;
    EXPECT_LE(a.worst, s.point_spacing * (1.0 + 1e-6)) << yaw;
    EXPECT_GE(a.worst, 0.8 * s.point_spacing) << yaw;  // and not needlessly slow
  }
}

// With long leads that see nothing, the head runs at max_head_speed there, slows into the plate
// within max_head_accel and is back at the plate's speed over it.
TEST(StripSpeed, TheHeadKeepsItsSpeedAndAccelerationLimits) {
  PassSettings s = demoHead();
  s.max_head_speed = 0.1;
  s.max_head_accel = 0.3;
  const Box box = plate(0.0, 0.0);
  const PartOnTable scene(box.mesh(), Isometry3d::Identity(), kTable);
  ScanPass pass = stripOverPlate(0.0, 0.25);
  evaluate(pass, scene, s);
  double fastest = 0.0, tightest = 0.0;
  for (std::size_t k = 0; k + 1 < pass.X_RS.size(); ++k) {
    EXPECT_LE(speed(pass, k), s.max_head_speed * (1.0 + kExact)) << k;
    fastest = std::max(fastest, speed(pass, k));
    if (k + 2 < pass.X_RS.size()) {
      // Speeds are constant on a stretch: from one stretch's middle to the next.
      const double dt = 0.5 * (pass.t[k + 2] - pass.t[k]);
      const double change = std::abs(speed(pass, k + 1) - speed(pass, k));
      EXPECT_LE(change, s.max_head_accel * dt * (1.0 + 1e-6)) << k;
      tightest = std::max(tightest, change / (s.max_head_accel * dt));
    }
  }
  EXPECT_NEAR(fastest, s.max_head_speed, kExact);
  EXPECT_GT(tightest, 0.9);  // the acceleration is what limits the ramps
  const double over_plate = s.point_spacing * s.frame_rate * s.speed_safety;
  for (std::size_t k : overPlate(pass, box))
    EXPECT_NEAR(speed(pass, k), over_plate, kExact * over_plate) << k;
  EXPECT_LE(achievedOnBox(pass, box, s).worst, s.point_spacing * (1.0 + 1e-6));
}

// A head turning 10° per key while it moves 1 mm, seeing nothing (looking up): max_head_turn
// sets the pace.
TEST(StripSpeed, TheHeadKeepsItsTurnLimit) {
  PassSettings s = demoHead();
  s.max_head_turn = 0.8;
  const Box box = plate(0.0, 0.0);
  const PartOnTable scene(box.mesh(), Isometry3d::Identity(), kTable);
  ScanPass pass;
  for (int i = 0; i <= 9; ++i) {
    const double a = deg(10.0 * i);
    pass.X_RS.push_back(scanplan::kinematics::frameFromAxes(
        Vector3d(0.001 * i, 0.0, 0.3), Vector3d::UnitZ(), Vector3d(std::cos(a), std::sin(a), 0.0)));
  }
  evaluate(pass, scene, s);
  ASSERT_EQ(pass.t.size(), pass.X_RS.size());
  for (std::size_t k = 0; k + 1 < pass.X_RS.size(); ++k) {
    const double turn =
        scanplan::kinematics::rotationDistance(pass.X_RS[k].linear(), pass.X_RS[k + 1].linear());
    EXPECT_NEAR(turn / (pass.t[k + 1] - pass.t[k]), s.max_head_turn, kExact) << k;
  }
}

// A hand-written pass keeps the user's times; only its covers are filled.
TEST(StripSpeed, AGivenPassKeepsItsTimes) {
  const PassSettings s = demoHead();
  const Box box = plate(0.0, 0.0);
  const PartOnTable scene(box.mesh(), Isometry3d::Identity(), kTable);
  ScanPass pass = stripOverPlate(0.0, 0.03);
  pass.kind = PassKind::kGiven;
  const std::vector<double> times = pass.t;
  evaluate(pass, scene, s);
  EXPECT_FALSE(pass.covers.empty());
  EXPECT_EQ(pass.t, times);
}

// The level spin (elevation 0, camera ahead) nearest the middle of the part's height.
ScanPass levelSpin(const PartOnTable& scene, const PassSettings& s) {
  std::vector<ScanPass> spins;
  for (ScanPass& p : scanplan::scanner::candidatePasses(scene, s))
    if (p.kind == PassKind::kSpin && p.label.starts_with("spin elevation 0 deg") &&
        p.label.find("behind") == std::string::npos)
      spins.push_back(std::move(p));
  EXPECT_FALSE(spins.empty());
  return spins.empty() ? ScanPass{} : spins[spins.size() / 2];
}

// Around a cylinder of radius r on the axis, the head looks at the wall level: the wall moves
// through the laser plane at r·ω and the lines lie along the axis (x_S·n = 0), so the table turns
// at spacing · frame rate · safety / r, or at max_spin_rate if that is lower. Measured: the next
// profile's plane meets the circle at the point's height r·Δψ away.
TEST(SpinSpeed, ASpinAroundACylinderTurnsAtOneSpacingPerProfileAtItsRadius) {
  constexpr double kRadius = 0.04, kHeight = 0.06;
  constexpr int kSides = 128;
  // Facets put points up to 1/cos(π/128) farther along the wall than the circle: 3e-4.
  constexpr double kFacets = 1e-3;
  const PartOnTable scene(cylinder(kRadius, kHeight, kSides), Isometry3d::Identity(), kTable);
  for (const double cap : {5.0, 0.4}) {
    PassSettings s = demoHead();
    s.max_spin_rate = cap;
    ScanPass pass = levelSpin(scene, s);
    ASSERT_GE(pass.X_RS.size(), 100u);
    const std::vector<double> azimuth = pass.azimuth;
    evaluate(pass, scene, s);
    EXPECT_EQ(pass.azimuth, azimuth);
    const double expected =
        std::min(s.point_spacing * s.frame_rate * s.speed_safety / kRadius, s.max_spin_rate);
    for (std::size_t k = 0; k + 1 < pass.X_RS.size(); ++k)
      ASSERT_NEAR(speed(pass, k), expected, kFacets * expected) << "cap " << cap << ", " << k;
    EXPECT_NEAR(pass.duration(), 2.0 * kPi / expected, kFacets * 2.0 * kPi / expected);

    double worst = 0.0;
    int checked = 0;
    const std::vector<double> fan = scanplan::scanner::fanAngles(s.window, 9);
    const int frames = static_cast<int>(std::floor(pass.duration() * s.frame_rate));
    for (int j = 0; j < frames; ++j) {
      const Isometry3d Xa = headAt(pass, j / s.frame_rate);
      const Isometry3d Xb = headAt(pass, (j + 1) / s.frame_rate);
      for (const double alpha : fan) {
        const Vector3d o = Xa.translation();
        const Vector3d d = Xa.linear() * Vector3d(0.0, std::sin(alpha), std::cos(alpha));
        // o + λd on the wall: |(o + λd)_xy| = r, the nearer root.
        const double a = d.head<2>().squaredNorm(), b = o.head<2>().dot(d.head<2>()),
                     c = o.head<2>().squaredNorm() - kRadius * kRadius;
        if (b * b - a * c < 0.0) continue;
        const Vector3d q = o + ((-b - std::sqrt(b * b - a * c)) / a) * d;
        const Vector3d n(q.x() / kRadius, q.y() / kRadius, 0.0);
        if (q.z() < 0.005 || q.z() > kHeight - 0.005 || !measured(s, Xa, q, n, d)) continue;
        // The next plane x_b·(p − o_b) = 0 on the circle at q's height: A cos ψ + B sin ψ = C.
        const Vector3d x_b = Xb.linear().col(0), o_b = Xb.translation();
        const double A = kRadius * x_b.x(), B = kRadius * x_b.y(),
                     C = x_b.dot(o_b) - x_b.z() * q.z();
        const double psi_q = std::atan2(q.y(), q.x()), base = std::atan2(B, A);
        const double spread = std::acos(std::clamp(C / std::hypot(A, B), -1.0, 1.0));
        double arc = 1e30;
        for (const double psi : {base + spread, base - spread})
          arc = std::min(arc, kRadius * std::abs(std::remainder(psi - psi_q, 2.0 * kPi)));
        worst = std::max(worst, arc);
        ++checked;
      }
    }
    EXPECT_GT(checked, 1000) << cap;
    EXPECT_LE(worst, s.point_spacing * (1.0 + kFacets)) << cap;
    if (expected < s.max_spin_rate) {
      EXPECT_GE(worst, 0.8 * s.point_spacing) << cap;
    }
  }
}

// Around a square prism the seen radius and the faces' slant change along the turn, and so does
// the speed the spacing allows; the table's rate changes by at most max_spin_accel, never passes
// max_spin_rate, and the faces, measured analytically, get their spacing everywhere.
TEST(SpinSpeed, ASpinAroundAPrismChangesRateWithinTheTablesAcceleration) {
  PassSettings s = demoHead();
  s.max_spin_rate = 5.0;
  s.max_spin_accel = 0.5;
  Box box;
  box.half = Vector3d(0.03, 0.03, 0.025);
  box.X_RB = Eigen::Translation3d(0.0, 0.0, 0.025);
  const PartOnTable scene(box.mesh(), Isometry3d::Identity(), kTable);
  ScanPass pass = levelSpin(scene, s);
  ASSERT_GE(pass.X_RS.size(), 100u);
  evaluate(pass, scene, s);
  double fastest = 0.0, slowest = 1e30, tightest = 0.0;
  for (std::size_t k = 0; k + 1 < pass.X_RS.size(); ++k) {
    EXPECT_LE(speed(pass, k), s.max_spin_rate * (1.0 + kExact)) << k;
    fastest = std::max(fastest, speed(pass, k));
    slowest = std::min(slowest, speed(pass, k));
    if (k + 2 < pass.X_RS.size()) {
      const double dt = 0.5 * (pass.t[k + 2] - pass.t[k]);
      const double change = std::abs(speed(pass, k + 1) - speed(pass, k));
      EXPECT_LE(change, s.max_spin_accel * dt * (1.0 + 1e-6)) << k;
      tightest = std::max(tightest, change / (s.max_spin_accel * dt));
    }
  }
  EXPECT_GT(fastest, 1.2 * slowest);  // the rate does change along the turn
  EXPECT_GT(tightest, 0.9);           // and the acceleration limits it
  const Achieved a = achievedOnBox(pass, box, s);
  EXPECT_GT(a.checked, 1000);
  EXPECT_LE(a.worst, s.point_spacing * (1.0 + 1e-6));
}

// The level helix around a cylinder taller than several lines: its line climbs one line spacing
// per turn, so one pass sweeps the wall that the level spins sweep band by band. At every
// azimuth its turns lie one spacing apart (the spins' pitch spreads their lines evenly and is at
// most that), so it covers all they cover together. It turns up to one revolution more than
// they do (1 + H / spacing turns against ⌈H / spacing⌉ spins for an extent H) but saves the
// moves between them: back off to the transfer sphere, along it, in again (as the automatic scan
// connects passes).
TEST(Helix, AHelixCoversWhatTheLevelSpinsCoverInLessTimeThanThemAndTheMovesBetween) {
  constexpr double kRadius = 0.04, kHeight = 0.15;
  const PartOnTable scene(cylinder(kRadius, kHeight, 128), Isometry3d::Identity(), kTable);
  PassSettings s = demoHead();
  s.max_spin_rate = 2.0;  // a fast table: the point spacing sets the rate
  std::vector<ScanPass> passes = scanplan::scanner::candidatePasses(scene, s);
  std::vector<ScanPass> spins, helices;
  for (ScanPass& p : passes) {
    if (p.kind != PassKind::kSpin || p.label.find("behind") != std::string::npos) continue;
    if (p.label.starts_with("spin elevation 0 deg")) spins.push_back(p);
    if (p.label.starts_with("helix elevation 0 deg")) helices.push_back(p);
  }
  ASSERT_GE(spins.size(), 3u);
  ASSERT_EQ(helices.size(), 1u);
  ScanPass& helix = helices.front();
  const double spacing = 2.0 * s.window.y_near * (1.0 - s.overlap);
  const double turns = 1.0 + kHeight / spacing;
  // Azimuth and climb: at most 1 + H / spacing turns (from half a spacing below the part to half
  // a spacing above it, less the ends where its line sees nothing), one spacing per turn.
  ASSERT_GE(helix.azimuth.size(), 2u);
  const double turned = helix.azimuth.back() - helix.azimuth.front();
  EXPECT_LE(turned, 2.0 * kPi * turns + deg(2.0));
  EXPECT_GT(turned, 2.0 * kPi * (static_cast<double>(spins.size()) - 1.0));
  std::ostringstream label;
  label << "helix elevation 0 deg, " << std::fixed << std::setprecision(1) << turned / (2.0 * kPi)
        << " turns";
  EXPECT_EQ(helix.label, label.str());
  for (std::size_t k = 0; k + 1 < helix.azimuth.size(); ++k)
    ASSERT_GT(helix.azimuth[k + 1], helix.azimuth[k]) << k;
  EXPECT_NEAR(helix.X_RS.back().translation().z() - helix.X_RS.front().translation().z(),
              spacing * turned / (2.0 * kPi), 1e-9);

  const auto sampling = scanplan::scanner::sampleArea(scene.part(), 0.003);
  const SampleIndex index(sampling);
  scanplan::scanner::evaluatePasses(spins, scene, s, index);
  scanplan::scanner::evaluatePass(helix, scene, s, index);
  std::vector<std::uint8_t> by_spins(sampling.samples.size(), 0), by_helix(by_spins);
  for (const ScanPass& p : spins)
    for (std::uint32_t i : p.covers) by_spins[i] = 1;
  for (std::uint32_t i : helix.covers) by_helix[i] = 1;
  // At the wall's foot a line reaching below the table top backs off (the standoff keeps the
  // table beyond the window's near end), so what a pass gets there depends on where its line
  // passes; above the reach of such lines the helix covers everything the spins do.
  const double foot = 2.0 * s.window.y_near;
  std::size_t spun = 0, missed = 0, missed_above = 0;
  for (std::size_t i = 0; i < by_spins.size(); ++i) {
    if (!by_spins[i]) continue;
    ++spun;
    if (by_helix[i]) continue;
    ++missed;
    if (sampling.samples[i].p.z() > foot) ++missed_above;
  }
  EXPECT_GT(spun, sampling.samples.size() / 2);  // the wall: most of the area
  EXPECT_EQ(missed_above, 0u) << "of " << spun;
  EXPECT_LE(missed, spun / 100) << "of " << spun;
  EXPECT_GT(helix.covers.size(), spun);

  // Where its whole line is on the wall the table turns at the spins' rate (the same wall at the
  // same radius).
  const double rate = s.point_spacing * s.frame_rate * s.speed_safety / kRadius;
  const auto on_wall = [&](const Isometry3d& X) {
    return X.translation().z() > s.window.y_far && X.translation().z() < kHeight - s.window.y_far;
  };
  std::size_t level = 0;
  for (std::size_t k = 0; k + 1 < helix.X_RS.size(); ++k) {
    if (!on_wall(helix.X_RS[k]) || !on_wall(helix.X_RS[k + 1])) continue;
    ASSERT_NEAR(speed(helix, k), rate, 1e-3 * rate) << k;
    ++level;
  }
  EXPECT_GT(level, helix.X_RS.size() / 2);

  // The spins in the order of their height, each turned to start where the last one ended.
  std::sort(spins.begin(), spins.end(), [](const ScanPass& a, const ScanPass& b) {
    return a.X_RS.front().translation().z() < b.X_RS.front().translation().z();
  });
  scanplan::scanner::TransferSphere sphere;  // around the part, grown by the demo head's reach
  sphere.centre = Vector3d(0.0, 0.0, 0.5 * kHeight);
  sphere.radius = std::hypot(kRadius, 0.5 * kHeight) + 0.156 + 0.02;
  double spin_time = 0.0, moves = 0.0;
  Isometry3d at = spins.front().X_RS.front();
  for (const ScanPass& p : spins) {
    const Vector3d from = at.translation(), to = p.X_RS.front().translation();
    const ScanPass turned_spin = scanplan::scanner::rotatedPass(
        p, std::atan2(from.y(), from.x()) - std::atan2(to.y(), to.x()));
    moves += scanplan::scanner::transferTime(at, turned_spin.X_RS.front(), sphere);
    spin_time += p.duration();
    at = turned_spin.X_RS.back();
  }
  EXPECT_LT(helix.duration(), spin_time + moves)
      << "spins " << spin_time << " s, moves between them " << moves << " s";
  // At most one turn more than the spins.
  EXPECT_LT(helix.duration(), spin_time * (1.0 + 1.0 / static_cast<double>(spins.size())));
}

// The stretches a pass records for each sample it covers (the first and the last that see it,
// what trimmedPass() keeps) do see it: each cut out alone and evaluated again covers the sample.
// Around a cylinder a whole turn ends where it starts, so the samples under the seam are seen by
// the first and the last stretch and by none between.
TEST(PassCut, TheFirstAndLastStretchRecordedForASampleSeeIt) {
  const PartOnTable scene(cylinder(0.04, 0.06, 128), Isometry3d::Identity(), kTable);
  const PassSettings s = demoHead();
  const auto sampling = scanplan::scanner::sampleArea(scene.part(), 0.003);
  const SampleIndex index(sampling);
  ScanPass pass = levelSpin(scene, s);
  scanplan::scanner::evaluatePass(pass, scene, s, index);
  ASSERT_EQ(pass.cover_first.size(), pass.covers.size());
  ASSERT_EQ(pass.cover_last.size(), pass.covers.size());
  ASSERT_GE(pass.covers.size(), 200u);
  const std::size_t top = pass.X_RS.size() - 2;
  std::size_t seam = 0;
  for (std::size_t j = 0; j < pass.covers.size(); ++j) {
    ASSERT_LE(pass.cover_first[j], pass.cover_last[j]);
    ASSERT_LE(pass.cover_last[j], top);
    seam += pass.cover_first[j] == 0 && pass.cover_last[j] == top ? 1u : 0u;
  }
  EXPECT_GT(seam, 5u);
  for (std::size_t j = 0; j < pass.covers.size(); j += pass.covers.size() / 25) {
    for (const std::size_t k : {pass.cover_first[j], pass.cover_last[j]}) {
      ScanPass piece = scanplan::scanner::trimmedPass(pass, k, k);
      ASSERT_EQ(piece.X_RS.size(), 2u);
      EXPECT_TRUE(piece.X_RS[0].isApprox(pass.X_RS[k]));
      scanplan::scanner::evaluatePass(piece, scene, s, index);
      EXPECT_TRUE(std::binary_search(piece.covers.begin(), piece.covers.end(), pass.covers[j]))
          << "sample " << pass.covers[j] << ", stretch " << k;
    }
  }
  // Cut to its middle third, the pass is no longer a whole turn, and keeps fewer samples.
  const ScanPass third = scanplan::scanner::trimmedPass(pass, top / 3, 2 * top / 3);
  EXPECT_FALSE(third.turnable());
  EXPECT_TRUE(pass.turnable());
  EXPECT_LT(third.covers.size(), pass.covers.size());
  EXPECT_NEAR(third.duration(), pass.t[2 * top / 3 + 1] - pass.t[top / 3], 1e-12);
}

}  // namespace
