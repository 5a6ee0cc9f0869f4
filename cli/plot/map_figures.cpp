// The map and path figures of `map` and `plan`: configmap.png/.svg (f), configmap_why (the
// limiting constraint), configmap_cylinder, configmap_path (paths over f) and path.png.
#include "cli/plot/map_figures.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

#include <fmt/format.h>

#include <scanplan/kinematics/units.h>
#include "cli/plot/image_io.h"

namespace scanplan::cli {
namespace {

constexpr int kMaxImageWidth = 2000;
constexpr int kMaxImageHeight = 1200;
// The cylinder picture: each half (view) this many rows, with a gap between them.
constexpr int kCylinderHalf = 240, kCylinderGap = 12;

// Min-pooled map image for one branch: time left → right, angle bottom → top.
template <class Colour>
RgbImage mapImage(const planner::ConfigMap& map, std::size_t branch, Colour colour) {
  const int nt = static_cast<int>(map.times.size()), na = static_cast<int>(map.angles.size());
  const int w = std::min(nt, kMaxImageWidth), h = std::min(na, kMaxImageHeight);
  RgbImage image = RgbImage::filled(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      // The block of cells behind this pixel; the worst cell represents it (forbidden bands
      // must not vanish when a map is shrunk).
      const int a0 = (h - 1 - y) * na / h, a1 = std::max(a0 + 1, (h - y) * na / h);
      const int t0 = x * nt / w, t1 = std::max(t0 + 1, (x + 1) * nt / w);
      std::size_t worst =
          map.index(branch, static_cast<std::size_t>(a0), static_cast<std::size_t>(t0));
      for (int a = a0; a < a1; ++a)
        for (int t = t0; t < t1; ++t) {
          const std::size_t i =
              map.index(branch, static_cast<std::size_t>(a), static_cast<std::size_t>(t));
          if (map.f[i] < map.f[worst]) worst = i;
        }
      image.set(x, y, colour(worst));
    }
  }
  return image;
}

// Fig. 6(b): the map wrapped on a cylinder (axis = time), seen from the side; the front half
// (table angles around 0°) above, the back half (around 180°) below.
RgbImage cylinderImage(const planner::ConfigMap& map, std::size_t branch) {
  const int nt = static_cast<int>(map.times.size());
  const int w = std::min(nt, kMaxImageWidth), half = kCylinderHalf, gap = kCylinderGap;
  RgbImage image = RgbImage::filled(w, 2 * half + gap, {255, 255, 255});
  const double step = map.angles.size() > 1 ? map.angles[1] - map.angles[0] : 1.0;
  for (int view = 0; view < 2; ++view) {
    const double centre = view == 0 ? 0.0 : std::numbers::pi;
    for (int y = 0; y < half; ++y) {
      const double v = 1.0 - 2.0 * (y + 0.5) / half;
      const double alpha = std::asin(v);  // angle on the cylinder seen at this row
      double theta = std::fmod(centre + alpha + 4.0 * std::numbers::pi, 2.0 * std::numbers::pi);
      if (theta < map.angles.front() - 1e-9 || theta > map.angles.back() + step) continue;
      const auto a = std::min(
          map.angles.size() - 1,
          static_cast<std::size_t>(std::max(0.0, std::floor((theta - map.angles.front()) / step))));
      const double shade = 0.35 + 0.65 * std::cos(alpha);
      for (int x = 0; x < w; ++x) {
        const auto t = static_cast<std::size_t>(x * nt / w);
        const double f = map.f[map.index(branch, a, t)];
        image.set(x, view * (half + gap) + y, grey(shade * f));
      }
    }
  }
  return image;
}

// The cylinder picture framed: time below, the table angle of the rows left (not linear: the
// rows are the cylinder seen from the side), title, colour bar and which half is which.
void writeCylinderFigure(const std::filesystem::path& dir,
                         const planner::ConfigMap& map,
                         std::size_t branch,
                         const PngSettings& png) {
  const RgbImage raster = cylinderImage(map, branch);
  Figure figure;
  figure.raster = upscale(raster, std::max(1, 1000 / std::max(raster.width, 1)), 1);
  FigureLabels& labels = figure.labels;
  labels.title = "Configuration map f on a cylinder (Fig. 6b), " + map.branches[branch].words();
  labels.x_label = "time (s)";
  labels.y_label = "table angle (deg)";
  labels.x0 = map.times.empty() ? 0.0 : map.times.front();
  labels.x1 = map.times.empty() ? 1.0 : map.times.back();
  // y in raster rows counted from the bottom; the angle seen at a row as cylinderImage has it.
  labels.y0 = 0.0;
  labels.y1 = raster.height;
  for (int view = 0; view < 2; ++view) {
    for (const int alpha : {-60, -30, 0, 30, 60}) {
      const double row = view * (kCylinderHalf + kCylinderGap) +
                         (1.0 - std::sin(deg(alpha))) * kCylinderHalf / 2.0;
      const int angle = ((view == 0 ? 0 : 180) + alpha + 360) % 360;
      labels.y_marks.emplace_back(raster.height - row, std::to_string(angle));
    }
  }
  labels.colour_bar = "f (shaded)";
  labels.legend = {{{0, 0, 0}, "above: front half,", LegendEntry::Mark::kNone},
                   {{0, 0, 0}, "around 0 deg", LegendEntry::Mark::kNone},
                   {{0, 0, 0}, "below: back half,", LegendEntry::Mark::kNone, {0, 0, 0}, 6},
                   {{0, 0, 0}, "around 180 deg", LegendEntry::Mark::kNone}};
  writePng(dir / "configmap_cylinder.png", renderFigure(figure), png);
}

}  // namespace

namespace {

// `stem`.png and `stem`.svg: the map raster, stretched to a readable aspect, framed with the
// title, axes (time in s, table angle in deg), tick values and legend; `overlays` over it.
void writeMapFigure(const std::filesystem::path& dir,
                    const std::string& stem,
                    const RgbImage& raster,
                    const planner::ConfigMap& map,
                    FigureLabels labels,
                    std::vector<Overlay> overlays,
                    const WriteSettings& settings) {
  // At least ~1000 px wide and 40 % as tall as wide: a 1095 × 180 map is not a thin strip;
  // nearest-neighbour blocks keep every cell's colour.
  const int fx = std::max(1, 1000 / std::max(raster.width, 1));
  const int fy = std::max(
      1, (2 * raster.width * fx + 5 * raster.height - 1) / (5 * std::max(raster.height, 1)));
  Figure figure;
  figure.raster = upscale(raster, fx, fy);
  figure.overlays = std::move(overlays);
  labels.x_label = "time (s)";
  labels.y_label = "table angle (deg)";
  labels.x0 = map.times.empty() ? 0.0 : map.times.front();
  labels.x1 = map.times.empty() ? 1.0 : map.times.back();
  const double step = map.angles.size() > 1 ? map.angles[1] - map.angles[0] : 0.0;
  labels.y0 = map.angles.empty() ? 0.0 : toDeg(map.angles.front());
  labels.y1 = map.angles.empty() ? 360.0 : toDeg(map.angles.back() + step);
  figure.labels = std::move(labels);
  writeFigureFiles(dir, stem, figure, settings);
}

}  // namespace

// The grey f map with paths over it (configmap_path): the legend names each path (drawn as a
// line in its colour), and a colour bar gives the grey scale of f.
void writeFigure(const std::filesystem::path& dir,
                 const std::string& stem,
                 const RgbImage& image,
                 const planner::ConfigMap& map,
                 const std::string& title,
                 std::vector<std::pair<Rgb, std::string>> legend,
                 std::vector<Overlay> paths,
                 const WriteSettings& settings) {
  FigureLabels labels;
  labels.title = title;
  for (auto& [colour, text] : legend) {
    labels.legend.push_back({colour, std::move(text), LegendEntry::Mark::kLine});
  }
  labels.colour_bar = "map f";
  writeMapFigure(dir, stem, image, map, std::move(labels), std::move(paths), settings);
}

RgbImage mapGreyImage(const planner::ConfigMap& map, std::size_t branch) {
  return mapImage(map, branch, [&](std::size_t i) { return grey(map.f[i]); });
}

void writeMapFigures(const std::filesystem::path& dir,
                     const planner::ConfigMap& map,
                     std::size_t shown,
                     const WriteSettings& settings) {
  const std::string branch = map.branches[shown].words();
  FigureLabels grey_labels;
  grey_labels.title =
      "Configuration map f (Eq. 6), " + branch + ": white = free, black = forbidden";
  grey_labels.colour_bar = "f";
  writeMapFigure(dir, "configmap", mapGreyImage(map, shown), map, grey_labels, {}, settings);
  // Colour by the limiting constraint, brighter where f is higher.
  FigureLabels why_labels;
  why_labels.title = "Limiting constraint per cell, " + branch + " (darker = lower f)";
  why_labels.legend.push_back({{0, 0, 0}, "limited by:", LegendEntry::Mark::kNone});
  for (int k = 0; k < planner::kLimitCount; ++k) {
    const std::string name = planner::limitName(static_cast<planner::Limit>(k));
    why_labels.legend.push_back({categoryColour(k + 1), k == 0 ? name + " (f = 1)" : name});
  }
  why_labels.legend.push_back(
      {{90, 90, 90}, "darker: lower f", LegendEntry::Mark::kNone, {90, 90, 90}, 10});
  writeMapFigure(
      dir, "configmap_why",
      mapImage(map, shown,
               [&](std::size_t i) {
                 const Rgb c = categoryColour(map.limit[i] + 1);
                 const double f = std::isnan(map.f[i]) ? 0.0 : map.f[i];  // NaN: as forbidden
                 const double s = 0.45 + 0.55 * std::clamp(f, 0.0, 1.0);
                 return Rgb{static_cast<std::uint8_t>(c.r * s), static_cast<std::uint8_t>(c.g * s),
                            static_cast<std::uint8_t>(c.b * s)};
               }),
      map, why_labels, {}, settings);
  writeCylinderFigure(dir, map, shown, settings.png);
}

// Three views of the path around the part (iso, top, front), side by side, captioned, with a
// legend.
double niceLength(double at_most) {
  const double decade = std::pow(10.0, std::floor(std::log10(at_most)));
  for (const double m : {5.0, 2.0, 1.0}) {
    if (m * decade <= at_most) return m * decade;
  }
  return decade;
}

RgbImage pathPicture(const kinematics::TriangleMesh& part,
                     const kinematics::ScanPath& path,
                     const std::optional<TableTop>& table) {
  constexpr int kView = 480;
  ViewGrid grid;
  ViewRow& row = grid.rows.emplace_back();
  row.title = fmt::format("Scan path: the laser origin around the part, part frame ({:.1f} s)",
                          path.duration());
  RenderRequest r;
  r.width = kView;
  r.height = kView;
  r.vertices = part.vertices;
  r.triangles = part.triangles;
  const Rgb part_colour{185, 185, 185}, table_colour{226, 214, 190};
  r.triangle_colours.assign(part.triangles.size(), part_colour);
  if (table) {  // the table top as a disc under the part, in the part frame
    constexpr int kSegments = 96;
    const Eigen::Isometry3d X_PR = table->X_RP.inverse();
    const int centre = static_cast<int>(r.vertices.size());
    r.vertices.push_back(X_PR * Eigen::Vector3d::Zero());
    for (int i = 0; i < kSegments; ++i) {
      const double a = 2.0 * std::numbers::pi * i / kSegments;
      r.vertices.push_back(
          X_PR * Eigen::Vector3d(table->radius * std::cos(a), table->radius * std::sin(a), 0.0));
      r.triangles.emplace_back(centre, centre + 1 + i, centre + 1 + (i + 1) % kSegments);
      r.triangle_colours.push_back(table_colour);
    }
  }
  for (const auto& s : path.samples) r.polyline.push_back(s.X_PS.translation());
  const Rgb start = categoryColour(2), end = categoryColour(5);
  if (!r.polyline.empty()) {
    r.markers.push_back({r.polyline.front(), start});
    r.markers.push_back({r.polyline.back(), end});
  }
  const double extent = part.bounds().isEmpty() ? 0.0 : part.bounds().sizes().maxCoeff();
  if (extent > 0.0) r.scale_bar = niceLength(0.5 * extent);
  for (const NamedView& view : partViews()) grid.captions.push_back(view.name);
  row.views = renderScenes(r, partViewRotations());
  grid.legend = {
      {r.polyline_colour, "path (lighter where the part hides it)", LegendEntry::Mark::kLine},
      {start, "start"},
      {end, "end"},
      {part_colour, "part"}};
  if (table) grid.legend.push_back({table_colour, "table top"});
  if (r.scale_bar > 0.0) {
    grid.legend.push_back({Rgb{0, 0, 0},
                           fmt::format("{:g} mm (bar, bottom left)", 1000.0 * r.scale_bar),
                           LegendEntry::Mark::kLine});
  }
  return drawViewGrid(grid);
}

}  // namespace scanplan::cli
