#pragma once

#include <optional>

#include <cstddef>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/scan_path.h>
#include <scanplan/planner/config_map.h>
#include "cli/plot/figure.h"
#include "cli/plot/image_io.h"

namespace scanplan::cli {

/// The f layer of one branch, min-pooled to at most 2000 x 1200 px (time →, angle ↑).
RgbImage mapGreyImage(const planner::ConfigMap& map, std::size_t branch);

/// `stem`.png and `stem`.svg: the map raster `image` (time →, angle ↑) framed with axes, title,
/// a colour bar of f and a legend line per path; `paths` are drawn over it in axis units (time
/// in s, table angle in deg), one per legend entry.
void writeFigure(const std::filesystem::path& dir,
                 const std::string& stem,
                 const RgbImage& image,
                 const planner::ConfigMap& map,
                 const std::string& title,
                 std::vector<std::pair<Rgb, std::string>> legend,
                 std::vector<Overlay> paths = {},
                 const WriteSettings& settings = {});

/// configmap.png/.svg (f), configmap_why.png/.svg (the limiting constraint, darker where f is
/// lower) and configmap_cylinder.png of branch `shown`, into `dir`.
void writeMapFigures(const std::filesystem::path& dir,
                     const planner::ConfigMap& map,
                     std::size_t shown,
                     const WriteSettings& settings = {});

/// Three views of the path (the laser origin, part frame) around the part, captioned, with start
/// and end marked.
/// The table top under the part in path.png: its radius (m) and the part frame on it (X_RP).
struct TableTop {
  double radius = 0.0;
  Eigen::Isometry3d X_RP = Eigen::Isometry3d::Identity();
};
RgbImage pathPicture(const kinematics::TriangleMesh& part,
                     const kinematics::ScanPath& path,
                     const std::optional<TableTop>& table = std::nullopt);
/// A round length for a scale bar: 1, 2 or 5 × 10^k, at most `at_most` (> 0).
double niceLength(double at_most);

}  // namespace scanplan::cli
