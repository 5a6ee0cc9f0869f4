#include <scanplan/scanner/scan_passes.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <nanoflann.hpp>

#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/scan_path.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/scanner/scannability.h>
#include <scanplan/scanner/simulator.h>

namespace scanplan::scanner {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kStation = 0.002;    // m between probed strip stations
constexpr double kSpinStation = 2.0;  // deg between probed spin stations
constexpr double kSmoothing = 0.015;  // m, the conservative standoff window (strips)
constexpr int kSpinSmoothing = 4;     // stations either side (spins)
constexpr int kStripKeyEvery = 3;     // stations per strip key

double zMid(const LaserWindow& w) { return 0.5 * (w.z_min + w.z_max); }

// The surface under a whole line: the head's probe origin o (far before the part), looking along
// v, the line along y. Returns the head's advance along v from o that centres the seen depths in
// the window (never nearer than z_min to anything), NaN when no ray meets the part; `rho` grows
// to the largest distance of a part hit from the table axis.
double probeLine(const PartOnTable& scene,
                 const LaserWindow& window,
                 const Eigen::Vector3d& o,
                 const Eigen::Vector3d& v,
                 const Eigen::Vector3d& y,
                 double& rho) {
  const double half = 0.9 * window.y_near;
  double nearest = 1e30, farthest = -1e30;
  bool part = false;
  for (int k = -3; k <= 3; ++k) {
    const auto hit = scene.cast(o + (half * k / 3.0) * y, v);
    if (!hit) continue;
    nearest = std::min(nearest, hit->distance);
    if (!scene.onPart(*hit)) continue;
    part = true;
    farthest = std::max(farthest, hit->distance);
    rho = std::max(rho, (o + (half * k / 3.0) * y + hit->distance * v).head<2>().norm());
  }
  if (!part) return kNaN;
  return std::min(0.5 * (nearest + farthest) - zMid(window), nearest - window.z_min);
}

// Does the line of a head at o (looking along v, the line along y) meet the part first, inside
// the depth window, with any of the rays probeLine() casts?
bool seesPart(const PartOnTable& scene,
              const LaserWindow& window,
              const Eigen::Vector3d& o,
              const Eigen::Vector3d& v,
              const Eigen::Vector3d& y) {
  const double half = 0.9 * window.y_near;
  for (int k = -3; k <= 3; ++k) {
    const auto hit = scene.cast(o + (half * k / 3.0) * y, v);
    if (hit && scene.onPart(*hit) && hit->distance >= window.z_min && hit->distance <= window.z_max)
      return true;
  }
  return false;
}

// The most conservative (least advanced) standoff within ±reach stations; NaN stations take the
// least advanced of all. Circular for closed passes.
std::vector<double> smoothStandoff(const std::vector<double>& advance, int reach, bool circular) {
  double fallback = 1e30;
  for (double a : advance)
    if (!std::isnan(a)) fallback = std::min(fallback, a);
  const int n = static_cast<int>(advance.size());
  std::vector<double> out(advance.size());
  for (int i = 0; i < n; ++i) {
    double m = 1e30;
    for (int j = i - reach; j <= i + reach; ++j) {
      int k = j;
      if (circular) k = ((j % n) + n) % n;
      if (k < 0 || k >= n) continue;
      const double a = advance[static_cast<std::size_t>(k)];
      m = std::min(m, std::isnan(a) ? fallback : a);
    }
    out[static_cast<std::size_t>(i)] = m;
  }
  return out;
}

// The provisional (worst-case) speed: one point spacing per profile on a surface the motion
// meets at the incidence limit, where the profiles lie point_spacing · cos(max_incidence) apart
// along the head's path. evaluatePass() retimes from what a pass sees.
double scanSpeed(const PassSettings& s) {
  return std::min(s.point_spacing * std::cos(s.max_incidence) * s.frame_rate, s.max_head_speed);
}

// Largest distance of a part vertex from the origin of R, and the part's height and radius.
struct PartSpan {
  double reach = 0.0, rho = 0.0, z_top = 0.0;
};
PartSpan partSpan(const kinematics::TriangleMesh& part) {
  PartSpan s;
  for (const Eigen::Vector3d& p : part.vertices) {
    s.reach = std::max(s.reach, p.norm());
    s.rho = std::max(s.rho, p.head<2>().norm());
    s.z_top = std::max(s.z_top, p.z());
  }
  return s;
}

// One spin: elevation e (rad, view down from horizontal), the line centre at u along the line
// direction in the plane through the axis, the camera ahead (+1) or behind (−1).
bool spinPass(const PartOnTable& scene,
              const HousingCheck& housing,
              const PassSettings& settings,
              double e,
              double u,
              int camera_side,
              double far,
              ScanPass& pass) {
  const int n = static_cast<int>(std::lround(360.0 / kSpinStation));
  std::vector<double> advance(static_cast<std::size_t>(n));
  std::vector<Eigen::Vector3d> origin(advance.size()), view(advance.size()),
      tangent(advance.size());
  double rho = 0.0;
  for (int j = 0; j < n; ++j) {
    const double phi = deg(kSpinStation * j);
    const Eigen::Vector3d r(std::cos(phi), std::sin(phi), 0.0), z = Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d line = -std::sin(e) * r + std::cos(e) * z;
    const Eigen::Vector3d v = -std::cos(e) * r - std::sin(e) * z;
    const auto i = static_cast<std::size_t>(j);
    view[i] = v;
    tangent[i] = z.cross(r);
    origin[i] = u * line - far * v;
    advance[i] = probeLine(scene, settings.window, origin[i], v, line, rho);
  }
  if (std::all_of(advance.begin(), advance.end(), [](double a) { return std::isnan(a); }))
    return false;
  const std::vector<double> smooth = smoothStandoff(advance, kSpinSmoothing, true);
  const double omega = std::min(scanSpeed(settings) / std::max(rho, 1e-3), settings.max_spin_rate);
  pass.kind = PassKind::kSpin;
  pass.label = fmt::format("spin elevation {:.0f} deg, line at {:.0f} mm{}", toDeg(e), toMm(u),
                           camera_side > 0 ? "" : ", camera behind");
  for (int j = 0; j <= n; ++j) {
    const auto i = static_cast<std::size_t>(j % n);
    const double phi = deg(kSpinStation * j);
    pass.t.push_back(phi / omega);
    pass.azimuth.push_back(phi);
    pass.X_RS.push_back(kinematics::frameFromAxes(origin[i] + smooth[i] * view[i], view[i],
                                                  camera_side * tangent[i]));
    if (j < n && !housing.fits(pass.X_RS.back())) return false;
  }
  return true;
}

// One helix: a spin at elevation e whose line centre climbs along the line direction by `pitch`
// per revolution while the table turns, from u_first over `turns` revolutions, the camera ahead
// (+1) or behind (−1). Cut to the longest run of keys where the housing fits; dropped when that
// is less than a whole turn.
bool helixPass(const PartOnTable& scene,
               const HousingCheck& housing,
               const PassSettings& settings,
               double e,
               double u_first,
               double pitch,
               double turns,
               int camera_side,
               double far,
               ScanPass& pass) {
  const int per_turn = static_cast<int>(std::lround(360.0 / kSpinStation));
  const int n = static_cast<int>(std::ceil(turns * per_turn));
  const auto stations = static_cast<std::size_t>(n) + 1;
  std::vector<double> advance(stations), phi(stations);
  std::vector<Eigen::Vector3d> origin(stations), view(stations), tangent(stations), line(stations);
  double rho = 0.0;
  for (int j = 0; j <= n; ++j) {
    const auto i = static_cast<std::size_t>(j);
    phi[i] = deg(kSpinStation * j);
    const Eigen::Vector3d r(std::cos(phi[i]), std::sin(phi[i]), 0.0), z = Eigen::Vector3d::UnitZ();
    line[i] = -std::sin(e) * r + std::cos(e) * z;
    view[i] = -std::cos(e) * r - std::sin(e) * z;
    tangent[i] = z.cross(r);
    origin[i] = (u_first + pitch * phi[i] / (2.0 * std::numbers::pi)) * line[i] - far * view[i];
    advance[i] = probeLine(scene, settings.window, origin[i], view[i], line[i], rho);
  }
  if (std::all_of(advance.begin(), advance.end(), [](double a) { return std::isnan(a); }))
    return false;
  const std::vector<double> smooth = smoothStandoff(advance, kSpinSmoothing, false);
  // Its ends where the line sees no part inside the window (beyond the part, or backed off from
  // the table) are left out.
  std::size_t seen_first = stations, seen_last = 0;
  for (std::size_t i = 0; i < stations; ++i) {
    if (!seesPart(scene, settings.window, origin[i] + smooth[i] * view[i], view[i], line[i]))
      continue;
    seen_first = std::min(seen_first, i);
    seen_last = i;
  }
  if (seen_first > seen_last) return false;
  // The longest run of keys where the housing fits.
  std::vector<Eigen::Isometry3d> keys(stations);
  std::size_t best_first = 0, best_count = 0, first = seen_first;
  for (std::size_t i = seen_first; i <= seen_last; ++i) {
    keys[i] = kinematics::frameFromAxes(origin[i] + smooth[i] * view[i], view[i],
                                        camera_side * tangent[i]);
    if (!housing.fits(keys[i])) {
      first = i + 1;
      continue;
    }
    if (i + 1 - first > best_count) {
      best_first = first;
      best_count = i + 1 - first;
    }
  }
  if (best_count < static_cast<std::size_t>(per_turn) + 1) return false;
  const double omega = std::min(scanSpeed(settings) / std::max(rho, 1e-3), settings.max_spin_rate);
  pass.kind = PassKind::kSpin;
  pass.label = fmt::format("helix elevation {:.0f} deg, {:.1f} turns{}", toDeg(e),
                           static_cast<double>(best_count - 1) / per_turn,
                           camera_side > 0 ? "" : ", camera behind");
  for (std::size_t i = best_first; i < best_first + best_count; ++i) {
    pass.t.push_back((phi[i] - phi[best_first]) / omega);
    pass.azimuth.push_back(phi[i]);
    pass.X_RS.push_back(keys[i]);
  }
  return true;
}

void addSpins(const PartOnTable& scene,
              const HousingCheck& housing,
              const PassSettings& settings,
              std::vector<ScanPass>& out) {
  if (!(settings.max_spin_rate > 0.0)) return;
  const PartSpan span = partSpan(scene.part());
  const double spacing = 2.0 * settings.window.y_near * (1.0 - settings.overlap);
  const std::array<double, 6> elevations{-20.0, 0.0, 25.0, 50.0, 70.0, 90.0};
  // The part's (ρ, z) profile projected on the line direction (−sin e, cos e).
  const auto extent = [&](double e) {
    double lo = 1e30, hi = -1e30;
    for (double rho : {0.0, span.rho})
      for (double z : {0.0, span.z_top}) {
        lo = std::min(lo, -rho * std::sin(e) + z * std::cos(e));
        hi = std::max(hi, -rho * std::sin(e) + z * std::cos(e));
      }
    return std::pair{lo, hi};
  };
  // Each spin and helix is made on its own (in parallel), kept in this order.
  struct Job {
    double e = 0.0, u = 0.0, turns = 0.0;  // turns > 0: a helix from u
    int side = 1;
  };
  std::vector<Job> jobs;
  for (double e_deg : elevations) {
    const double e = deg(e_deg);
    const auto [lo, hi] = extent(e);
    const int lines = std::max(1, static_cast<int>(std::ceil((hi - lo) / spacing)));
    for (int k = 0; k < lines; ++k)
      for (int side : {1, -1}) jobs.push_back({e, lo + (hi - lo) * (k + 0.5) / lines, 0.0, side});
  }
  // Helices, where the extent takes more than one spin. At every azimuth the helix's turns lie
  // one spacing apart, shifted by the turned fraction of a spacing: the lowest is at most half a
  // spacing above lo, the highest at least half a spacing below hi (the margins the spins keep
  // between neighbouring lines) when it runs from lo − spacing / 2 to hi + spacing / 2, over
  // 1 + (hi − lo) / spacing turns.
  for (double e_deg : elevations) {
    const double e = deg(e_deg);
    const auto [lo, hi] = extent(e);
    if (!(hi - lo > spacing)) continue;
    for (int side : {1, -1})
      jobs.push_back({e, lo - 0.5 * spacing, 1.0 + (hi - lo) / spacing, side});
  }
  std::vector<ScanPass> made(jobs.size());
  std::vector<std::uint8_t> ok(jobs.size(), 0);
  tbb::parallel_for(std::size_t{0}, jobs.size(), [&](std::size_t i) {
    const Job& j = jobs[i];
    if (j.turns > 0.0) {
      const double top = j.u + j.turns * spacing;  // the helix's last line, half a spacing up
      const double far = span.reach + std::max(std::abs(j.u), std::abs(top)) + 0.05;
      ok[i] = helixPass(scene, housing, settings, j.e, j.u, spacing, j.turns, j.side, far, made[i]);
    } else {
      ok[i] = spinPass(scene, housing, settings, j.e, j.u, j.side,
                       span.reach + std::abs(j.u) + 0.05, made[i]);
    }
  });
  for (std::size_t i = 0; i < jobs.size(); ++i)
    if (ok[i]) out.push_back(std::move(made[i]));
}

// A strip's axes: v the view, u along the strip, w across; the part's extent on them.
struct StripAxes {
  Eigen::Vector3d u, v, w;
  double u_min = 1e30, u_max = -1e30, w_min = 1e30, w_max = -1e30, v_min = 1e30;
};

StripAxes stripAxes(const kinematics::TriangleMesh& part,
                    const Eigen::Vector3d& v,
                    const Eigen::Vector3d& u) {
  StripAxes a{u, v, v.cross(u)};
  for (const Eigen::Vector3d& p : part.vertices) {
    a.u_min = std::min(a.u_min, p.dot(a.u));
    a.u_max = std::max(a.u_max, p.dot(a.u));
    a.w_min = std::min(a.w_min, p.dot(a.w));
    a.w_max = std::max(a.w_max, p.dot(a.w));
    a.v_min = std::min(a.v_min, p.dot(a.v));
  }
  return a;
}

// One strip at w across, the camera ahead (+1) or behind (−1) along +u.
bool stripPass(const PartOnTable& scene,
               const HousingCheck& housing,
               const PassSettings& settings,
               const StripAxes& a,
               double w,
               int camera_side,
               ScanPass& pass) {
  const double start = a.u_min - settings.lead;
  const int n =
      static_cast<int>(std::ceil((a.u_max - a.u_min + 2.0 * settings.lead) / kStation)) + 1;
  const Eigen::Vector3d plane = w * a.w + (a.v_min - 0.1) * a.v;
  std::vector<double> advance(static_cast<std::size_t>(n));
  double rho = 0.0;
  int first = n, last = -1;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d o = plane + (start + kStation * i) * a.u;
    advance[static_cast<std::size_t>(i)] = probeLine(scene, settings.window, o, a.v, a.w, rho);
    if (!std::isnan(advance[static_cast<std::size_t>(i)])) {
      first = std::min(first, i);
      last = i;
    }
  }
  if (last < 0) return false;
  const int lead = static_cast<int>(std::ceil(settings.lead / kStation));
  first = std::max(0, first - lead);
  last = std::min(n - 1, last + lead);
  const std::vector<double> smooth =
      smoothStandoff(advance, static_cast<int>(kSmoothing / kStation), false);
  pass.kind = PassKind::kStrip;
  // Keys where the housing fits; the strip is the longest unbroken run of them.
  std::vector<Eigen::Isometry3d> run, best;
  for (int i = first;; i = std::min(i + kStripKeyEvery, last)) {
    const Eigen::Vector3d o =
        plane + (start + kStation * i) * a.u + smooth[static_cast<std::size_t>(i)] * a.v;
    const Eigen::Isometry3d X = kinematics::frameFromAxes(o, a.v, camera_side * a.u);
    if (housing.fits(X)) {
      run.push_back(X);
    } else {
      run.clear();
    }
    if (run.size() > best.size()) best = run;
    if (i == last) break;
  }
  for (const Eigen::Isometry3d& X : best) {
    pass.t.push_back(
        pass.t.empty() ? 0.0
                       : pass.t.back() + (X.translation() - pass.X_RS.back().translation()).norm() /
                                             scanSpeed(settings));
    pass.X_RS.push_back(X);
  }
  return pass.t.size() >= 2;
}

// View directions (from the head toward the part) sampled on the sphere: straight down, then
// rings of azimuths at lower elevations; each with its strip directions.
std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> stripViews() {
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> views;
  const Eigen::Vector3d down = -Eigen::Vector3d::UnitZ();
  views.push_back({down, Eigen::Vector3d::UnitX()});
  views.push_back({down, Eigen::Vector3d::UnitY()});
  const std::pair<double, int> rings[] = {
      {70.0, 8}, {50.0, 12}, {30.0, 12}, {10.0, 12}, {-10.0, 12}};
  for (const auto& [elevation, count] : rings) {
    for (int k = 0; k < count; ++k) {
      const double phi = deg(360.0 * k / count), e = deg(elevation);
      const Eigen::Vector3d r(std::cos(phi), std::sin(phi), 0.0);
      const Eigen::Vector3d v = -std::cos(e) * r - std::sin(e) * Eigen::Vector3d::UnitZ();
      const Eigen::Vector3d across = Eigen::Vector3d::UnitZ().cross(r);  // horizontal
      views.push_back({v, across});
      views.push_back({v, v.cross(across).normalized()});  // up the part
    }
  }
  return views;
}

void addStrips(const PartOnTable& scene,
               const HousingCheck& housing,
               const PassSettings& settings,
               std::vector<ScanPass>& out) {
  const double spacing = 2.0 * settings.window.y_near * (1.0 - settings.overlap);
  // Each strip is made on its own (in parallel), kept in this order.
  struct Job {
    StripAxes axes;
    double elevation = 0.0, azimuth = 0.0, w = 0.0;
    int k = 0, strips = 0, side = 1;
  };
  std::vector<Job> jobs;
  for (const auto& [v, u] : stripViews()) {
    const StripAxes a = stripAxes(scene.part(), v, u);
    const int strips = std::max(1, static_cast<int>(std::ceil((a.w_max - a.w_min) / spacing)));
    const double e = std::asin(std::clamp(-v.z(), -1.0, 1.0));
    for (int k = 0; k < strips; ++k) {
      const double w = a.w_min + (a.w_max - a.w_min) * (k + 0.5) / strips;
      // The camera ahead of the laser turning counter-clockwise about the table axis (as in a
      // spin): every strip then holds the head the same way round seen from the robot, once the
      // table brings it in front, so the wrist does not wind up from pass to pass.
      const Eigen::Vector3d centre = 0.5 * (a.u_min + a.u_max) * a.u + w * a.w;
      const int side = Eigen::Vector3d::UnitZ().cross(centre).dot(a.u) < 0.0 ? -1 : 1;
      jobs.push_back({a, e, std::atan2(-v.y(), -v.x()), w, k, strips, side});
    }
  }
  std::vector<ScanPass> made(jobs.size());
  std::vector<std::uint8_t> ok(jobs.size(), 0);
  tbb::parallel_for(std::size_t{0}, jobs.size(), [&](std::size_t i) {
    const Job& j = jobs[i];
    if (!stripPass(scene, housing, settings, j.axes, j.w, j.side, made[i])) return;
    made[i].label = fmt::format("strip view elevation {:.0f} deg azimuth {:.0f} deg, {} of {}",
                                toDeg(j.elevation), toDeg(j.azimuth), j.k + 1, j.strips);
    ok[i] = 1;
  });
  for (std::size_t i = 0; i < jobs.size(); ++i)
    if (ok[i]) out.push_back(std::move(made[i]));
}

}  // namespace

const char* passKindName(PassKind kind) {
  switch (kind) {
    case PassKind::kSpin:
      return "spin";
    case PassKind::kStrip:
      return "strip";
    case PassKind::kGiven:
      return "given";
  }
  return "?";
}

double candidateStations(const std::vector<Eigen::Vector3d>& part_R, const PassSettings& settings) {
  kinematics::TriangleMesh points;
  points.vertices = part_R;
  const double spacing = 2.0 * settings.window.y_near * (1.0 - settings.overlap);
  double stations = 0.0;
  for (const auto& [v, u] : stripViews()) {
    const StripAxes a = stripAxes(points, v, u);
    stations += std::max(1.0, std::ceil((a.w_max - a.w_min) / spacing)) *
                std::ceil((a.u_max - a.u_min + 2.0 * settings.lead) / kStation);
  }
  return stations;
}

std::vector<ScanPass> candidatePasses(const PartOnTable& scene, const PassSettings& settings) {
  const HousingCheck housing(scene, settings.housing, settings.housing_spacing);
  std::vector<ScanPass> out;
  addSpins(scene, housing, settings, out);
  addStrips(scene, housing, settings, out);
  return out;
}

ScanPass aimedPass(const PartOnTable& scene,
                   const PassSettings& settings,
                   const Eigen::Isometry3d& witness,
                   double half_length) {
  const HousingCheck housing(scene, settings.housing, settings.housing_spacing);
  const Eigen::Vector3d x = witness.linear().col(0);
  const int steps =
      std::max(1, static_cast<int>(std::ceil(half_length / (kStation * kStripKeyEvery))));
  // The longest run of fitting keys that holds the witness itself.
  std::vector<Eigen::Isometry3d> keys;
  for (int i = -steps; i <= steps; ++i) {
    Eigen::Isometry3d X = witness;
    X.translation() += (half_length * i / steps) * x;
    if (housing.fits(X)) {
      keys.push_back(X);
    } else if (i < 0) {
      keys.clear();
    } else {
      break;
    }
  }
  ScanPass pass;
  pass.kind = PassKind::kStrip;
  const Eigen::Vector3d p = witness.translation() + zMid(settings.window) * witness.linear().col(2);
  pass.label =
      fmt::format("aimed at ({:.0f}, {:.0f}, {:.0f}) mm", toMm(p.x()), toMm(p.y()), toMm(p.z()));
  for (const Eigen::Isometry3d& X : keys) {
    pass.t.push_back(
        pass.t.empty() ? 0.0
                       : pass.t.back() + (X.translation() - pass.X_RS.back().translation()).norm() /
                                             scanSpeed(settings));
    pass.X_RS.push_back(X);
  }
  if (pass.X_RS.size() < 2) pass = {};
  return pass;
}

ScanPass aimedSpin(const PartOnTable& scene,
                   const PassSettings& settings,
                   const Eigen::Isometry3d& witness,
                   double min_arc,
                   double max_arc) {
  const HousingCheck housing(scene, settings.housing, settings.housing_spacing);
  const int half =
      static_cast<int>(std::floor(std::min(180.0, 0.5 * toDeg(max_arc)) / kSpinStation + 1e-9));
  const int full = static_cast<int>(std::lround(180.0 / kSpinStation));
  const auto turned = [&](int j) {
    return Eigen::Isometry3d(Eigen::AngleAxisd(deg(kSpinStation * j), Eigen::Vector3d::UnitZ())) *
           witness;
  };
  if (!(settings.max_spin_rate > 0.0) || !housing.fits(witness)) return {};
  // The run of fitting stations either side of the witness; a whole turn when they all fit.
  int lo = 0, hi = 0;
  while (hi < half && housing.fits(turned(hi + 1))) ++hi;
  while (lo > std::max(hi - 2 * full + 1, -half) && housing.fits(turned(lo - 1))) --lo;
  if (hi - lo == 2 * full - 1) hi = lo + 2 * full;  // all 180 stations: close the turn
  if (deg(kSpinStation * (hi - lo)) < min_arc) return {};
  const Eigen::Vector3d p = witness.translation() + zMid(settings.window) * witness.linear().col(2);
  const double rho = std::max(p.head<2>().norm(), 1e-3);
  const double omega = std::min(scanSpeed(settings) / rho, settings.max_spin_rate);
  ScanPass pass;
  pass.kind = PassKind::kSpin;
  pass.label = fmt::format("aimed spin at ({:.0f}, {:.0f}, {:.0f}) mm, {:.0f} deg", toMm(p.x()),
                           toMm(p.y()), toMm(p.z()), kSpinStation * (hi - lo));
  for (int j = lo; j <= hi; ++j) {
    pass.azimuth.push_back(deg(kSpinStation * j));
    pass.t.push_back((pass.azimuth.back() - pass.azimuth.front()) / omega);
    pass.X_RS.push_back(turned(j));
  }
  return pass;
}

// ---- evaluation ---------------------------------------------------------------------------

struct SampleIndex::Tree {
  struct Points {
    const AreaSampling& s;
    std::size_t kdtree_get_point_count() const { return s.samples.size(); }
    double kdtree_get_pt(std::size_t i, std::size_t d) const {
      return s.samples[i].p[static_cast<Eigen::Index>(d)];
    }
    template <class Box>
    bool kdtree_get_bbox(Box&) const {
      return false;
    }
  };
  using Index = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Points>,
                                                    Points,
                                                    3,
                                                    std::uint32_t>;
  explicit Tree(const AreaSampling& s) : points{s}, index(3, points) { index.buildIndex(); }
  Points points;
  Index index;
};

SampleIndex::SampleIndex(const AreaSampling& sampling)
    : sampling_(sampling), tree_(std::make_unique<Tree>(sampling)) {}
SampleIndex::~SampleIndex() = default;

void SampleIndex::near(const Eigen::Vector3d& p,
                       const Eigen::Vector3d& n,
                       double radius,
                       std::vector<std::uint32_t>& out) const {
  std::vector<std::pair<std::uint32_t, double>> found;
  tree_->index.radiusSearch(p.data(), radius * radius, found,
                            nanoflann::SearchParams(32, 0.f, false));
  for (const auto& [i, d2] : found) {
    if (sampling_.samples[i].n.dot(n) >= 0.5) out.push_back(i);
  }
}

void SampleIndex::within(const Eigen::Vector3d& p,
                         double radius,
                         std::vector<std::uint32_t>& out) const {
  std::vector<std::pair<std::uint32_t, double>> found;
  tree_->index.radiusSearch(p.data(), radius * radius, found,
                            nanoflann::SearchParams(32, 0.f, false));
  for (const auto& [i, d2] : found) out.push_back(i);
}

std::uint32_t SampleIndex::nearest(const Eigen::Vector3d& p) const {
  std::uint32_t index = 0;
  double d2 = 0.0;
  tree_->index.knnSearch(p.data(), 1, &index, &d2);
  return index;
}

namespace {

// Where time t falls on a pass (keys interpolated linearly in time, as it runs): the stretch
// (from key k to key k + 1) and the share of it run; clamped to the pass. The search starts at
// stretch `from` (times only grow).
struct PassTime {
  std::size_t stretch = 0;
  double s = 0.0;
};

PassTime passTime(const ScanPass& pass, double t, std::size_t from = 0) {
  std::size_t k = from;
  while (k + 2 < pass.t.size() && pass.t[k + 1] < t) ++k;
  const double span = pass.t[k + 1] - pass.t[k];
  return {k, span > 0.0 ? std::clamp((t - pass.t[k]) / span, 0.0, 1.0) : 0.0};
}

constexpr std::uint32_t kNoStretch = std::numeric_limits<std::uint32_t>::max();

// The pass's covers from per-sample first and last covering stretches (kNoStretch: not covered).
void setCovers(ScanPass& pass,
               const std::vector<std::uint32_t>& first,
               const std::vector<std::uint32_t>& last) {
  pass.covers.clear();
  pass.cover_first.clear();
  pass.cover_last.clear();
  for (std::size_t i = 0; i < first.size(); ++i) {
    if (first[i] == kNoStretch) continue;
    pass.covers.push_back(static_cast<std::uint32_t>(i));
    pass.cover_first.push_back(first[i]);
    pass.cover_last.push_back(last[i]);
  }
}

// The measured points of one profile at head pose X (R frame), each with its winding normal. A
// camera must see a point within max_incidence of its normal, or, with `camera_incidence` false,
// merely from the front (as the scanner simulation has it).
void profilePoints(const PartOnTable& scene,
                   const PassSettings& settings,
                   const std::vector<double>& fan,
                   const Eigen::Isometry3d& X,
                   std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& out,
                   bool camera_incidence = true) {
  const double cos_max = std::cos(settings.max_incidence);
  const double cos_camera = camera_incidence ? cos_max : std::numeric_limits<double>::min();
  const auto& part = scene.part();
  for (const double alpha : fan) {
    const Eigen::Vector3d d_S(0.0, std::sin(alpha), std::cos(alpha));
    const Eigen::Vector3d d = X.linear() * d_S;
    const auto hit = scene.cast(X.translation(), d, 0.0, settings.window.z_max / std::cos(alpha));
    if (!hit || !scene.onPart(*hit)) continue;
    if (!settings.window.contains(hit->distance * d_S.y(), hit->distance * d_S.z())) continue;
    const Eigen::Vector3i& f = part.triangles[hit->triangle];
    const Eigen::Vector3d& a = part.vertices[static_cast<std::size_t>(f[0])];
    const Eigen::Vector3d n = (part.vertices[static_cast<std::size_t>(f[1])] - a)
                                  .cross(part.vertices[static_cast<std::size_t>(f[2])] - a)
                                  .normalized();
    if (-n.dot(d) < cos_max) continue;
    const Eigen::Vector3d p = X.translation() + hit->distance * d;
    for (const Eigen::Vector3d& c_S : settings.cameras) {
      const Eigen::Vector3d c = X * c_S;
      if (n.dot((c - p).normalized()) >= cos_camera && scene.clear(p + 1e-5 * n, c)) {
        out.push_back({p, n});
        break;
      }
    }
  }
}

// The time `amount` takes at `limit` per second; a limit ≤ 0 is none.
double limitTime(double amount, double limit) { return limit > 0.0 ? amount / limit : 0.0; }

// The speed caps of the 1-D profile at the keys (a key takes the lower of its two stretches';
// the ends their one stretch's), then the classic time-optimal pass: forward, each key no
// faster than the one before accelerating over the stretch between them (v² grows by 2·a·L at
// most), then the same backward. Stretches of no length (a turn in place) tie no keys together.
std::vector<double> speedProfile(const std::vector<double>& length,
                                 const std::vector<double>& cap,
                                 double accel) {
  const std::size_t n = length.size() + 1;
  std::vector<double> v(n, std::numeric_limits<double>::infinity());
  for (std::size_t k = 0; k + 1 < n; ++k) {
    if (!(length[k] > 0.0)) continue;
    v[k] = std::min(v[k], cap[k]);
    v[k + 1] = std::min(v[k + 1], cap[k]);
  }
  if (!(accel > 0.0) || !std::isfinite(accel)) return v;
  for (std::size_t k = 0; k + 1 < n; ++k)
    if (length[k] > 0.0)
      v[k + 1] = std::min(v[k + 1], std::sqrt(v[k] * v[k] + 2.0 * accel * length[k]));
  for (std::size_t k = n - 1; k > 0; --k)
    if (length[k - 1] > 0.0)
      v[k - 1] = std::min(v[k - 1], std::sqrt(v[k] * v[k] + 2.0 * accel * length[k - 1]));
  return v;
}

}  // namespace

void timePass(ScanPass& pass,
              const PassSettings& settings,
              const std::vector<double>& line_travel) {
  constexpr double kMinStep = 1e-6;  // s between keys at least: times stay increasing
  const std::size_t n = pass.X_RS.size();
  if (n < 2) {
    pass.t.assign(n, 0.0);
    return;
  }
  const bool spin = pass.kind == PassKind::kSpin && pass.azimuth.size() == n;
  // The head as the arm moves it: in R for strips (the table stands still), in the world for
  // spins, where the table turns the azimuth away (only the standoff changes are left).
  const auto head = [&](std::size_t k) {
    if (!spin) return pass.X_RS[k];
    return Eigen::Isometry3d(Eigen::AngleAxisd(-pass.azimuth[k], Eigen::Vector3d::UnitZ())) *
           pass.X_RS[k];
  };
  // Profile lines at most point_spacing apart: one spacing per frame at the line's speed.
  const double line_speed = settings.speed_safety * settings.point_spacing * settings.frame_rate;
  std::vector<double> length(n - 1), least(n - 1), cap(n - 1);
  Eigen::Isometry3d from = head(0);
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const Eigen::Isometry3d to = head(k + 1);
    const double move = (to.translation() - from.translation()).norm();
    const double turn = kinematics::rotationDistance(from.linear(), to.linear());
    double dt = std::max({k < line_travel.size() ? limitTime(line_travel[k], line_speed) : 0.0,
                          limitTime(move, settings.max_head_speed),
                          limitTime(turn, settings.max_head_turn), kMinStep});
    if (spin) {
      length[k] = std::abs(pass.azimuth[k + 1] - pass.azimuth[k]);
      dt = std::max(dt, limitTime(length[k], settings.max_spin_rate));
    } else {
      length[k] = (pass.X_RS[k + 1].translation() - pass.X_RS[k].translation()).norm();
    }
    least[k] = dt;
    cap[k] = length[k] / dt;
    from = to;
  }
  const std::vector<double> v =
      speedProfile(length, cap, spin ? settings.max_spin_accel : settings.max_head_accel);
  pass.t.assign(n, 0.0);
  for (std::size_t k = 0; k + 1 < n; ++k) {
    // Constant acceleration between the keys' speeds: the stretch at their mean speed.
    double dt = least[k];
    if (length[k] > 0.0) dt = std::max(dt, 2.0 * length[k] / (v[k] + v[k + 1]));
    pass.t[k + 1] = pass.t[k] + dt;
  }
}

void evaluatePass(ScanPass& pass,
                  const PartOnTable& scene,
                  const PassSettings& settings,
                  const SampleIndex& index) {
  const std::vector<double> fan = fanAngles(settings.window, settings.eval_rays);
  // Per sample, the first and last stretch whose profiles cover it (kNoStretch: none).
  std::vector<std::uint32_t> first(index.sampling().samples.size(), kNoStretch);
  std::vector<std::uint32_t> last(first.size(), 0);
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> points;
  std::vector<std::uint32_t> near;
  // line_travel[k]: how far the profile lines move over the surface from key k to key k + 1, the
  // most over the points measured on that stretch. The laser plane is x_S = 0; a point p with
  // normal n crosses it by Δx = |(X_b⁻¹p).x − (X_a⁻¹p).x| between the keys. On the surface (its
  // tangent plane T at p) the line is the level set x_S·q = const of q in T: the gradient of
  // x_S·q within T is x_S's projection on T, x_S − (x_S·n)n, of length √(1 − (x_S·n)²), so the
  // line moves along that projection by Δx / √(1 − (x_S·n)²). This holds for any motion of the
  // plane, strips (translation along x_S) and spins (turning about the table axis) alike. A
  // measured point is within max_incidence of its laser ray, which lies in the plane: the root
  // is at least cos(max_incidence).
  const bool timed = pass.kind != PassKind::kGiven;
  const std::size_t n_keys = pass.X_RS.size();
  std::vector<double> line_travel(n_keys > 0 ? n_keys - 1 : 0, 0.0);
  const double min_root = std::cos(settings.max_incidence);
  const auto crossing = [&](const Eigen::Isometry3d& a_inv, const Eigen::Isometry3d& b_inv,
                            const Eigen::Vector3d& p, double root) {
    return std::abs((b_inv * p).x() - (a_inv * p).x()) / root;
  };
  Eigen::Isometry3d before_inv = Eigen::Isometry3d::Identity();  // key k − 1, inverted
  for (std::size_t k = 0; k + 1 < n_keys; ++k) {
    const Eigen::Isometry3d &a = pass.X_RS[k], &b = pass.X_RS[k + 1];
    const Eigen::Isometry3d a_inv = a.inverse(), b_inv = b.inverse();
    const double travel = (b.translation() - a.translation()).norm();
    const int steps = std::max(1, static_cast<int>(std::ceil(travel / settings.eval_step)));
    for (int s = 0; s < steps + (k + 2 == n_keys ? 1 : 0); ++s) {
      points.clear();
      const Eigen::Isometry3d X = kinematics::interpolatePose(a, b, double(s) / steps);
      profilePoints(scene, settings, fan, X, points);
      for (const auto& [p, n] : points) {
        near.clear();
        index.near(p, n, settings.eval_radius, near);
        const auto stretch = static_cast<std::uint32_t>(k);
        for (std::uint32_t i : near) {
          first[i] = std::min(first[i], stretch);
          last[i] = std::max(last[i], stretch);
        }
        if (!timed) continue;
        const double x_n = X.linear().col(0).dot(n);
        const double root = std::max(std::sqrt(std::max(0.0, 1.0 - x_n * x_n)), min_root);
        line_travel[k] = std::max(line_travel[k], crossing(a_inv, b_inv, p, root));
        // A profile at a key also ends the stretch before it.
        if (s == 0 && k > 0)
          line_travel[k - 1] = std::max(line_travel[k - 1], crossing(before_inv, a_inv, p, root));
      }
    }
    before_inv = a_inv;
  }
  setCovers(pass, first, last);
  if (timed) timePass(pass, settings, line_travel);
}

void measurePass(ScanPass& pass,
                 const PartOnTable& scene,
                 const PassSettings& settings,
                 const SampleIndex& index,
                 int rays,
                 double radius) {
  std::vector<std::uint32_t> first(index.sampling().samples.size(), kNoStretch);
  std::vector<std::uint32_t> last(first.size(), 0);
  setCovers(pass, {}, {});
  if (pass.X_RS.size() < 2 || pass.t.size() != pass.X_RS.size() || !(settings.frame_rate > 0.0))
    return;
  const std::vector<double> fan = fanAngles(settings.window, rays);
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> points;
  std::vector<std::uint32_t> near;
  const double t0 = pass.t.front();
  const auto profiles =
      static_cast<std::size_t>(std::floor((pass.t.back() - t0) * settings.frame_rate + 1e-9)) + 1;
  PassTime at;
  for (std::size_t j = 0; j < profiles; ++j) {
    at = passTime(pass, t0 + static_cast<double>(j) / settings.frame_rate, at.stretch);
    const auto stretch = static_cast<std::uint32_t>(at.stretch);
    points.clear();
    profilePoints(
        scene, settings, fan,
        kinematics::interpolatePose(pass.X_RS[at.stretch], pass.X_RS[at.stretch + 1], at.s), points,
        false);
    for (const auto& point : points) {
      near.clear();
      index.within(point.first, radius, near);
      for (std::uint32_t i : near) {
        first[i] = std::min(first[i], stretch);
        last[i] = std::max(last[i], stretch);
      }
    }
  }
  setCovers(pass, first, last);
}

void evaluatePasses(std::vector<ScanPass>& passes,
                    const PartOnTable& scene,
                    const PassSettings& settings,
                    const SampleIndex& index,
                    const std::function<void(std::size_t, std::size_t)>& progress) {
  std::atomic<std::size_t> done{0};
  tbb::parallel_for(std::size_t{0}, passes.size(), [&](std::size_t i) {
    evaluatePass(passes[i], scene, settings, index);
    const std::size_t n = done.fetch_add(1) + 1;
    if (progress) progress(n, passes.size());
  });
}

ScanPass rotatedPass(const ScanPass& pass, double angle) {
  ScanPass out = pass;
  const Eigen::Isometry3d R(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()));
  for (Eigen::Isometry3d& X : out.X_RS) X = R * X;
  for (double& a : out.azimuth) a += angle;
  return out;
}

ScanPass trimmedPass(const ScanPass& pass, std::size_t first, std::size_t last, double pad) {
  ScanPass out;
  out.kind = pass.kind;
  out.label = pass.label;
  const bool spin = pass.azimuth.size() == pass.X_RS.size();
  // The pass at time t (keys interpolated linearly in time, as it runs) into out's keys.
  const auto add = [&](double t) {
    const PassTime at = passTime(pass, t);
    const std::size_t k = at.stretch;
    out.X_RS.push_back(kinematics::interpolatePose(pass.X_RS[k], pass.X_RS[k + 1], at.s));
    if (spin)
      out.azimuth.push_back(pass.azimuth[k] + at.s * (pass.azimuth[k + 1] - pass.azimuth[k]));
    out.t.push_back(t);
  };
  const double from = std::max(pass.t.front(), pass.t[first] - std::max(pad, 0.0));
  const double to = std::min(pass.t.back(), pass.t[last + 1] + std::max(pad, 0.0));
  if (from < pass.t[first]) add(from);
  for (std::size_t k = first; k <= last + 1; ++k) {
    out.X_RS.push_back(pass.X_RS[k]);
    if (spin) out.azimuth.push_back(pass.azimuth[k]);
    out.t.push_back(pass.t[k]);
  }
  if (to > pass.t[last + 1]) add(to);
  for (double& t : out.t) t -= from;
  // A sample stays when a stretch known to cover it (its first or its last) is kept; stretches
  // are renumbered from the first key kept (one more with the padding before it).
  const std::size_t shift = first - (from < pass.t[first] ? 1u : 0u);
  const auto kept = [&](std::size_t k) { return first <= k && k <= last; };
  for (std::size_t j = 0; j < pass.covers.size() && j < pass.cover_first.size(); ++j) {
    const std::size_t f = pass.cover_first[j], l = pass.cover_last[j];
    if (!kept(f) && !kept(l)) continue;
    out.covers.push_back(pass.covers[j]);
    out.cover_first.push_back(static_cast<std::uint32_t>((kept(f) ? f : l) - shift));
    out.cover_last.push_back(static_cast<std::uint32_t>((kept(l) ? l : f) - shift));
  }
  return out;
}

}  // namespace scanplan::scanner
