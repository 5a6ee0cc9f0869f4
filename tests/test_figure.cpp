// Figures on cairo: the raster copied exactly into the plot area, text in the margins, the same
// layout in PNG, SVG and PDF, and the same bytes for the same figure.
#include "cli/plot/figure.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <scanplan/kinematics/error.h>
#include "cli/plot/image_io.h"
#include "tests/image_support.h"

namespace {

using namespace scanplan::cli;
using scanplan::test::Crop;
using scanplan::test::darkPixels;
using scanplan::test::plotArea;

constexpr Rgb kWhite{255, 255, 255};

FigureLabels someLabels() {
  FigureLabels labels;
  labels.title = "J, objective (s) against planner.ray.horizon";
  labels.x_label = "planner.ray.horizon";
  labels.y_label = "J, objective (s)";
  labels.x0 = 9.2;
  labels.x1 = 30.8;
  labels.y0 = 20;
  labels.y1 = 30;
  labels.legend = {{{213, 94, 0}, "ray"},
                   {{0, 114, 178}, "dp", LegendEntry::Mark::kLine},
                   {{90, 90, 90}, "case", LegendEntry::Mark::kCross, {90, 90, 90}, 10}};
  return labels;
}

Figure rasterFigure() {
  Figure figure;
  figure.labels = someLabels();
  figure.raster = RgbImage::filled(300, 200);
  for (int y = 0; y < 200; ++y) {
    for (int x = 0; x < 300; ++x) {
      figure.raster.set(x, y,
                        {static_cast<std::uint8_t>(x % 251), static_cast<std::uint8_t>(y), 77});
    }
  }
  return figure;
}

bool hasColour(const RgbImage& image, int x0, Rgb colour) {
  for (int y = 0; y < image.height; ++y) {
    for (int x = x0; x < image.width; ++x) {
      if (image.at(x, y) == colour) return true;
    }
  }
  return false;
}

TEST(Figure, RasterIsCopiedExactlyAndTextFillsTheMargins) {
  const Figure figure = rasterFigure();
  const FigureLayout f = layoutFigure(figure);
  const RgbImage image = renderFigure(figure);
  ASSERT_EQ(image.width, f.width);
  ASSERT_EQ(image.height, f.height);
  ASSERT_EQ(f.area_width, 300);
  ASSERT_EQ(f.area_height, 200);
  ASSERT_GT(f.area_x, 30);
  ASSERT_GT(f.area_y, 20);
  ASSERT_GT(image.width, f.area_x + 300 + 60);
  ASSERT_GT(image.height, f.area_y + 200 + 40);
  for (int y = 0; y < 200; ++y) {
    for (int x = 0; x < 300; ++x) {
      ASSERT_EQ(image.at(f.area_x + x, f.area_y + y), figure.raster.at(x, y)) << x << ", " << y;
    }
  }
  // The frame just outside the raster, where the tests of written figures look for it.
  const Crop c = plotArea(image);
  EXPECT_EQ(c.x, f.area_x);
  EXPECT_EQ(c.y, f.area_y);
  EXPECT_EQ(c.w, 300);
  EXPECT_EQ(c.h, 200);
  EXPECT_GT(darkPixels(image, 0, 0, image.width, f.area_y - 2), 150) << "title";
  EXPECT_GT(darkPixels(image, 0, f.area_y, f.area_x - 8, f.area_y + 200), 150) << "y values, title";
  EXPECT_GT(darkPixels(image, 0, f.area_y + 202, image.width, image.height), 150)
      << "x values, title";
  EXPECT_GT(darkPixels(image, f.area_x + 302, 0, image.width, image.height), 30) << "legend text";
  EXPECT_TRUE(hasColour(image, f.area_x + 302, {213, 94, 0})) << "swatch";
  EXPECT_TRUE(hasColour(image, f.area_x + 302, {0, 114, 178})) << "line";
}

TEST(Figure, SameFigureSameBytesInEveryFormat) {
  const Figure figure = rasterFigure();
  const std::string png = encodePng(renderFigure(figure));
  const std::string svg = figureSvg(figure);
  const std::string pdf = figurePdf(figure);
  // Another figure in between: cairo's process-wide surface counters must not show.
  Figure other = rasterFigure();
  other.labels.title = "another";
  EXPECT_NE(figureSvg(other), svg);
  EXPECT_EQ(encodePng(renderFigure(figure)), png);
  EXPECT_EQ(figureSvg(figure), svg);
  EXPECT_EQ(figurePdf(figure), pdf);
  EXPECT_EQ(pdf.rfind("%PDF-", 0), 0u);
}

TEST(Figure, SvgIsVectorWithTheRasterEmbeddedAndItsWordsDescribed) {
  const Figure figure = rasterFigure();
  const FigureLayout f = layoutFigure(figure);
  const std::string svg = figureSvg(figure);
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  // 0.75 pt per figure pixel: the SVG shows at the PNG's size.
  EXPECT_NE(svg.find("width=\"" + std::to_string(f.width * 3 / 4)), std::string::npos)
      << svg.substr(0, 300);
  EXPECT_NE(svg.find("<image id=\"image1\" width=\"300\" height=\"200\""), std::string::npos);
  EXPECT_NE(svg.find("<symbol overflow=\"visible\" id=\"glyph"), std::string::npos) << "glyphs";
  EXPECT_NE(svg.find("<title>J, objective (s) against planner.ray.horizon</title>"),
            std::string::npos);
  EXPECT_NE(svg.find("<desc>x: planner.ray.horizon; y: J, objective (s); ray; dp; case; x ticks: "
                     "10, 15, 20, 25, 30; y ticks: 20, 22, 24, 26, 28, 30</desc>"),
            std::string::npos);
  // Without a raster there is no image at all: the batch plots are pure vector.
  Figure plain;
  plain.labels = someLabels();
  plain.labels.title = "Coverage & overlap <per pass>";
  plain.grid = true;
  plain.overlays.push_back({Overlay::Kind::kLine, {{10, 21}, {20, 29}}, {0, 114, 178}, 2.0});
  const std::string vector = figureSvg(plain);
  EXPECT_EQ(vector.find("<image"), std::string::npos);
  EXPECT_NE(vector.find("<title>Coverage &amp; overlap &lt;per pass&gt;</title>"),
            std::string::npos);
}

TEST(Figure, OverlaysAreDrawnInAxisUnitsAndClippedToTheArea) {
  Figure figure;
  figure.labels = someLabels();
  figure.labels.legend.clear();
  const Rgb blue{0, 114, 178}, orange{213, 94, 0};
  // A horizontal line at y = 25 (the middle) from x = 9.2 to 50 (past the right edge), and a
  // cross at (20, 22.5).
  figure.overlays.push_back({Overlay::Kind::kLine, {{9.2, 25}, {50, 25}}, blue, 3.0});
  figure.overlays.push_back({Overlay::Kind::kCrosses, {{20, 22.5}}, orange, 2.0});
  const FigureLayout f = layoutFigure(figure);
  const RgbImage image = renderFigure(figure);
  const int mid = f.area_y + f.area_height / 2;
  EXPECT_EQ(image.at(f.area_x + 10, mid), blue);
  EXPECT_EQ(image.at(f.area_x + f.area_width - 3, mid), blue);
  EXPECT_NE(image.at(f.area_x + f.area_width + 5, mid), blue) << "clipped";
  const int cx = f.area_x + static_cast<int>((20 - 9.2) / 21.6 * f.area_width);
  const int cy = f.area_y + static_cast<int>(0.75 * f.area_height);
  EXPECT_EQ(image.at(cx, cy), orange) << "the cross's centre";
}

TEST(Figure, DegenerateRangesAndRastersStillGiveTicksAndNoCrash) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const double big = std::numeric_limits<double>::max();
  for (const auto& [a, b] :
       std::vector<std::pair<double, double>>{{25.46247875282346, 25.462478752823472},
                                              {3, 3},
                                              {0, 0},
                                              {nan, nan},
                                              {nan, 2},
                                              {-inf, inf},
                                              {-big, big},
                                              {1e300, 1e300},
                                              {5, -5}}) {
    SCOPED_TRACE(::testing::Message() << a << " " << b);
    Figure figure;
    figure.raster = RgbImage::filled(200, 100, kWhite);
    figure.labels = someLabels();
    figure.labels.x0 = figure.labels.y0 = a;
    figure.labels.x1 = figure.labels.y1 = b;
    const FigureLayout f = layoutFigure(figure);
    const RgbImage image = renderFigure(figure);
    EXPECT_LT(image.width, 1200) << "tick values stay short";
    EXPECT_GT(darkPixels(image, 0, f.area_y, f.area_x - 8, f.area_y + 100), 20) << "y ticks";
    EXPECT_GT(darkPixels(image, 0, f.area_y + 102, image.width, f.area_y + 135), 20) << "x ticks";
    const std::string svg = figureSvg(figure);
    EXPECT_EQ(svg.find("nan"), std::string::npos);
    EXPECT_EQ(svg.find("inf"), std::string::npos);
  }
  // Categories, a colour bar, no legend, long text, no raster.
  Figure figure;
  figure.labels = someLabels();
  figure.labels.categories = {"ray", "dp", "a very long category name that cannot fit", ""};
  figure.labels.legend.clear();
  figure.labels.colour_bar = "f";
  figure.labels.title = std::string(500, 'x');
  EXPECT_NO_THROW(renderFigure(figure));
  EXPECT_NO_THROW(figureSvg(figure));
  figure.raster = RgbImage::filled(200, 100, kWhite);
  figure.raster.rgb.pop_back();
  EXPECT_THROW(renderFigure(figure), scanplan::InputError);
}

// ---- drawViewGrid: rows of captioned views --------------------------------------------------

// A view of one flat colour with a distinct pixel in a corner (so a shifted copy shows).
RgbImage solidView(int w, int h, Rgb fill, Rgb corner) {
  RgbImage v = RgbImage::filled(w, h, fill);
  v.set(w - 1, h - 1, corner);
  return v;
}

TEST(ViewGrid, ViewsAreCopiedWholeUnderTheirCaptionsWithTitlesScalesAndLegend) {
  constexpr int kCaption = 20;  // the caption band over each view (one line of text)
  ViewGrid grid;
  grid.captions = {"iso", "top", "front"};
  grid.rows.resize(2);
  const Rgb corner{255, 0, 0};
  for (int r = 0; r < 2; ++r) {
    grid.rows[static_cast<std::size_t>(r)].title = r == 0 ? "Points by time:" : "Coverage:";
    for (int c = 0; c < 3; ++c) {
      const auto shade = static_cast<std::uint8_t>(200 - 30 * c - 10 * r);
      grid.rows[static_cast<std::size_t>(r)].views.push_back(
          solidView(300, 80, {shade, shade, 255}, corner));
    }
  }
  grid.rows[0].scale = {{0, 0, 255}, {0, 255, 0}};
  grid.rows[0].scale_from = "0 s";
  grid.rows[0].scale_to = "9 s";
  grid.legend = {{{10, 20, 30}, "not covered"}};
  const RgbImage image = drawViewGrid(grid);
  EXPECT_EQ(image.width, 900);
  // Find each view by its fill colour's first pixel, then check it whole.
  int next_y = 0;
  for (int r = 0; r < 2; ++r) {
    for (int c = 0; c < 3; ++c) {
      const auto shade = static_cast<std::uint8_t>(200 - 30 * c - 10 * r);
      int top = -1;
      for (int y = next_y; y < image.height && top < 0; ++y) {
        const Rgb p = image.at(c * 300, y);
        if (p.r == shade && p.g == shade && p.b == 255) top = y;
      }
      ASSERT_GE(top, 0) << "view " << r << "," << c;
      int wrong = 0;
      for (int y = 0; y < 80; ++y) {
        for (int x = 0; x < 300; ++x) {
          const Rgb want = x == 299 && y == 79 ? corner : Rgb{shade, shade, 255};
          const Rgb got = image.at(c * 300 + x, top + y);
          wrong += got.r != want.r || got.g != want.g || got.b != want.b;
        }
      }
      EXPECT_EQ(wrong, 0) << "view " << r << "," << c;
      // Its caption (grey text) is drawn in the band just above it, within its column.
      int caption = 0;
      for (int y = top - kCaption; y < top; ++y) {
        for (int x = c * 300; x < c * 300 + 300; ++x) caption += image.at(x, y).r < 160;
      }
      EXPECT_GT(caption, 10) << "caption of view " << r << "," << c;
      if (c == 2) next_y = top + 80;
    }
  }
  // The first row's title and its colour scale (both ends' colours drawn), and the legend.
  EXPECT_GT(darkPixels(image, 0, 0, 120, kCaption + 10), 20) << "title";
  int green = 0, blue = 0, swatch = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const Rgb p = image.at(x, y);
      green += p.r == 0 && p.g > 230 && p.b < 25;
      blue += p.r == 0 && p.g < 25 && p.b > 230;
      swatch += p.r == 10 && p.g == 20 && p.b == 30;
    }
  }
  EXPECT_GT(green, 20) << "the colour scale's end";
  EXPECT_GT(blue, 20) << "the colour scale's start";
  EXPECT_GE(swatch, 100) << "the legend's swatch";
}

}  // namespace
