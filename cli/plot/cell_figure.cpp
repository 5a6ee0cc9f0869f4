#include "cli/plot/cell_figure.h"

#include <algorithm>
#include <set>

#include <fmt/format.h>

#include "cli/plot/figure.h"
#include "cli/plot/map_figures.h"

namespace scanplan::cli {

namespace {

Rgb bodyColour(const pipeline::ReplayBody& b) {
  if (b.name == "scanner") return {60, 66, 78};
  if (b.name == "table") return {226, 214, 190};
  if (b.name == "part") return {185, 185, 185};
  if (b.frame >= 0 && b.frame <= 6) return {243, 156, 52};
  return {127, 147, 168};
}

// The cell's bodies at a frame as one render request: the links' stand-ins in place of their
// meshes when `standins` (the links without one as they are), else the meshes.
RenderRequest cellScene(const pipeline::ReplayScene& scene,
                        const pipeline::ReplayFrame& f,
                        bool standins) {
  std::set<int> replaced;  // frames whose link a stand-in replaces
  for (const pipeline::ReplayBody& b : scene.bodies)
    if (b.standin) replaced.insert(b.frame);
  RenderRequest r;
  r.width = r.height = 480;
  for (const pipeline::ReplayBody& b : scene.bodies) {
    const bool link_mesh = !b.standin && b.frame >= 0 && b.frame <= 6 && replaced.count(b.frame);
    if (standins ? link_mesh : b.standin) continue;
    const Eigen::Isometry3d X =
        b.frame < 0 ? Eigen::Isometry3d::Identity() : f.poses[static_cast<std::size_t>(b.frame)];
    const int base = static_cast<int>(r.vertices.size());
    for (const Eigen::Vector3d& v : b.mesh.vertices) r.vertices.push_back(X * v);
    for (std::size_t t = 0; t < b.mesh.triangles.size(); ++t) {
      r.triangles.push_back(b.mesh.triangles[t] + Eigen::Vector3i::Constant(base));
      r.triangle_colours.push_back(t < b.colours.size()
                                       ? Rgb{b.colours[t][0], b.colours[t][1], b.colours[t][2]}
                                       : bodyColour(b));
    }
  }
  return r;
}

}  // namespace

RgbImage cellPicture(const pipeline::ReplayScene& scene,
                     std::size_t frame,
                     const std::string& title) {
  const pipeline::ReplayFrame& f = scene.frames.at(frame);
  RenderRequest r = cellScene(scene, f, false);
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& v : r.vertices) box.extend(v);
  r.scale_bar = box.isEmpty() ? 0.0 : niceLength(0.3 * box.sizes().maxCoeff());
  ViewGrid grid;
  ViewRow& row = grid.rows.emplace_back();
  row.title =
      fmt::format("{} at t = {:.1f} s ({})", title, f.t, f.scanning ? "scanning" : "moving");
  for (const NamedView& view : partViews()) grid.captions.push_back(view.name);
  row.views = renderScenes(r, partViewRotations());
  const bool standins = std::any_of(scene.bodies.begin(), scene.bodies.end(),
                                    [](const pipeline::ReplayBody& b) { return b.standin; });
  if (standins) {
    RenderRequest s = cellScene(scene, f, true);
    s.scale_bar = r.scale_bar;
    ViewRow& second = grid.rows.emplace_back();
    second.title = "what the maps measure: each link mesh's hull, convex pieces or cylinder (a colour each)";
    second.views = renderScenes(s, partViewRotations());
  }
  grid.legend = {{Rgb{243, 156, 52}, "robot"},
                 {Rgb{60, 66, 78}, "scanner"},
                 {Rgb{226, 214, 190}, "table"},
                 {Rgb{185, 185, 185}, "part (coloured by coverage when simulated)"}};
  for (const pipeline::ReplayBody& b : scene.bodies) {
    if (b.name != "table" && b.name != "part" && (b.frame < 0 || b.frame == 8)) {
      grid.legend.push_back({Rgb{127, 147, 168}, "obstacles"});
      break;
    }
  }
  if (r.scale_bar > 0.0) {
    grid.legend.push_back(
        {Rgb{0, 0, 0}, fmt::format("{:g} mm", 1000.0 * r.scale_bar), LegendEntry::Mark::kLine});
  }
  return drawViewGrid(grid);
}

}  // namespace scanplan::cli
