#pragma once
// cell.png: the robot in its cell at one moment of the plan (three views).

#include <cstddef>
#include <string>

#include <scanplan/pipeline/replay.h>
#include "cli/plot/image_io.h"

namespace scanplan::cli {

/// The cell of `scene` at frame `frame` (world frame; robot links orange, scanner dark, table
/// beige, part as coloured, obstacles blue-grey) in iso, top and front views, titled `title`,
/// with a scale bar. Throws std::out_of_range for a frame past the end.
RgbImage cellPicture(const pipeline::ReplayScene& scene,
                     std::size_t frame,
                     const std::string& title);

}  // namespace scanplan::cli
