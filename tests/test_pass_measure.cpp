// What a pass measures as the scanner runs it (scanner::measurePass) and leaving out the passes a
// cover does not need (scanner::pruneToGoal), on synthetic cases with known answers: a strip over
// a plate against the plate's exact ray hits, profile by profile; small covers worked by hand;
// random covers against the properties the pruning promises.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "geometry_support.h"
#include "pass_support.h"

#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/scan_path.h>
#include <scanplan/scanner/area_coverage.h>
#include <scanplan/scanner/laser_model.h>
#include <scanplan/scanner/part_on_table.h>
#include <scanplan/scanner/pass_selection.h>
#include <scanplan/scanner/scan_passes.h>
#include <scanplan/scanner/simulator.h>

namespace {

using Eigen::Isometry3d;
using Eigen::Vector3d;
using scanplan::scanner::PartOnTable;
using scanplan::scanner::PassSettings;
using scanplan::scanner::pruneToGoal;
using scanplan::scanner::SampleIndex;
using scanplan::scanner::ScanPass;

// An 80 × 60 × 10 mm plate (R frame), its top at z = 60 mm, tilted by `tilt` about y.
struct Plate {
  Isometry3d X_RB = Isometry3d::Identity();
  Vector3d half{0.04, 0.03, 0.005};

  explicit Plate(double tilt) {
    X_RB = Eigen::Translation3d(0.0, 0.0, 0.055) * Eigen::AngleAxisd(tilt, Vector3d::UnitY());
  }
  scanplan::kinematics::TriangleMesh mesh() const {
    scanplan::kinematics::TriangleMesh m = scanplan::test::centredCube(1.0);
    for (Vector3d& v : m.vertices) v = X_RB * (2.0 * half.cwiseProduct(v));
    return m;
  }
  // The top face's hit of the ray o + s·d, and whether it lies on the top face.
  std::optional<Vector3d> topHit(const Vector3d& o, const Vector3d& d) const {
    const Isometry3d X_BR = X_RB.inverse();
    const Vector3d ob = X_BR * o, db = X_BR.linear() * d;
    if (!(db.z() < 0.0)) return std::nullopt;
    const double s = (half.z() - ob.z()) / db.z();
    const Vector3d q = ob + s * db;
    if (std::abs(q.x()) > half.x() || std::abs(q.y()) > half.y()) return std::nullopt;
    return X_RB * q;
  }
};

// A strip along x, the head looking down 150 mm above the plate's top, keys every 6 mm, timed
// at 40 mm/s.
ScanPass stripOver(double reach) {
  ScanPass pass;
  for (int i = 0; i <= static_cast<int>(std::lround(2.0 * reach / 0.006)); ++i) {
    const Vector3d p(-reach + 0.006 * i, 0.0, 0.21);
    pass.X_RS.push_back(
        scanplan::kinematics::frameFromAxes(p, -Vector3d::UnitZ(), Vector3d::UnitX()));
    pass.t.push_back(0.006 * i / 0.04);
  }
  return pass;
}

// The samples of the plate's top that measurePass() must call covered, found independently: at
// every profile time the head interpolated, each fan ray met with the top face exactly, kept
// inside the window and within the incidence limit, seen by the camera from the front (a convex
// plate hides nothing from it); then every sample within `radius` of such a point, by brute
// force. Per sample, the first stretch whose profile measures it.
std::vector<std::int64_t> expectedFirst(const ScanPass& pass,
                                        const Plate& plate,
                                        const PassSettings& s,
                                        const scanplan::scanner::AreaSampling& sampling,
                                        int rays,
                                        double radius) {
  std::vector<std::int64_t> first(sampling.samples.size(), -1);
  const std::vector<double> fan = scanplan::scanner::fanAngles(s.window, rays);
  const Vector3d n = plate.X_RB.linear().col(2);
  const int profiles = static_cast<int>(std::floor(pass.duration() * s.frame_rate + 1e-9)) + 1;
  for (int j = 0; j < profiles; ++j) {
    const double t = j / s.frame_rate;
    std::size_t k = 0;
    while (k + 2 < pass.t.size() && pass.t[k + 1] < t) ++k;
    const double u = std::clamp((t - pass.t[k]) / (pass.t[k + 1] - pass.t[k]), 0.0, 1.0);
    const Isometry3d X = scanplan::kinematics::interpolatePose(pass.X_RS[k], pass.X_RS[k + 1], u);
    for (const double alpha : fan) {
      const Vector3d d_S(0.0, std::sin(alpha), std::cos(alpha));
      const Vector3d d = X.linear() * d_S;
      const auto q = plate.topHit(X.translation(), d);
      if (!q) continue;
      const Vector3d q_S = X.inverse() * *q;
      if (!s.window.contains(q_S.y(), q_S.z()) || -n.dot(d) < std::cos(s.max_incidence)) continue;
      if (!(n.dot(X * s.cameras.front() - *q) > 0.0)) continue;
      for (std::size_t i = 0; i < sampling.samples.size(); ++i)
        if (first[i] < 0 && (sampling.samples[i].p - *q).norm() <= radius)
          first[i] = static_cast<std::int64_t>(k);
    }
  }
  return first;
}

// Tilted 50° away from the camera (100 mm along x_S, 150 mm up) it sees the top at about 84°:
// the planning model (camera within 60°) measures next to none of it, the scanner (and so
// measurePass()) all of it. Level, both agree. Either way measurePass() finds exactly the samples,
// and the first stretches, that the exact hits give, but for samples within rounding of the
// radius.
TEST(MeasurePass, CoversWhatTheExactHitsOfEveryProfileCover) {
  for (const double tilt_deg : {0.0, -50.0}) {
    const PassSettings s = scanplan::test::demoHead();
    const Plate plate(scanplan::deg(tilt_deg));
    const PartOnTable scene(plate.mesh(), Isometry3d::Identity(), scanplan::test::kDemoTable);
    const auto sampling = scanplan::scanner::sampleArea(scene.part(), 0.001);
    const SampleIndex index(sampling);
    ScanPass pass = stripOver(0.02);
    constexpr int kRays = 60;
    constexpr double kRadius = 5e-4;
    scanplan::scanner::measurePass(pass, scene, s, index, kRays, kRadius);
    const std::vector<std::int64_t> first = expectedFirst(pass, plate, s, sampling, kRays, kRadius);
    std::set<std::uint32_t> expected;
    for (std::size_t i = 0; i < first.size(); ++i)
      if (first[i] >= 0) expected.insert(static_cast<std::uint32_t>(i));
    ASSERT_GT(expected.size(), 500u) << tilt_deg;
    std::size_t differ = 0, wrong_first = 0;
    std::set<std::uint32_t> got(pass.covers.begin(), pass.covers.end());
    for (const std::uint32_t i : expected) differ += got.count(i) ? 0u : 1u;
    for (const std::uint32_t i : got) differ += expected.count(i) ? 0u : 1u;
    for (std::size_t j = 0; j < pass.covers.size(); ++j) {
      const std::int64_t f = first[pass.covers[j]];
      if (f >= 0 && std::abs(f - static_cast<std::int64_t>(pass.cover_first[j])) > 1) ++wrong_first;
      EXPECT_LE(pass.cover_first[j], pass.cover_last[j]);
    }
    // Embree's hits are float: a sample within ~1e-7 m of the radius may fall either side.
    EXPECT_LE(differ, expected.size() / 200) << tilt_deg;
    EXPECT_EQ(wrong_first, 0u) << tilt_deg;
    // The planning model, stricter on the camera, measures next to none of the tilted top.
    ScanPass planned = stripOver(0.02);
    scanplan::scanner::evaluatePass(planned, scene, s, index);
    if (tilt_deg < 0.0) {
      std::size_t top = 0;
      for (const std::uint32_t i : planned.covers) top += expected.count(i);
      EXPECT_LE(top, expected.size() / 100);  // at most the edges, near what the sides show
    }
  }
}

// Four passes over samples 0…99 (all counting), worked by hand for a goal of 90:
//   A 0…79 (10 s), B 70…89 (4 s), C 85…99 (2 s), D 90…91 (3 s).
// D adds nothing of its own: out first. Then B's own 80…84 cost 5 samples in 4 s against C's
// 90…99, 10 in 2 s, and A's 70 in 10 s: B goes (95 left). Neither A nor C can go then.
TEST(PruneToGoal, LeavesOutTheCheapestCoveragePerSecondUntilTheGoal) {
  const auto range = [](std::uint32_t a, std::uint32_t b) {
    ScanPass p;
    for (std::uint32_t i = a; i <= b; ++i) p.covers.push_back(i);
    return p;
  };
  const std::vector<ScanPass> passes{range(0, 79), range(70, 89), range(85, 99), range(90, 91)};
  const std::vector<double> cost{10.0, 4.0, 2.0, 3.0};
  const std::vector<std::uint8_t> counts(100, 1);
  EXPECT_EQ(pruneToGoal(passes, cost, counts, 0.9), (std::vector<std::size_t>{0, 2}));
  // At a goal of 100 only D may go; above what they cover, none.
  EXPECT_EQ(pruneToGoal(passes, cost, counts, 1.0), (std::vector<std::size_t>{0, 1, 2}));
  std::vector<std::uint8_t> more(120, 1);
  EXPECT_EQ(pruneToGoal(passes, cost, more, 0.9), (std::vector<std::size_t>{0, 1, 2, 3}));
  // Samples that do not count are not kept for: with 80…99 not counting, B, C and D all go.
  std::vector<std::uint8_t> some(100, 1);
  std::fill(some.begin() + 80, some.end(), 0);
  EXPECT_EQ(pruneToGoal(passes, cost, some, 0.95), (std::vector<std::size_t>{0}));
}

// Random covers: what is kept reaches the goal (half of what all the passes cover), and no kept
// pass could go without falling below it; at a goal of everything, no coverage is given up.
TEST(PruneToGoal, KeepsTheGoalAndOnlyPassesItNeeds) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 60; ++trial) {
    const std::uint32_t n = 200;
    std::vector<ScanPass> passes(5 + rng() % 20);
    std::vector<double> cost(passes.size());
    for (std::size_t p = 0; p < passes.size(); ++p) {
      const auto a = static_cast<std::uint32_t>(rng() % n);
      const auto len = static_cast<std::uint32_t>(1 + rng() % 40);
      for (std::uint32_t i = a; i < std::min(n, a + len); ++i) passes[p].covers.push_back(i);
      cost[p] = 0.5 + static_cast<double>(rng() % 100) / 10.0;
    }
    std::vector<std::uint8_t> counts(n);
    for (auto& c : counts) c = rng() % 5 != 0 ? 1 : 0;
    const auto coverage = [&](const std::vector<std::size_t>& kept) {
      std::vector<std::uint8_t> seen(n, 0);
      for (const std::size_t p : kept)
        for (const std::uint32_t i : passes[p].covers) seen[i] = counts[i];
      return static_cast<std::size_t>(std::count(seen.begin(), seen.end(), 1));
    };
    std::vector<std::size_t> all(passes.size());
    for (std::size_t p = 0; p < all.size(); ++p) all[p] = p;
    const std::size_t counted =
        static_cast<std::size_t>(std::count(counts.begin(), counts.end(), 1));
    const double goal = 0.5 * static_cast<double>(coverage(all)) / static_cast<double>(counted);
    const auto need =
        static_cast<std::size_t>(std::ceil(goal * static_cast<double>(counted) - 1e-9));
    const std::vector<std::size_t> kept = pruneToGoal(passes, cost, counts, goal);
    ASSERT_GE(coverage(kept), need) << trial;
    EXPECT_LT(kept.size(), passes.size()) << trial;
    for (std::size_t j = 0; j < kept.size(); ++j) {
      std::vector<std::size_t> less = kept;
      less.erase(less.begin() + static_cast<std::ptrdiff_t>(j));
      EXPECT_LT(coverage(less), need) << trial << " pass " << kept[j] << " was not needed";
    }
    // At a goal of all the counting samples, nothing they cover is given up.
    EXPECT_EQ(coverage(pruneToGoal(passes, cost, counts, 1.0)), coverage(all)) << trial;
  }
}

}  // namespace
