#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "cli/plot/image_io.h"

namespace scanplan::test {

/// Pixels darker than (100, 100, 100) in every channel inside [x0, x1) × [y0, y1), clipped to
/// the image: where text, ticks or lines were drawn on a white figure.
inline int darkPixels(const cli::RgbImage& image, int x0, int y0, int x1, int y1) {
  int n = 0;
  for (int y = std::max(y0, 0); y < std::min(y1, image.height); ++y) {
    for (int x = std::max(x0, 0); x < std::min(x1, image.width); ++x) {
      const cli::Rgb c = image.at(x, y);
      n += c.r < 100 && c.g < 100 && c.b < 100 ? 1 : 0;
    }
  }
  return n;
}

/// Where a figure's plot area (its data raster) sits in its PNG, in pixels.
struct Crop {
  int x = 0, y = 0, w = 0, h = 0;
};
/// The plot area of a figure's pixels: just inside the 1 px black frame around it, found as the
/// first row with a black run of at least `min_width` px (the frame's top edge) and the black
/// column under the run's first pixel (its left edge). All zero when there is none.
inline Crop plotArea(const cli::RgbImage& png, int min_width = 200) {
  const cli::Rgb black{0, 0, 0};
  for (int y = 0; y < png.height; ++y) {
    int run = 0;
    for (int x = 0; x <= png.width; ++x) {
      if (x < png.width && png.at(x, y) == black) {
        ++run;
        continue;
      }
      if (run >= min_width) {
        const int x0 = x - run;
        int down = 0;
        while (y + down < png.height && png.at(x0, y + down) == black) ++down;
        return {x0 + 1, y + 1, run - 2, down - 2};
      }
      run = 0;
    }
  }
  ADD_FAILURE() << "no plot frame in a " << png.width << " x " << png.height << " figure";
  return {};
}

}  // namespace scanplan::test
