#include "cli/report/simulation_files.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <sstream>

#include <fmt/format.h>

#include <scanplan/kinematics/units.h>
#include <scanplan/scanner/cloud_io.h>
#include "cli/io/output.h"
#include "cli/plot/figure.h"
#include "cli/plot/image_io.h"

namespace scanplan::cli {

namespace {

Rgb toRgb(const std::array<std::uint8_t, 3>& c) { return {c[0], c[1], c[2]}; }

// A binary file written by `write` (a PLY writer): streamed onto the file, or (the reference)
// formatted into memory first.
void writeBinary(const std::filesystem::path& file,
                 const WriteSettings& settings,
                 const std::function<void(std::ostream&)>& write) {
  if (settings.stream_binary) {
    writeFileAtomically(file, write);
    return;
  }
  std::ostringstream out(std::ios::binary);
  write(out);
  writeFileAtomically(file, out.str());
}

// The points of cloud.png's top row, coloured by acquisition time, in one view (R_view unset).
RenderRequest cloudPoints(const kinematics::TriangleMesh& part,
                          const std::vector<scanner::CloudPoint>& cloud,
                          double t_end) {
  RenderRequest points;
  // Fit both rows to the part's box: invisible corner markers would show, so use the part.
  points.vertices = part.vertices;
  points.dots.resize(cloud.size());
  points.dot_colours.resize(cloud.size());
  // The points of a profile share its time: one colour each (the same as computed per point).
  double last_t = std::numeric_limits<double>::quiet_NaN();
  Rgb colour;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const scanner::CloudPoint& p = cloud[i];
    points.dots[i] = p.p_P;
    if (!(p.t == last_t)) {
      last_t = p.t;
      colour = toRgb(scanner::densityColour(t_end > 0.0 ? p.t / t_end : 0.0, 1.0, true));
    }
    points.dot_colours[i] = colour;
  }
  return points;
}

// A profile image for a person: the camera image as it is (left) and with the detected stripe
// marked in red (right), each pixel drawn 2 × 2.
RgbImage profileImagePicture(const scanner::ProfileImage& image, const config::JobSpec& job) {
  const int w = image.columns, h = image.rows;
  RgbImage picture = RgbImage::filled(2 * w + 4, h, Rgb{0, 114, 178});
  for (int r = 0; r < h; ++r) {
    for (int k = 0; k < w; ++k) {
      const auto g = static_cast<std::uint8_t>(std::lround(image.at(r, k)));
      picture.set(k, r, {g, g, g});
      picture.set(w + 4 + k, r, {g, g, g});
    }
  }
  const auto method = job.scanner.camera.detection == "gauss"
                          ? scanner::StripeMethod::kGaussian
                          : scanner::StripeMethod::kCentreOfGravity;
  const auto rows = scanner::detectStripe(image, job.scanner.camera.threshold_grey, method);
  for (int k = 0; k < w; ++k) {
    if (const auto& row = rows[static_cast<std::size_t>(k)]) {
      const int r = std::clamp(static_cast<int>(std::lround(*row)), 0, h - 1);
      picture.set(w + 4 + k, r, {230, 30, 30});
    }
  }
  return upscale(picture, 2, 2);
}

}  // namespace

void writeSimulationOutputs(const std::filesystem::path& dir,
                            const config::JobSpec& job,
                            const kinematics::TriangleMesh& part,
                            const pipeline::SimulationRun& run,
                            const WriteSettings& settings) {
  writeBinary(dir / "cloud.ply", settings,
              [&](std::ostream& out) { scanner::writeCloudPly(out, run.cloud.points); });
  scanner::CoverageSettings coverage_settings;
  coverage_settings.min_points = static_cast<std::uint32_t>(job.simulation.coverage_min_points);
  writeBinary(dir / "coverage.ply", settings, [&](std::ostream& out) {
    scanner::writeCoveragePly(out, part, run.coverage, coverage_settings);
  });

  // cloud.png: top row the points (coloured by acquisition time), bottom row the part coloured
  // by density; iso, top and front views, captioned, each row with its colour scale.
  constexpr int kView = 480;
  const double t_end = run.cloud.points.empty() ? 1.0 : run.cloud.points.back().t;
  std::vector<Rgb> triangle_colours;
  const double max_density = run.coverage.density_p95_per_mm2;
  for (std::size_t i = 0; i < part.triangles.size(); ++i) {
    const bool covered = run.coverage.hits[i] >= coverage_settings.min_points;
    triangle_colours.push_back(toRgb(scanner::densityColour(
        scanner::triangleDensityPerMm2(part, run.coverage, i), max_density, covered)));
  }
  ViewGrid grid;
  grid.rows.resize(2);  // both rows first: references into the vector stay valid
  ViewRow& cloud = grid.rows[0];
  cloud.title =
      fmt::format("Simulated cloud, {} points, by acquisition time:", run.cloud.points.size());
  ViewRow& density = grid.rows[1];
  // The picture colours whole triangles: its title gives the triangles' measure (the summary's
  // area coverage, within the spacing of a point, is the stricter one).
  density.title = fmt::format(
      "The part by triangle: {:.1f}% of its area on triangles with a point (red-orange: none); "
      "point density:",
      100.0 * run.coverage.covered_fraction);
  for (int i = 0; i < 64; ++i) {
    const double u = i / 63.0;
    cloud.scale.push_back(toRgb(scanner::densityColour(u, 1.0, true)));
    density.scale.push_back(toRgb(scanner::densityColour(u * max_density, max_density, true)));
  }
  cloud.scale_from = "0 s";
  cloud.scale_to = fmt::format("{:.0f} s", t_end);
  density.scale_from = "0";
  density.scale_to = fmt::format("{:.1f} points/mm² (95%)", max_density);
  RenderRequest mesh;
  mesh.width = mesh.height = kView;
  mesh.vertices = part.vertices;
  mesh.triangles = part.triangles;
  mesh.triangle_colours = std::move(triangle_colours);
  density.views = renderScenes(mesh, partViewRotations());
  for (const NamedView& view : partViews()) grid.captions.push_back(view.name);
  if (settings.shared_views) {
    // One request for the three views, its points read once for all of them.
    RenderRequest points = cloudPoints(part, run.cloud.points, t_end);
    points.width = points.height = kView;
    cloud.views = renderScenes(points, partViewRotations());
  } else {
    for (const NamedView& view : partViews()) {
      RenderRequest points = cloudPoints(part, run.cloud.points, t_end);
      points.width = points.height = kView;
      points.R_view = view.R_view;
      cloud.views.push_back(renderScene(points));
    }
  }
  grid.legend = {{toRgb(scanner::densityColour(0.0, 1.0, false)),
                  coverage_settings.min_points > 1
                      ? fmt::format("not covered (fewer than {} points on the triangle)",
                                    coverage_settings.min_points)
                      : std::string("not covered (no point on the triangle)")}};
  writePng(dir / "cloud.png", drawViewGrid(grid), settings.views);

  if (run.profile_images.empty()) return;
  std::filesystem::create_directories(dir / "profiles");
  for (const auto& [index, image] : run.profile_images) {
    writePng(dir / "profiles" / fmt::format("profile_{:06d}.png", index),
             profileImagePicture(image, job), settings.png);
  }
}

namespace {

Rgb classColour(std::size_t c) {
  const auto rgb = pipeline::coverageClassColour(static_cast<pipeline::CoverageClass>(c));
  return {rgb[0], rgb[1], rgb[2]};
}

const char* classWords(std::size_t c) {
  return pipeline::coverageClassWords(static_cast<pipeline::CoverageClass>(c));
}

void writeUncoveredPly(const std::filesystem::path& file,
                       const scanner::AreaSampling& sampling,
                       const pipeline::Certificate& certificate,
                       const WriteSettings& settings) {
  std::vector<Eigen::Vector3d> points, normals;
  std::vector<std::uint8_t> labels;
  for (std::size_t i = 0; i < sampling.samples.size(); ++i) {
    const auto c = certificate.classes[i];
    if (c == pipeline::CoverageClass::kCovered) continue;
    points.push_back(sampling.samples[i].p);
    normals.push_back(sampling.samples[i].n);
    labels.push_back(static_cast<std::uint8_t>(c));
  }
  std::vector<std::string> reasons;
  for (std::size_t c = 0; c < pipeline::kCoverageClasses; ++c)
    reasons.emplace_back(pipeline::coverageClassName(static_cast<pipeline::CoverageClass>(c)));
  writeBinary(file, settings, [&](std::ostream& out) {
    scanner::writeLabelledSamplesPly(out, points, normals, labels, reasons);
  });
}

}  // namespace

void writeCertificateOutputs(const std::filesystem::path& dir,
                             const kinematics::TriangleMesh& part,
                             const scanner::AreaSampling& sampling,
                             const pipeline::Certificate& certificate,
                             const WriteSettings& settings) {
  writeUncoveredPly(dir / "uncovered.ply", sampling, certificate, settings);
  constexpr int kView = 480;
  // The samples lifted 0.3 mm off the surface, so the grey part hides those on its far side
  // but not the ones on the side facing the viewer.
  const double lift = 3e-4;
  ViewGrid grid;
  grid.rows.resize(1);
  ViewRow& row = grid.rows[0];
  row.title = fmt::format(
      "Scannability certificate: {:.1f}% of the area scannable, {:.1f}% of that covered",
      100.0 * certificate.scannable_fraction, 100.0 * certificate.covered_of_scannable);
  RenderRequest r;
  r.width = r.height = kView;
  r.vertices = part.vertices;
  r.triangles = part.triangles;
  for (std::size_t i = 0; i < sampling.samples.size(); ++i) {
    r.dots.push_back(sampling.samples[i].p + lift * sampling.samples[i].n);
    r.dot_colours.push_back(classColour(static_cast<std::size_t>(certificate.classes[i])));
  }
  for (const NamedView& view : partViews()) grid.captions.push_back(view.name);
  row.views = renderScenes(r, partViewRotations());
  for (std::size_t c = 0; c < pipeline::kCoverageClasses; ++c)
    grid.legend.push_back({classColour(c), fmt::format("{} {:.1f}%", classWords(c),
                                                       100.0 * certificate.fraction[c])});
  // Why the area is not covered: the classes other than covered, as shares of what is not.
  double uncovered = 0.0;
  for (std::size_t c = 1; c < pipeline::kCoverageClasses; ++c) uncovered += certificate.fraction[c];
  if (uncovered > 0.0) {
    BreakdownBar& bar = grid.bars.emplace_back();
    bar.title = fmt::format("Why {:.1f}% of the area is not covered:", 100.0 * uncovered);
    for (std::size_t c = 1; c < pipeline::kCoverageClasses; ++c) {
      const double share = certificate.fraction[c] / uncovered;
      bar.segments.push_back(
          {classColour(c), share, fmt::format("{} {:.0f}%", classWords(c), 100.0 * share)});
    }
  }
  writePng(dir / "certificate.png", drawViewGrid(grid), settings.views);
}

void writeCoverageCurve(const std::filesystem::path& dir,
                        const pipeline::CoverageCurve& curve,
                        double program_s,
                        const WriteSettings& settings) {
  if (curve.t.empty()) return;
  const Rgb blue{0, 114, 178}, vermilion{213, 94, 0}, grey{120, 120, 120};
  Figure f;
  f.grid = true;
  FigureLabels& l = f.labels;
  l.title = fmt::format("Coverage against program time: {:.1f}% of the scannable area in {:.0f} s",
                        100.0 * curve.fraction.back(), program_s);
  l.x_label = "program time (s)";
  l.y_label = "scannable area covered (%)";
  l.x0 = 0.0;
  l.x1 = std::max(program_s, curve.t.back());
  l.y0 = 0.0;
  l.y1 = 100.0;
  Overlay line{Overlay::Kind::kLine, {{0.0, 0.0}}, blue, 2.0};
  for (std::size_t k = 0; k < curve.t.size(); ++k) {
    const double before = line.points.back().second;
    line.points.push_back({curve.t[k], before});  // a step: nothing new until t[k]
    line.points.push_back({curve.t[k], 100.0 * curve.fraction[k]});
  }
  line.points.push_back({l.x1, 100.0 * curve.fraction.back()});
  f.overlays.push_back(line);
  l.legend.push_back({blue, "covered so far", LegendEntry::Mark::kLine});
  for (const double share : {0.95, 0.98}) {
    const auto t = curve.timeTo(share);
    if (!t) continue;
    f.overlays.push_back({Overlay::Kind::kCrosses, {{*t, 100.0 * share}}, vermilion, 2.0});
    l.legend.push_back({vermilion, fmt::format("{:.0f}% in {:.0f} s", 100.0 * share, *t),
                        LegendEntry::Mark::kCross});
  }
  f.overlays.push_back({Overlay::Kind::kLine, {{program_s, 0.0}, {program_s, 100.0}}, grey, 1.0});
  l.legend.push_back(
      {grey, fmt::format("program ends at {:.0f} s", program_s), LegendEntry::Mark::kLine});
  writeFigureFiles(dir, "coverage_time", f, settings);
}

}  // namespace scanplan::cli
