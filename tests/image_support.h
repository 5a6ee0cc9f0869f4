#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
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

/// Where a figure's data raster sits in its PNG (pixels), from the nested viewport of the SVG
/// that svgFigure writes for a cropped figure.
struct Crop {
  int x = 0, y = 0, w = 0, h = 0;
};
inline Crop svgCrop(const std::string& svg) {
  Crop c;
  const std::size_t at = svg.find("viewBox=\"", svg.find("<svg", 1));
  EXPECT_NE(at, std::string::npos) << svg;
  if (at == std::string::npos) return c;
  EXPECT_EQ(std::sscanf(svg.c_str() + at, "viewBox=\"%d %d %d %d\"", &c.x, &c.y, &c.w, &c.h), 4);
  return c;
}

}  // namespace scanplan::test
