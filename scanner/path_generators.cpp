#include <scanplan/scanner/path_generators.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <fmt/format.h>

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/units.h>

namespace scanplan::scanner {
namespace {

using kinematics::ScanSample;

// A time-stamped pose; `scanning` says whether the motion arriving at this key acquires.
struct Key {
  double t;
  Eigen::Isometry3d X;
  bool scanning;
};

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kMaxStations = 2e6;  // probed raster stations of one element

std::string where(std::size_t index) { return "scan.paths[" + std::to_string(index) + "]"; }

// Appends a straight move to `to` at `speed` (m/s), orientation limited to `rot_speed` (rad/s).
void moveTo(std::vector<Key>& keys,
            const Eigen::Isometry3d& to,
            double speed,
            double rot_speed,
            bool scanning) {
  const Key& from = keys.back();
  const double dt =
      std::max({(to.translation() - from.X.translation()).norm() / speed,
                kinematics::rotationDistance(from.X.linear(), to.linear()) / rot_speed, 1e-6});
  keys.push_back({from.t + dt, to, scanning});
}

std::vector<Key> ringKeys(const RingSpec& ring,
                          const kinematics::TriangleMesh& part,
                          const Raycaster& raycaster,
                          const LaserWindow& window,
                          std::size_t index,
                          ElementReport& report) {
  const Eigen::AlignedBox3d box = part.bounds();
  const Eigen::Vector2d axis = ring.axis_xy.value_or(box.center().head<2>());
  const Eigen::Vector3d aim(axis.x(), axis.y(), ring.height);
  const double sign = ring.extent >= 0.0 ? 1.0 : -1.0;
  const auto view = [&](double phi) -> Eigen::Vector3d {
    const Eigen::Vector3d radial(std::cos(phi), std::sin(phi), 0.0);
    return Eigen::Vector3d(-std::cos(ring.tilt) * radial -
                           std::sin(ring.tilt) * Eigen::Vector3d::UnitZ());
  };
  const auto tangent = [&](double phi) -> Eigen::Vector3d {
    return Eigen::Vector3d(-std::sin(phi), std::cos(phi), 0.0) * sign;
  };

  // Depth of the surface along the view, probed from far outside: the central ray and two rays
  // across the laser line, every 2° of the ring.
  const double far = 0.5 * box.diagonal().norm() + window.z_max + 0.1;
  const double z_mid = 0.5 * (window.z_min + window.z_max);
  const double half_line = 0.8 * window.halfWidth(z_mid);
  const int probes = std::max(2, static_cast<int>(std::ceil(std::abs(ring.extent) / deg(2.0))) + 1);
  std::vector<double> depths;
  for (int i = 0; i < probes; ++i) {
    const double phi = ring.start + ring.extent * i / (probes - 1);
    const Eigen::Vector3d z = view(phi);
    const Eigen::Vector3d y = z.cross(tangent(phi));
    for (double o : {-half_line, 0.0, half_line}) {
      if (const auto hit = raycaster.cast(aim - far * z + o * y, z))
        depths.push_back(hit->distance);
    }
  }
  if (depths.empty()) {
    throw InputError(where(index) + ": ring at height " + std::to_string(toMm(ring.height)) +
                     " mm, tilt " + std::to_string(toDeg(ring.tilt)) +
                     " deg never sees the part: expected a height and tilt whose view meets it "
                     "(part z spans " +
                     std::to_string(toMm(box.min().z())) + " … " +
                     std::to_string(toMm(box.max().z())) + " mm)");
  }
  // Place the window over the most probes (a sliding window over the sorted depths), centred
  // on them: rays that fall into a bore or past an edge must not drag the whole ring off.
  std::sort(depths.begin(), depths.end());
  const double depth_span = window.z_max - window.z_min;
  std::size_t best_lo = 0, best_hi = 0;
  for (std::size_t lo = 0, hi = 0; lo < depths.size(); ++lo) {
    while (hi + 1 < depths.size() && depths[hi + 1] - depths[lo] <= depth_span) ++hi;
    if (hi - lo > best_hi - best_lo) {
      best_lo = lo;
      best_hi = hi;
    }
  }
  // Laser origin at distance L from the aim point.
  const double L = ring.distance.value_or(far - 0.5 * (depths[best_lo] + depths[best_hi]) + z_mid);
  report.depth_min = depths.front() - (far - L);
  report.depth_max = depths.back() - (far - L);
  const auto in_window = std::count_if(depths.begin(), depths.end(), [&](double d) {
    const double z = d - (far - L);
    return z >= window.z_min && z <= window.z_max;
  });
  report.coverage_in_window = static_cast<double>(in_window) / static_cast<double>(depths.size());
  if (report.depth_max - report.depth_min > window.z_max - window.z_min) {
    report.note =
        "the surface depth varies by more than the depth window; parts of the ring are out of "
        "range";
  }

  std::vector<Key> keys;
  const int steps = std::max(2, static_cast<int>(std::ceil(std::abs(ring.extent) / deg(1.0))) + 1);
  for (int i = 0; i < steps; ++i) {
    const double phi = ring.start + ring.extent * i / (steps - 1);
    const Eigen::Vector3d z = view(phi);
    keys.push_back({std::abs(phi - ring.start) / ring.speed,
                    kinematics::frameFromAxes(aim - L * z, z, tangent(phi)), true});
  }
  return keys;
}

// A raster's axes (u along the passes, w across them, v the view) and the part's extent on them.
struct RasterAxes {
  Eigen::Vector3d u, v, w;
  double u_min = 1e9, u_max = -1e9, w_min = 1e9, w_max = -1e9, v_min = 1e9;
};

RasterAxes rasterAxes(const RasterSpec& raster,
                      const kinematics::TriangleMesh& part,
                      std::size_t index) {
  RasterAxes a;
  const Eigen::Vector3d v = raster.view.normalized();
  Eigen::Vector3d u = raster.pass_direction - raster.pass_direction.dot(v) * v;
  if (u.norm() < 1e-6) {
    throw InputError(
        where(index) +
        ": raster pass_direction is parallel to the view: expected a direction across the view");
  }
  u.normalize();
  const Eigen::Vector3d w = v.cross(u);
  for (const Eigen::Vector3d& p : part.vertices) {
    a.u_min = std::min(a.u_min, p.dot(u));
    a.u_max = std::max(a.u_max, p.dot(u));
    a.w_min = std::min(a.w_min, p.dot(w));
    a.w_max = std::max(a.w_max, p.dot(w));
    a.v_min = std::min(a.v_min, p.dot(v));
  }
  a.u = u;
  a.v = v;
  a.w = w;
  return a;
}

constexpr double kRasterStep = 0.002;  // m between probed stations along a pass

// One pass at wk across, probed at `samples` stations every kRasterStep along u from
// u_min − lead: the required scanner position along v at each (`pv`: the nearest surface under
// the line no closer than z_min, the seen depths centred in the window where that allows), and
// the nearest and farthest surface distance from the probe plane v0 (`seen`); NaN off the part.
struct PassProbe {
  std::vector<double> pv;
  std::vector<std::pair<double, double>> seen;
};

PassProbe probePass(const RasterAxes& a,
                    const RasterSpec& raster,
                    const Raycaster& raycaster,
                    const LaserWindow& window,
                    double v0,
                    double wk,
                    int samples) {
  const double z_mid = 0.5 * (window.z_min + window.z_max);
  const double half_line = 0.9 * window.y_near;
  const double step = kRasterStep;
  PassProbe out{
      std::vector<double>(static_cast<std::size_t>(samples), kNaN),
      std::vector<std::pair<double, double>>(static_cast<std::size_t>(samples), {kNaN, kNaN})};
  for (int i = 0; i < samples; ++i) {
    const double s = a.u_min - raster.lead + step * i;
    double near = 1e9, farthest = -1e9;
    for (double o : {-half_line, -0.5 * half_line, 0.0, 0.5 * half_line, half_line}) {
      if (const auto hit = raycaster.cast(s * a.u + (wk + o) * a.w + v0 * a.v, a.v)) {
        near = std::min(near, hit->distance);
        farthest = std::max(farthest, hit->distance);
      }
    }
    if (near > 1e8) continue;
    out.seen[static_cast<std::size_t>(i)] = {near, farthest};
    out.pv[static_cast<std::size_t>(i)] =
        std::min(v0 + 0.5 * (near + farthest) - z_mid, v0 + near - window.z_min);
  }
  return out;
}

// Smooth: the most conservative (farthest back) position within ±15 mm, so the surface never
// comes closer than z_min between stations; stations off the part take the pass's.
std::vector<double> smoothPass(const std::vector<double>& pv, int samples) {
  const double step = kRasterStep;
  const double fallback = *std::min_element(pv.begin(), pv.end(), [](double a, double b) {
    return std::isnan(b) || (!std::isnan(a) && a < b);
  });
  const int window_steps = static_cast<int>(0.015 / step);
  std::vector<double> smooth(pv.size());
  for (int i = 0; i < samples; ++i) {
    double m = 1e9;
    for (int j = std::max(0, i - window_steps); j <= std::min(samples - 1, i + window_steps); ++j) {
      const double x = pv[static_cast<std::size_t>(j)];
      m = std::min(m, std::isnan(x) ? fallback : x);
    }
    smooth[static_cast<std::size_t>(i)] = m;
  }
  return smooth;
}

// What the passes saw: the depth range in the window and how many stations fit it.
struct RasterDepths {
  std::size_t probed = 0, in_window = 0;
  double depth_min = 1e9, depth_max = -1e9;
};

// The keys of pass k (forward on even k), a transfer from the previous pass first.
void addPassKeys(const RasterAxes& a,
                 const RasterSpec& raster,
                 const LaserWindow& window,
                 double v0,
                 int k,
                 double wk,
                 int samples,
                 const std::vector<double>& smooth,
                 const PassProbe& probe,
                 std::vector<Key>& keys,
                 RasterDepths& depths) {
  const Eigen::Vector3d &u = a.u, &v = a.v, &w = a.w;
  const double step = kRasterStep;
  const bool forward = k % 2 == 0;
  const Eigen::Vector3d motion = forward ? u : Eigen::Vector3d(-u);
  double s_prev = 0.0;
  for (int n = 0; n < samples; n += 5) {  // keys every 10 mm; positions every 2 mm were probed
    const int i = forward ? n : samples - 1 - n;
    const double s = a.u_min - raster.lead + step * i;
    const double p = smooth[static_cast<std::size_t>(i)];
    const Eigen::Isometry3d X = kinematics::frameFromAxes(s * u + wk * w + p * v, v, motion);
    // The move from the previous key acquires when it overlaps the part's extent at all.
    const bool on_part = std::max(s, s_prev) >= a.u_min && std::min(s, s_prev) <= a.u_max;
    s_prev = s;
    if (keys.empty()) {
      keys.push_back({0.0, X, false});
    } else if (n == 0) {
      // Transfer from the previous pass: back off to the farther of the two heights first.
      const Eigen::Isometry3d& last = keys.back().X;
      const double back = std::min(last.translation().dot(v), p);
      Eigen::Isometry3d up = last, over = X;
      up.translation() += (back - last.translation().dot(v)) * v;
      over.translation() += (back - p) * v;
      moveTo(keys, up, raster.speed * 3.0, 0.5, false);
      moveTo(keys, over, raster.speed * 3.0, 0.5, false);
      moveTo(keys, X, raster.speed * 3.0, 0.5, false);
    } else {
      moveTo(keys, X, raster.speed, 0.5, on_part);
    }
    const auto& [near, farthest] = probe.seen[static_cast<std::size_t>(i)];
    if (!std::isnan(near)) {
      const double z_near = near - (p - v0), z_far = farthest - (p - v0);
      ++depths.probed;
      depths.in_window += (z_near >= window.z_min - 1e-9 && z_far <= window.z_max + 1e-9) ? 1 : 0;
      depths.depth_min = std::min(depths.depth_min, z_near);
      depths.depth_max = std::max(depths.depth_max, z_far);
    }
  }
}

std::vector<Key> rasterKeys(const RasterSpec& raster,
                            const kinematics::TriangleMesh& part,
                            const Raycaster& raycaster,
                            const LaserWindow& window,
                            std::size_t index,
                            ElementReport& report) {
  const RasterAxes a = rasterAxes(raster, part, index);
  const double spacing = 2.0 * window.y_near * (1.0 - raster.overlap);
  const double v0 = a.v_min - 0.1;  // probe plane, before the part along the view
  const double pass_count = std::ceil((a.w_max - a.w_min) / spacing);
  const double station_count = std::ceil((a.u_max - a.u_min + 2.0 * raster.lead) / kRasterStep) + 1;
  if (!(pass_count * station_count <= kMaxStations)) {
    throw InputError(fmt::format(
        "{}: the raster would probe {:.3g} stations ({:.0f} passes of {:.0f}): expected at most "
        "{:.0f} (check lead_mm and the part's units and scale: it spans {:.0f} x {:.0f} mm "
        "here)",
        where(index), pass_count * station_count, pass_count, station_count, kMaxStations,
        toMm(a.u_max - a.u_min), toMm(a.w_max - a.w_min)));
  }
  const int passes = std::max(1, static_cast<int>(pass_count));
  const int samples = static_cast<int>(station_count);

  std::vector<Key> keys;
  RasterDepths depths;
  for (int k = 0; k < passes; ++k) {
    const double wk = a.w_min + (a.w_max - a.w_min) * (k + 0.5) / passes;
    const PassProbe probe = probePass(a, raster, raycaster, window, v0, wk, samples);
    if (std::all_of(probe.pv.begin(), probe.pv.end(), [](double x) { return std::isnan(x); })) {
      continue;
    }
    const std::vector<double> smooth = smoothPass(probe.pv, samples);
    addPassKeys(a, raster, window, v0, k, wk, samples, smooth, probe, keys, depths);
  }
  if (keys.size() < 2) {
    throw InputError(where(index) +
                     ": raster finds no part surface under the passes: expected a view direction "
                     "that meets the part");
  }
  report.depth_min = depths.depth_min;
  report.depth_max = depths.depth_max;
  report.coverage_in_window =
      depths.probed ? static_cast<double>(depths.in_window) / static_cast<double>(depths.probed)
                    : 0.0;
  report.note =
      fmt::format("{} passes, {:.1f} mm apart", passes, toMm((a.w_max - a.w_min) / passes));
  return keys;
}

std::vector<Key> waypointKeys(const WaypointSpec& spec, std::size_t index) {
  if (spec.points.size() < 2) {
    throw InputError(where(index) + ".points: " + std::to_string(spec.points.size()) +
                     " point(s): expected at least 2");
  }
  std::vector<Key> keys{{0.0, spec.points.front().X_PS, spec.points.front().scanning}};
  for (std::size_t i = 1; i < spec.points.size(); ++i) {
    const Waypoint& p = spec.points[i];
    moveTo(keys, p.X_PS, p.speed, p.rotation_speed, p.scanning);
  }
  return keys;
}

std::vector<Key> fileKeys(const FileSpec& spec, std::size_t index) {
  if (spec.samples.size() < 2) {
    throw InputError(where(index) + ": the path file has " + std::to_string(spec.samples.size()) +
                     " row(s): expected at least 2");
  }
  std::vector<Key> keys;
  for (const ScanSample& s : spec.samples)
    keys.push_back({s.t - spec.samples.front().t, s.X_PS, s.scanning});
  return keys;
}

}  // namespace

GeneratedPath generatePath(const PathRequest& request,
                           const kinematics::TriangleMesh& part,
                           const Raycaster& raycaster,
                           const LaserWindow& window) {
  GeneratedPath out;
  std::vector<Key> all;
  for (std::size_t i = 0; i < request.elements.size(); ++i) {
    ElementReport report;
    std::vector<Key> keys;
    const PathElement& element = request.elements[i];
    if (const auto* ring = std::get_if<RingSpec>(&element)) {
      report.kind = "ring";
      keys = ringKeys(*ring, part, raycaster, window, i, report);
    } else if (const auto* raster = std::get_if<RasterSpec>(&element)) {
      report.kind = "raster";
      keys = rasterKeys(*raster, part, raycaster, window, i, report);
    } else if (const auto* points = std::get_if<WaypointSpec>(&element)) {
      report.kind = "waypoints";
      keys = waypointKeys(*points, i);
    } else {
      report.kind = "file";
      keys = fileKeys(std::get<FileSpec>(element), i);
    }
    if (!all.empty()) {
      // Transfer: back off along −z_S, cross over, approach.
      const Eigen::Isometry3d& from = all.back().X;
      const Eigen::Isometry3d& to = keys.front().X;
      Eigen::Isometry3d from_back = from, to_back = to;
      from_back.translation() -= request.retreat * from.linear().col(2);
      to_back.translation() -= request.retreat * to.linear().col(2);
      moveTo(all, from_back, request.transfer_speed, 0.5, false);
      moveTo(all, to_back, request.transfer_speed, 0.5, false);
      moveTo(all, to, request.transfer_speed, 0.5, false);
    }
    const double offset = all.empty() ? 0.0 : all.back().t;
    report.start_time = offset;
    report.duration = keys.back().t - keys.front().t;
    for (std::size_t k = all.empty() ? 0 : 1; k < keys.size(); ++k) {
      all.push_back({offset + keys[k].t - keys.front().t, keys[k].X, keys[k].scanning});
    }
    out.elements.push_back(report);
  }
  if (all.empty()) throw InputError("scan.paths: empty: expected at least one path element");

  // Sample every dt by interpolation between keys; a path too long to sample is refused first
  // (a ring at 1e-6 °/s or a part a thousand times too large would fill the memory).
  out.path.dt = request.dt;
  const double total = all.back().t;
  if (!(total / request.dt <= static_cast<double>(kMaxPathSamples))) {
    throw InputError(fmt::format(
        "scan.paths: the path takes {:.0f} s, {:.0f} samples every {} s: expected at most {} "
        "samples (check the speeds, scan.dt_s and the part's units and scale)",
        total, total / request.dt, request.dt, kMaxPathSamples));
  }
  const auto n = static_cast<std::size_t>(std::floor(total / request.dt + 1e-9)) + 1;
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * request.dt;
    while (k + 2 < all.size() && all[k + 1].t < t) ++k;
    const Key& a = all[k];
    const Key& b = all[std::min(k + 1, all.size() - 1)];
    const double s = b.t > a.t ? std::clamp((t - a.t) / (b.t - a.t), 0.0, 1.0) : 0.0;
    out.path.samples.push_back(
        {t, kinematics::interpolatePose(a.X, b.X, s), i == 0 ? a.scanning : b.scanning});
  }
  return out;
}

FileSpec parsePathCsv(const std::string& text, const std::string& source) {
  FileSpec spec;
  std::istringstream in(text);
  std::string line;
  int number = 0;
  double last_t = -std::numeric_limits<double>::infinity();
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    if (line.rfind("t_s", 0) == 0) continue;  // header
    std::vector<double> v;
    std::stringstream row(line);
    std::string cell;
    while (std::getline(row, cell, ',')) {
      char* end = nullptr;
      const double x = std::strtod(cell.c_str(), &end);
      while (end && *end == ' ') ++end;
      if (cell.empty() || end == cell.c_str() || (end && *end != '\0') || !std::isfinite(x)) {
        throw InputError(
            source + ":" + std::to_string(number) + ": '" + cell +
            "' is not a finite number: expected t_s, x_mm, y_mm, z_mm, qw, qx, qy, qz[, scanning]");
      }
      v.push_back(x);
    }
    if (v.size() != 8 && v.size() != 9) {
      throw InputError(
          source + ":" + std::to_string(number) + ": " + std::to_string(v.size()) +
          " columns: expected 8 or 9 (t_s, x_mm, y_mm, z_mm, qw, qx, qy, qz[, scanning])");
    }
    if (!(v[0] > last_t)) {
      throw InputError(source + ":" + std::to_string(number) + ": t_s " + std::to_string(v[0]) +
                       " does not increase: expected strictly increasing times");
    }
    last_t = v[0];
    Eigen::Quaterniond q(v[4], v[5], v[6], v[7]);
    if (std::abs(q.norm() - 1.0) > 1e-3) {
      throw InputError(source + ":" + std::to_string(number) + ": quaternion norm " +
                       std::to_string(q.norm()) + ": expected a unit quaternion (qw, qx, qy, qz)");
    }
    ScanSample s;
    s.t = v[0];
    s.X_PS.translation() = Eigen::Vector3d(v[1], v[2], v[3]) * kMmToM;
    s.X_PS.linear() = q.normalized().toRotationMatrix();
    s.scanning = v.size() == 9 ? v[8] != 0.0 : true;
    spec.samples.push_back(s);
  }
  return spec;
}

std::string pathToCsv(const kinematics::ScanPath& path) {
  std::ostringstream out;
  out.precision(10);
  out << "t_s,x_mm,y_mm,z_mm,qw,qx,qy,qz,scanning\n";
  for (const ScanSample& s : path.samples) {
    Eigen::Quaterniond q(s.X_PS.linear());
    if (q.w() < 0) q.coeffs() *= -1.0;
    const Eigen::Vector3d p = s.X_PS.translation() * kMToMm;
    out << s.t << ',' << p.x() << ',' << p.y() << ',' << p.z() << ',' << q.w() << ',' << q.x()
        << ',' << q.y() << ',' << q.z() << ',' << (s.scanning ? 1 : 0) << '\n';
  }
  return out.str();
}

}  // namespace scanplan::scanner
