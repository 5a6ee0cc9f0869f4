// The built-in bitmap font that labels the PNG plots: text marks pixels, only inside its box,
// and different text gives different pixels.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "cli/plot/bitmap_font.h"
#include "cli/plot/image_io.h"
#include "kinematics/error.h"
#include "tests/image_support.h"

namespace {

using namespace scanplan::cli;

constexpr Rgb kWhite{255, 255, 255}, kInk{200, 0, 0};

struct Box {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // [x0, x1) × [y0, y1)
};

// The inked pixels, and whether any lies outside `box`.
std::vector<int> inked(const RgbImage& image, const Box& box, bool& outside) {
  std::vector<int> pixels;
  outside = false;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      if (image.at(x, y) == kWhite) continue;
      pixels.push_back(y * image.width + x);
      outside = outside || x < box.x0 || x >= box.x1 || y < box.y0 || y >= box.y1;
    }
  }
  return pixels;
}

std::vector<int> render(const std::string& text, int scale, bool& outside) {
  RgbImage image = RgbImage::filled(400, 60, kWhite);
  const int end = drawText(image, 10, 20, text, kInk, scale);
  // The next cell starts one blank column after the last glyph.
  EXPECT_EQ(end, 10 + (text.empty() ? 0 : textWidth(text, scale) + scale)) << text;
  return inked(image, {10, 20, 10 + textWidth(text, scale), 20 + textHeight(scale)}, outside);
}

TEST(BitmapFont, TextMarksPixelsInsideItsBox) {
  for (const int scale : {1, 2, 3}) {
    for (const std::string text :
         {"J (s) against planner.ray.horizon", "0123456789", "gjpqy_", "|", "(not set)"}) {
      bool outside = true;
      const std::vector<int> pixels = render(text, scale, outside);
      EXPECT_FALSE(pixels.empty()) << text << " at scale " << scale;
      EXPECT_FALSE(outside) << text << " at scale " << scale << " drew outside its box";
    }
  }
  EXPECT_EQ(textWidth("", 2), 0);
  EXPECT_EQ(textWidth("ab", 2), (2 * kCellWidth - 1) * 2);
  EXPECT_EQ(textHeight(3), kGlyphHeight * 3);
  bool outside = false;
  EXPECT_TRUE(render("   ", 2, outside).empty()) << "spaces draw nothing";
}

TEST(BitmapFont, DifferentTextGivesDifferentPixels) {
  bool outside = false;
  const std::string texts[] = {"ray", "dp",  "ompl", "J_s", "10", "15",
                               "30",  "1.0", "l.0",  "O",   "0"};
  std::vector<std::vector<int>> drawn;
  for (const std::string& t : texts) drawn.push_back(render(t, 2, outside));
  for (std::size_t i = 0; i < drawn.size(); ++i) {
    for (std::size_t j = i + 1; j < drawn.size(); ++j) {
      EXPECT_NE(drawn[i], drawn[j]) << texts[i] << " and " << texts[j] << " look the same";
    }
  }
  // Every printable ASCII character has its own glyph.
  std::vector<std::vector<int>> glyphs;
  for (char c = 0x21; c < 0x7f; ++c) glyphs.push_back(render(std::string(1, c), 1, outside));
  for (std::size_t i = 0; i < glyphs.size(); ++i) {
    EXPECT_FALSE(glyphs[i].empty()) << static_cast<char>(0x21 + i);
    for (std::size_t j = i + 1; j < glyphs.size(); ++j) {
      EXPECT_NE(glyphs[i], glyphs[j])
          << static_cast<char>(0x21 + i) << " and " << static_cast<char>(0x21 + j);
    }
  }
}

TEST(BitmapFont, NonAsciiIsOneCellAndDegreeAndSquaredHaveGlyphs) {
  bool outside = false;
  const std::vector<int> question = render("?", 2, outside);
  EXPECT_EQ(textWidth("deg/s\u00b2", 2), textWidth("deg/s2", 2)) << "one cell per character";
  EXPECT_NE(render("\u00b0", 2, outside), question);
  EXPECT_NE(render("\u00b2", 2, outside), question);
  EXPECT_NE(render("\u00b0", 2, outside), render("\u00b2", 2, outside));
  EXPECT_EQ(render("\u03c9", 2, outside), question) << "ω has no glyph: drawn as '?'";
  EXPECT_EQ(render("\t", 2, outside), question);
}

TEST(BitmapFont, UpwardTextIsTheTextTurnedAnticlockwise) {
  const std::string text = "min f (s)";
  const int scale = 2, w = textWidth(text, scale), h = textHeight(scale);
  RgbImage across = RgbImage::filled(w, h, kWhite);
  drawText(across, 0, 0, text, kInk, scale);
  RgbImage up = RgbImage::filled(h + 20, w + 20, kWhite);
  drawTextUp(up, 10, w + 9, text, kInk, scale);  // bottom-left corner at (10, w + 9)
  bool outside = true;
  EXPECT_FALSE(inked(up, {10, 10, 10 + h, 10 + w}, outside).empty());
  EXPECT_FALSE(outside);
  // Pixel (x, y) of the horizontal text is pixel (10 + y, w + 9 − x) of the upward one.
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      ASSERT_EQ(across.at(x, y), up.at(10 + y, w + 9 - x)) << x << ", " << y;
    }
  }
}

TEST(BitmapFont, TextIsClippedToTheImage) {
  RgbImage image = RgbImage::filled(30, 10, kWhite);
  drawText(image, -7, -5, "clipped at every edge", kInk, 3);
  drawTextUp(image, 25, 4, "and upwards", kInk, 2);
  bool outside = true;
  EXPECT_FALSE(inked(image, {0, 0, 30, 10}, outside).empty());
}

TEST(BitmapFont, FitTextCutsWithDotsAndNeverInsideAUtf8Character) {
  EXPECT_EQ(fitText("short", 200, 2), "short");
  const std::string cut = fitText("a rather long axis title", textWidth("a rather", 2), 2);
  EXPECT_TRUE(cut.ends_with("..")) << cut;
  EXPECT_LE(textWidth(cut, 2), textWidth("a rather", 2));
  const std::string degrees =
      fitText("angle \u00b0\u00b0\u00b0\u00b0", textWidth("angle \u00b0", 2), 2);
  for (const char c : degrees.substr(0, degrees.size() - 2)) {
    EXPECT_NE(static_cast<unsigned char>(c), 0xc2) << "a lead byte without its continuation";
  }
}

// ---- labelFigure: a data raster framed with title, ticks, axis titles and legend -------------

using scanplan::test::darkPixels;

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

TEST(LabelFigure, RasterIsCopiedExactlyAndTextFillsTheMargins) {
  RgbImage raster = RgbImage::filled(300, 200, {250, 250, 250});
  for (int y = 0; y < 200; ++y) {
    for (int x = 0; x < 300; ++x) {
      raster.set(x, y, {static_cast<std::uint8_t>(x % 251), static_cast<std::uint8_t>(y), 77});
    }
  }
  const LabelledFigure f = labelFigure(raster, someLabels());
  const RgbImage& image = f.image;
  ASSERT_GT(f.area_x, 30);
  ASSERT_GT(f.area_y, 20);
  ASSERT_GT(image.width, f.area_x + 300 + 60);
  ASSERT_GT(image.height, f.area_y + 200 + 40);
  for (int y = 0; y < 200; ++y) {
    for (int x = 0; x < 300; ++x) {
      ASSERT_EQ(image.at(f.area_x + x, f.area_y + y), raster.at(x, y)) << x << ", " << y;
    }
  }
  EXPECT_GT(darkPixels(image, 0, 0, image.width, f.area_y - 2), 200) << "title";
  EXPECT_GT(darkPixels(image, 0, f.area_y, f.area_x - 8, f.area_y + 200), 200) << "y values, title";
  EXPECT_GT(darkPixels(image, 0, f.area_y + 202, image.width, image.height), 200)
      << "x values, title";
  EXPECT_GT(darkPixels(image, f.area_x + 302, 0, image.width, image.height), 50) << "legend text";
  const auto has = [&](Rgb colour) {
    for (int y = 0; y < image.height; ++y) {
      for (int x = f.area_x + 302; x < image.width; ++x) {
        if (image.at(x, y) == colour) return true;
      }
    }
    return false;
  };
  EXPECT_TRUE(has({213, 94, 0})) << "swatch";
  EXPECT_TRUE(has({0, 114, 178})) << "line";
  // Deterministic.
  EXPECT_EQ(labelFigure(raster, someLabels()).image.rgb, image.rgb);
}

TEST(LabelFigure, DegenerateRangesAndRastersStillGiveTicksAndNoCrash) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const double big = std::numeric_limits<double>::max();
  const RgbImage raster = RgbImage::filled(200, 100, kWhite);
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
    FigureLabels labels = someLabels();
    labels.x0 = labels.y0 = a;
    labels.x1 = labels.y1 = b;
    const LabelledFigure f = labelFigure(raster, labels);
    EXPECT_LT(f.image.width, 1200) << "tick values stay short";
    EXPECT_GT(darkPixels(f.image, 0, f.area_y, f.area_x - 8, f.area_y + 100), 30)
        << "y tick values";
    EXPECT_GT(darkPixels(f.image, 0, f.area_y + 102, f.image.width, f.area_y + 130), 30)
        << "x tick values";
  }
  // Categories, a colour bar, no legend, long text, an empty raster.
  FigureLabels labels = someLabels();
  labels.categories = {"ray", "dp", "a very long category name that cannot fit", ""};
  labels.legend.clear();
  labels.colour_bar = "f";
  labels.title = std::string(500, 'x');
  EXPECT_NO_THROW(labelFigure(raster, labels));
  EXPECT_NO_THROW(labelFigure(RgbImage{}, labels));
  RgbImage broken = raster;
  broken.rgb.pop_back();
  EXPECT_THROW(labelFigure(broken, labels), scanplan::InputError);
}

// ---- drawViewGrid: rows of captioned views --------------------------------------------------

// A view of one flat colour with a distinct pixel in a corner (so a shifted copy shows).
RgbImage solidView(int w, int h, Rgb fill, Rgb corner) {
  RgbImage v = RgbImage::filled(w, h, fill);
  v.set(w - 1, h - 1, corner);
  return v;
}

TEST(ViewGrid, ViewsAreCopiedWholeUnderTheirCaptionsWithTitlesScalesAndLegend) {
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
  grid.rows[0].scale = {{0, 0, 0}, {0, 255, 0}};
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
      // Its caption is drawn in the band just above it, within its column.
      EXPECT_GT(darkPixels(image, c * 300, top - textHeight(), c * 300 + 300, top), 10)
          << "caption of view " << r << "," << c;
      if (c == 2) next_y = top + 80;
    }
  }
  // The first row's title and its colour scale (both scale colours drawn), and the legend.
  EXPECT_GT(darkPixels(image, 0, 0, 120, textHeight() + 12), 20) << "title";
  int green = 0, swatch = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const Rgb p = image.at(x, y);
      green += p.r == 0 && p.g == 255 && p.b == 0;
      swatch += p.r == 10 && p.g == 20 && p.b == 30;
    }
  }
  EXPECT_GT(green, 100) << "the colour scale";
  EXPECT_EQ(swatch, textHeight() * textHeight()) << "the legend's swatch";
}

}  // namespace
