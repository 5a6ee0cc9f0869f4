// The terminal summary of `path`, `map` and `plan`: one line per stage, aligned, in mm,
// degrees and seconds.
#include "cli/report/plan_summary.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include <scanplan/kinematics/ptp_move.h>
#include <scanplan/kinematics/units.h>

namespace scanplan::cli {

// The cell, as the first lines of the summary.
std::string cellSummary(const config::JobSpec& job,
                        const kinematics::CellModel& cell,
                        const kinematics::LoadedMesh& part) {
  std::string s = fmt::format("job        {} ({})\n", job.name, job.source.string());
  s += fmt::format("robot      {}\n", cell.robot.name());
  s += fmt::format("table      radius {} mm, axis at ({:.1f}, {:.1f}, {:.1f}) mm, {}\n",
                   job.table.radius_mm, toMm(cell.table.X_WA.translation().x()),
                   toMm(cell.table.X_WA.translation().y()), toMm(cell.table.X_WA.translation().z()),
                   job.table.continuous
                       ? "continuous"
                       : fmt::format("{} … {} deg", job.table.min_deg, job.table.max_deg));
  const Eigen::Vector3d size = part.mesh.bounds().sizes() * kMToMm;
  s += fmt::format("part       {}: {} triangles, {:.1f} x {:.1f} x {:.1f} mm, {}\n",
                   job.part.mesh.as_written, part.mesh.triangles.size(), size.x(), size.y(),
                   size.z(), part.mesh.isClosed() ? "closed" : "open (has holes)");
  return s;
}

std::string pathSummary(const scanner::LaserWindow& window,
                        const scanner::GeneratedPath& generated) {
  std::string s = fmt::format(
      "scanner    depth window {:.1f} … {:.1f} mm, line {:.1f} mm near, {:.1f} mm far (Eq. 5)\n",
      toMm(window.z_min), toMm(window.z_max), 2 * toMm(window.y_near), 2 * toMm(window.y_far));
  for (std::size_t i = 0; i < generated.elements.size(); ++i) {
    const auto& e = generated.elements[i];
    if (e.kind == "auto") {  // its own lines follow (autoScanSummary)
      s += fmt::format("path[{}]    {:<9} t = {:.1f} … {:.1f} s, {}\n", i, e.kind, e.start_time,
                       e.start_time + e.duration, e.note);
      continue;
    }
    s += fmt::format(
        "path[{}]    {:<9} t = {:.1f} … {:.1f} s, surface depth {:.1f} … {:.1f} mm, {:.0f}% of "
        "probes in the window{}\n",
        i, e.kind, e.start_time, e.start_time + e.duration, toMm(e.depth_min), toMm(e.depth_max),
        100.0 * e.coverage_in_window, e.note.empty() ? "" : "; " + e.note);
  }
  s += fmt::format("samples    {} every {} s ({:.1f} s)\n", generated.path.samples.size(),
                   generated.path.dt, generated.path.duration());
  return s;
}

std::string autoScanSummary(const pipeline::AutoScanReport& r) {
  std::size_t spins = 0;
  for (const auto& p : r.passes) spins += p.kind == "spin" ? 1u : 0u;
  std::string s = fmt::format(
      "auto       {} passes ({} spins, {} strips) of {} candidates in {:.1f} s: {:.1f}% of the "
      "scannable area planned ({} samples every {:.1f} mm); stopped: {}\n",
      r.passes.size(), spins, r.passes.size() - spins, r.candidates, r.seconds,
      100.0 * r.planned_fraction, r.counted, toMm(r.sample_spacing), r.stop);
  s += fmt::format(
      "           {:.1f} s scanning in the passes chosen, {:.1f} s cut from them ({} left out, {} "
      "split), {} more left out ({:.1f} s): {:.1f}% measured{}{}\n",
      r.scan_time, r.cut_time, r.cut_dropped, r.cut_split, r.pruned, r.pruned_time,
      100.0 * r.measured_fraction,
      r.rechosen == 0 ? std::string()
      : r.rechosen_kept
          ? fmt::format(" (the cover chosen again for a {}larger margin)",
                        r.rechosen > 1 ? "still " : "")
          : fmt::format(" ({} larger margins tried: none measures the target)", r.rechosen),
      r.unreachable.empty()
          ? std::string()
          : fmt::format("; {} candidates out of the arm's reach", r.unreachable.size()));
  if (!r.cover_status.empty()) {
    s += fmt::format(
        "           set cover: {:.1f} s of passes and moves by greedy, {:.1f} s by the integer "
        "programme ({}, {:.2f} s); proven bound {:.1f} s{}\n",
        r.greedy_cost, r.cover_cost, r.cover_status, r.cover_seconds, r.cover_bound,
        r.cover_bound > 0.0 && r.cover_cost > 0.0
            ? fmt::format(", gap {:.1f}%", 100.0 * (r.cover_cost - r.cover_bound) / r.cover_cost)
            : std::string());
  }
  std::array<std::size_t, 5> count{};
  for (const auto c : r.classes) ++count[static_cast<std::size_t>(c)];
  const double n = std::max<double>(1.0, static_cast<double>(r.classes.size()));
  s += fmt::format(
      "           before the scan: {:.1f}% scannable, {:.1f}% out of the arm's reach, {:.1f}% "
      "faces "
      "the table, {:.1f}% occluded, {:.1f}% no standoff fits the housing\n",
      100.0 * static_cast<double>(count[0]) / n, 100.0 * static_cast<double>(count[4]) / n,
      100.0 * static_cast<double>(count[1]) / n, 100.0 * static_cast<double>(count[2]) / n,
      100.0 * static_cast<double>(count[3]) / n);
  return s;
}

namespace {

// One mesh link: what stands in for it in the maps, and why.
std::string linkMeshLine(const std::string& name, const collision::MapHull& h) {
  std::string text = fmt::format("  {:<8} mesh {} triangles, hull of {} vertices {:.1f} mm out",
                                 name, h.mesh_triangles, h.hull_vertices, toMm(h.hull_margin));
  if (h.cylinder) {
    return text + fmt::format(
                      "; round about its joint's axis: a cylinder of {:.1f} mm radius, {:.1f} mm "
                      "long, at most {:.1f} mm out: the maps measure the cylinder\n",
                      toMm(h.cylinder_radius), toMm(h.cylinder_length), toMm(h.margin));
  }
  if (h.pieces > 0) {
    const std::string margin =
        h.used ? fmt::format(" at most {:.1f} mm out", toMm(h.margin)) : std::string();
    text += fmt::format("; {} convex pieces ({} vertices){}, {} in {:.1f} s", h.pieces,
                        h.piece_vertices, margin, h.from_cache ? "read from the cache" : "fitted",
                        h.fit_seconds);
  }
  if (h.used)
    return text + fmt::format(": the maps measure the {}\n", h.pieces > 0 ? "pieces" : "hull");
  if (h.pieces > 0) {
    return text +
           ": they do not fit the limits (constraints.clearance.piece_margin_mm, "
           "max_pieces), so the maps measure the mesh; raise those, or give the link "
           "primitive shapes\n";
  }
  return text + ": the maps measure the mesh\n";
}

}  // namespace

std::string linkMeshLines(const std::vector<std::string>& names,
                          const std::vector<collision::MapHull>& hulls) {
  std::string text;
  for (const collision::MapHull& h : hulls) {
    const auto i = static_cast<std::size_t>(h.body);
    text += linkMeshLine(i < names.size() ? names[i] : fmt::format("body {}", i), h);
  }
  if (text.empty()) return text;
  return "link mesh  convex stand-ins hold each mesh link in the maps, never farther than the "
         "mesh and at most the stated margin nearer (constraints.clearance.link_meshes); "
         "validation measures the meshes\n" +
         text;
}

std::string linkMeshSummary(const collision::Scene& scene) {
  std::vector<std::string> names;
  for (const collision::BodyInfo& b : scene.bodies()) names.push_back(b.name);
  std::string text = linkMeshLines(names, scene.mapHulls());
  if (!text.empty()) return text;
  std::size_t triangles = 0;
  for (const collision::BodyInfo& b : scene.bodies()) {
    if (b.motion == collision::BodyMotion::kRobotLink) triangles += b.triangles;
  }
  if (triangles == 0) return {};
  return fmt::format(
      "link mesh  the maps measure the link meshes exactly ({} triangles; link_meshes: exact)\n",
      triangles);
}

std::string mapSummary(const planner::ConfigMap& map, double seconds) {
  const std::size_t cells = map.cellsPerBranch();
  std::string text = fmt::format(
      "map        {} angles x {} samples x {} branch(es) = {} cells in {:.1f} s ({:.0f} cells/s)\n",
      map.angles.size(), map.times.size(), map.branches.size(), cells * map.branches.size(),
      seconds, static_cast<double>(cells) / seconds);
  for (std::size_t b = 0; b < map.branches.size(); ++b) {
    std::size_t feasible = 0;
    double sum = 0.0;
    for (std::size_t i = b * cells; i < (b + 1) * cells; ++i) {
      feasible += map.f[i] > 0.0f ? 1u : 0u;
      sum += map.f[i];
    }
    text +=
        fmt::format("  {:<21} feasible {:5.1f}% of cells, mean f {:.3f}\n", map.branches[b].words(),
                    100.0 * static_cast<double>(feasible) / static_cast<double>(cells),
                    sum / static_cast<double>(cells));
  }
  return text;
}

namespace {

// Which axes set the moves' time, the largest share first: the axes a faster robot or table
// would have to beat.
std::string movesByAxisSummary(const pipeline::ProgramTimes& p) {
  std::vector<std::pair<double, int>> order;
  for (int j = 0; j < kinematics::kNumAxes; ++j)
    if (p.moving_by_axis(j) >= 0.05) order.push_back({-p.moving_by_axis(j), j});
  std::sort(order.begin(), order.end());
  std::string s = "           the moves' time set by";
  for (const auto& [minus, j] : order)
    s += fmt::format(" {} {:.1f} s,", j == 0 ? std::string("the table") : fmt::format("j{}", j),
                     -minus);
  if (!order.empty()) s.pop_back();
  return s + " (its speed or acceleration limit)\n";
}

}  // namespace

// The program's time: scanning, the moves between passes, and passes left out.
std::string programSummary(const pipeline::ScanPlan& plan) {
  const pipeline::ProgramTimes& p = plan.program;
  std::string s = fmt::format("program    {:.1f} s: {:.1f} s scanning, {:.1f} s moving", p.total,
                              p.scanning, p.moving);
  if (p.moves > 0)
    s += fmt::format(" in {} point-to-point moves between passes ({} backed off)", p.moves,
                     p.detours);
  if (p.held > 0)
    s += fmt::format("; {} passes start where the table stands after the pass before (J {:+.3f} s)",
                     p.held, p.held_cost);
  s += "\n";
  if (p.moves > 0) s += movesByAxisSummary(p);
  for (const auto& [segment, why] : plan.dropped)
    s += fmt::format("  dropped pass {}: {}\n", segment + 1, why);
  return s;
}

std::string curveSummary(const pipeline::ScanPlan& plan) {
  const pipeline::CoverageCurve& c = plan.coverage_curve;
  if (c.t.empty()) return {};
  std::string s = "curve      ";
  for (const double share : {0.90, 0.95, 0.98}) {
    const auto t = c.timeTo(share);
    s += t ? fmt::format("{:.0f}% of the scannable area in {:.0f} s, ", 100.0 * share, *t)
           : fmt::format("{:.0f}% not reached, ", 100.0 * share);
  }
  return s + fmt::format("{:.1f}% at the end ({:.0f} s; coverage_time.png)\n",
                         100.0 * c.fraction.back(), plan.program.total);
}

// The plan's lines after the map: the path, the choice, refinement, the DP gap, comparisons and
// the trajectory.
std::string choiceSummary(const pipeline::ScanPlan& plan) {
  const planner::ConfigMap& map = plan.prepared->map;
  const pipeline::PathChoice& c = plan.choice;
  const planner::ObjectiveTerms& t = c.terms;
  std::string s = fmt::format(
      "plan       {} on {}: J = {:.3f} s (f {:.3f}, omega {:.3f}, alpha {:.3f}) in {:.2f} s\n",
      c.chosen.method, map.branches[c.chosen.result.branch].words(), t.total, t.cost_f,
      t.cost_omega, t.cost_alpha, c.chosen.seconds);
  for (const auto& [b, why] : c.rejected) {
    s += fmt::format("  rejected {} (lower J): {}\n", map.branches[b].words(), why);
  }
  if (c.refine) {
    s += fmt::format("refine     J {:.3f} -> {:.3f} s ({})\n", c.refine->before.total,
                     c.refine->after.total, c.refine->improved ? "improved" : "kept the input");
  }
  if (const auto gap = c.dpGap()) {
    const double step = toDeg(map.angles[1] - map.angles[0]) / c.dp_subdivisions;
    s += fmt::format("baseline   DP optimum J = {:.3f} s (grid {:.3g} deg): gap {:+.1f}%\n",
                     c.dp->terms.total, step, 100.0 * *gap);
  }
  for (const pipeline::PlannerOutcome& o : c.others) {
    s += o.result.solved()
             ? fmt::format("compare    {:<5} J = {:.3f} s in {:.2f} s\n", o.method,
                           o.result.terms.total, o.seconds)
             : fmt::format("compare    {:<5} no path: {}\n", o.method, o.result.reason);
  }
  s += programSummary(plan);
  const planner::TrajectoryBuild& tb = *plan.trajectory;
  const auto& worst = tb.trajectory.samples[tb.min_f_sample];
  s += fmt::format(
      "trajectory {} samples over {:.1f} s; table |omega| <= {:.1f} deg/s, |alpha| <= {:.1f} "
      "deg/s^2; min f {:.3f} at t = {:.1f} s ({}); min clearance {}\n",
      tb.trajectory.samples.size(), tb.trajectory.duration(), toDeg(t.max_abs_omega),
      toDeg(t.max_abs_alpha), tb.min_f, worst.t, worst.limit,
      std::isfinite(tb.min_clearance) ? fmt::format("{:.1f} mm", toMm(tb.min_clearance))
                                      : std::string("beyond every d_high"));
  return s;
}

}  // namespace scanplan::cli
