#include "cli/plot/bitmap_font.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <utility>

#include <fmt/format.h>

#include "kinematics/error.h"

namespace scanplan::cli {
namespace {

using Glyph = std::array<std::uint8_t, kGlyphWidth>;

// Printable ASCII 0x20 … 0x7e, 5 columns each, left to right; bit 0 is the top row, bit 6 the
// baseline row, bit 7 the descender row (g, j, p, q, y, _).
constexpr std::array<Glyph, 95> kAscii{{
    {0x00, 0x00, 0x00, 0x00, 0x00},  // ' '
    {0x00, 0x00, 0x5f, 0x00, 0x00},  // !
    {0x00, 0x07, 0x00, 0x07, 0x00},  // "
    {0x14, 0x7f, 0x14, 0x7f, 0x14},  // #
    {0x24, 0x2a, 0x7f, 0x2a, 0x12},  // $
    {0x23, 0x13, 0x08, 0x64, 0x62},  // %
    {0x36, 0x49, 0x55, 0x22, 0x50},  // &
    {0x00, 0x05, 0x03, 0x00, 0x00},  // '
    {0x00, 0x1c, 0x22, 0x41, 0x00},  // (
    {0x00, 0x41, 0x22, 0x1c, 0x00},  // )
    {0x14, 0x08, 0x3e, 0x08, 0x14},  // *
    {0x08, 0x08, 0x3e, 0x08, 0x08},  // +
    {0x00, 0xa0, 0x60, 0x00, 0x00},  // ,
    {0x08, 0x08, 0x08, 0x08, 0x08},  // -
    {0x00, 0x60, 0x60, 0x00, 0x00},  // .
    {0x20, 0x10, 0x08, 0x04, 0x02},  // /
    {0x3e, 0x51, 0x49, 0x45, 0x3e},  // 0
    {0x00, 0x42, 0x7f, 0x40, 0x00},  // 1
    {0x42, 0x61, 0x51, 0x49, 0x46},  // 2
    {0x21, 0x41, 0x45, 0x4b, 0x31},  // 3
    {0x18, 0x14, 0x12, 0x7f, 0x10},  // 4
    {0x27, 0x45, 0x45, 0x45, 0x39},  // 5
    {0x3c, 0x4a, 0x49, 0x49, 0x30},  // 6
    {0x01, 0x71, 0x09, 0x05, 0x03},  // 7
    {0x36, 0x49, 0x49, 0x49, 0x36},  // 8
    {0x06, 0x49, 0x49, 0x29, 0x1e},  // 9
    {0x00, 0x36, 0x36, 0x00, 0x00},  // :
    {0x00, 0xb6, 0x76, 0x00, 0x00},  // ;
    {0x08, 0x14, 0x22, 0x41, 0x00},  // <
    {0x14, 0x14, 0x14, 0x14, 0x14},  // =
    {0x00, 0x41, 0x22, 0x14, 0x08},  // >
    {0x02, 0x01, 0x51, 0x09, 0x06},  // ?
    {0x32, 0x49, 0x79, 0x41, 0x3e},  // @
    {0x7e, 0x11, 0x11, 0x11, 0x7e},  // A
    {0x7f, 0x49, 0x49, 0x49, 0x36},  // B
    {0x3e, 0x41, 0x41, 0x41, 0x22},  // C
    {0x7f, 0x41, 0x41, 0x22, 0x1c},  // D
    {0x7f, 0x49, 0x49, 0x49, 0x41},  // E
    {0x7f, 0x09, 0x09, 0x09, 0x01},  // F
    {0x3e, 0x41, 0x49, 0x49, 0x7a},  // G
    {0x7f, 0x08, 0x08, 0x08, 0x7f},  // H
    {0x00, 0x41, 0x7f, 0x41, 0x00},  // I
    {0x20, 0x40, 0x41, 0x3f, 0x01},  // J
    {0x7f, 0x08, 0x14, 0x22, 0x41},  // K
    {0x7f, 0x40, 0x40, 0x40, 0x40},  // L
    {0x7f, 0x02, 0x0c, 0x02, 0x7f},  // M
    {0x7f, 0x04, 0x08, 0x10, 0x7f},  // N
    {0x3e, 0x41, 0x41, 0x41, 0x3e},  // O
    {0x7f, 0x09, 0x09, 0x09, 0x06},  // P
    {0x3e, 0x41, 0x51, 0x21, 0x5e},  // Q
    {0x7f, 0x09, 0x19, 0x29, 0x46},  // R
    {0x46, 0x49, 0x49, 0x49, 0x31},  // S
    {0x01, 0x01, 0x7f, 0x01, 0x01},  // T
    {0x3f, 0x40, 0x40, 0x40, 0x3f},  // U
    {0x1f, 0x20, 0x40, 0x20, 0x1f},  // V
    {0x3f, 0x40, 0x38, 0x40, 0x3f},  // W
    {0x63, 0x14, 0x08, 0x14, 0x63},  // X
    {0x07, 0x08, 0x70, 0x08, 0x07},  // Y
    {0x61, 0x51, 0x49, 0x45, 0x43},  // Z
    {0x00, 0x7f, 0x41, 0x41, 0x00},  // [
    {0x02, 0x04, 0x08, 0x10, 0x20},  // backslash
    {0x00, 0x41, 0x41, 0x7f, 0x00},  // ]
    {0x04, 0x02, 0x01, 0x02, 0x04},  // ^
    {0x80, 0x80, 0x80, 0x80, 0x80},  // _
    {0x00, 0x01, 0x02, 0x04, 0x00},  // `
    {0x20, 0x54, 0x54, 0x54, 0x78},  // a
    {0x7f, 0x48, 0x44, 0x44, 0x38},  // b
    {0x38, 0x44, 0x44, 0x44, 0x20},  // c
    {0x38, 0x44, 0x44, 0x48, 0x7f},  // d
    {0x38, 0x54, 0x54, 0x54, 0x18},  // e
    {0x08, 0x7e, 0x09, 0x01, 0x02},  // f
    {0x18, 0xa4, 0xa4, 0xa4, 0x7c},  // g
    {0x7f, 0x08, 0x04, 0x04, 0x78},  // h
    {0x00, 0x44, 0x7d, 0x40, 0x00},  // i
    {0x40, 0x80, 0x84, 0x7d, 0x00},  // j
    {0x7f, 0x10, 0x28, 0x44, 0x00},  // k
    {0x00, 0x41, 0x7f, 0x40, 0x00},  // l
    {0x7c, 0x04, 0x18, 0x04, 0x78},  // m
    {0x7c, 0x08, 0x04, 0x04, 0x78},  // n
    {0x38, 0x44, 0x44, 0x44, 0x38},  // o
    {0xfc, 0x24, 0x24, 0x24, 0x18},  // p
    {0x18, 0x24, 0x24, 0x18, 0xfc},  // q
    {0x7c, 0x08, 0x04, 0x04, 0x08},  // r
    {0x48, 0x54, 0x54, 0x54, 0x20},  // s
    {0x04, 0x3f, 0x44, 0x40, 0x20},  // t
    {0x3c, 0x40, 0x40, 0x20, 0x7c},  // u
    {0x1c, 0x20, 0x40, 0x20, 0x1c},  // v
    {0x3c, 0x40, 0x30, 0x40, 0x3c},  // w
    {0x44, 0x28, 0x10, 0x28, 0x44},  // x
    {0x1c, 0xa0, 0xa0, 0xa0, 0x7c},  // y
    {0x44, 0x64, 0x54, 0x4c, 0x44},  // z
    {0x00, 0x08, 0x36, 0x41, 0x00},  // {
    {0x00, 0x00, 0x7f, 0x00, 0x00},  // |
    {0x00, 0x41, 0x36, 0x08, 0x00},  // }
    {0x02, 0x01, 0x02, 0x04, 0x02},  // ~
}};
constexpr Glyph kDegree{0x06, 0x09, 0x09, 0x06, 0x00};   // °
constexpr Glyph kSquared{0x19, 0x15, 0x12, 0x00, 0x00};  // ²

// The glyphs of a UTF-8 string, one per character.
template <typename F>
void forEachGlyph(std::string_view text, F&& f) {
  const Glyph& unknown = kAscii['?' - 0x20];
  for (std::size_t i = 0; i < text.size();) {
    const auto b = static_cast<unsigned char>(text[i]);
    if (b < 0x80) {
      f(b >= 0x20 && b <= 0x7e ? kAscii[b - 0x20] : unknown);
      ++i;
      continue;
    }
    // A multi-byte sequence: its length from the lead byte, its code point from all bytes.
    const std::size_t length = b >= 0xf0 ? 4 : b >= 0xe0 ? 3 : b >= 0xc0 ? 2 : 1;
    char32_t code = length == 1 ? 0u : static_cast<char32_t>(b & (0x7fu >> length));
    std::size_t n = 1;
    for (; n < length && i + n < text.size(); ++n) {
      const auto c = static_cast<unsigned char>(text[i + n]);
      if ((c & 0xc0) != 0x80) break;
      code = (code << 6) | (c & 0x3f);
    }
    f(n == length && code == 0xb0 ? kDegree : n == length && code == 0xb2 ? kSquared : unknown);
    i += n;
  }
}

void fillSquare(RgbImage& image, int x, int y, int size, Rgb colour) {
  const int x0 = std::max(x, 0), y0 = std::max(y, 0);
  const int x1 = std::min(x + size, image.width), y1 = std::min(y + size, image.height);
  for (int yy = y0; yy < y1; ++yy) {
    for (int xx = x0; xx < x1; ++xx) image.set(xx, yy, colour);
  }
}

}  // namespace

int drawText(RgbImage& image, int x, int y, std::string_view text, Rgb colour, int scale) {
  scale = std::max(scale, 1);
  int cx = x;
  forEachGlyph(text, [&](const Glyph& g) {
    for (int col = 0; col < kGlyphWidth; ++col) {
      for (int row = 0; row < kGlyphHeight; ++row) {
        if ((g[static_cast<std::size_t>(col)] >> row) & 1) {
          fillSquare(image, cx + col * scale, y + row * scale, scale, colour);
        }
      }
    }
    cx += kCellWidth * scale;
  });
  return cx;
}

int drawTextUp(RgbImage& image, int x, int y, std::string_view text, Rgb colour, int scale) {
  scale = std::max(scale, 1);
  int cy = y + 1;  // the text runs upwards from row y: along the text is −y
  forEachGlyph(text, [&](const Glyph& g) {
    for (int col = 0; col < kGlyphWidth; ++col) {
      for (int row = 0; row < kGlyphHeight; ++row) {
        if ((g[static_cast<std::size_t>(col)] >> row) & 1) {
          fillSquare(image, x + row * scale, cy - (col + 1) * scale, scale, colour);
        }
      }
    }
    cy -= kCellWidth * scale;
  });
  return cy - 1;
}

int textWidth(std::string_view text, int scale) {
  scale = std::max(scale, 1);
  int cells = 0;
  forEachGlyph(text, [&](const Glyph&) { ++cells; });
  return cells == 0 ? 0 : (cells * kCellWidth - 1) * scale;
}

std::string fitText(const std::string& text, int width, int scale) {
  if (textWidth(text, scale) <= width) return text;
  std::string cut = text;
  while (!cut.empty() && textWidth(cut + "..", scale) > width) cut.pop_back();
  // Never end inside a UTF-8 sequence.
  while (!cut.empty() && (static_cast<unsigned char>(cut.back()) & 0xc0) == 0x80) cut.pop_back();
  if (!cut.empty() && static_cast<unsigned char>(cut.back()) >= 0xc0) cut.pop_back();
  return cut + "..";
}

LabelledFigure labelFigure(const RgbImage& raster, const FigureLabels& text) {
  constexpr int kScale = 2, kTick = 6, kPad = 12, kMark = 20;
  constexpr Rgb kBlack{0, 0, 0}, kWhite{255, 255, 255};
  if (raster.width > 0 && raster.height > 0 &&
      raster.rgb.size() !=
          3 * static_cast<std::size_t>(raster.width) * static_cast<std::size_t>(raster.height)) {
    throw InputError(fmt::format("figure: raster {} × {} with {} bytes: expected 3 per pixel",
                                 raster.width, raster.height, raster.rgb.size()));
  }
  const RgbImage area =
      raster.width > 0 && raster.height > 0 ? raster : RgbImage::filled(1, 1, kWhite);
  const auto range = [](double a, double b) {
    return flatRange(a, b) || !std::isfinite(b - a) ? axisRange(a, b, 0.0) : std::pair{a, b};
  };
  const std::pair<double, double> xr = range(text.x0, text.x1), yr = range(text.y0, text.y1);
  const double x0 = xr.first, x1 = xr.second, y0 = yr.first, y1 = yr.second;
  const int line = textHeight(kScale);

  std::vector<std::pair<double, std::string>> y_labels, x_labels;
  const Ticks y_ticks = niceTicks(y0, y1);
  for (const double v : y_ticks.values) y_labels.emplace_back(v, tickLabel(y_ticks, v));
  if (!text.y_marks.empty()) {
    y_labels.clear();
    for (const auto& [v, s] : text.y_marks) {
      if (std::isfinite(v) && v >= std::min(y0, y1) && v <= std::max(y0, y1)) {
        y_labels.emplace_back(v, s);
      }
    }
  }
  if (text.categories.empty()) {
    const Ticks x_ticks = niceTicks(x0, x1);
    for (const double v : x_ticks.values) x_labels.emplace_back(v, tickLabel(x_ticks, v));
  } else {
    for (std::size_t i = 0; i < text.categories.size(); ++i) {
      x_labels.emplace_back(static_cast<double>(i), text.categories[i]);
    }
  }

  // The colour bar's labels, and the legend column's width and height.
  const std::vector<std::pair<double, std::string>> bar_labels{
      {1.0, "1 free"}, {0.5, "0.5"}, {0.0, "0 forbidden"}};
  const bool bar = !text.colour_bar.empty();
  int y_label_width = 0, legend_width = 0, legend_height = 0;
  for (const auto& [v, s] : y_labels) y_label_width = std::max(y_label_width, textWidth(s, kScale));
  for (const LegendEntry& e : text.legend) {
    const int indent = e.mark == LegendEntry::Mark::kNone ? 0 : kMark + 8;
    legend_width = std::max(legend_width, indent + textWidth(e.text, kScale));
    legend_height += e.space_before + line + 10;
  }
  const int bar_height = std::clamp(area.height / 2, 80, 240);
  if (bar) {
    legend_width = std::max(legend_width, textWidth(text.colour_bar, kScale));
    for (const auto& [v, s] : bar_labels) {
      legend_width = std::max(legend_width, kMark + kTick + 6 + textWidth(s, kScale));
    }
    legend_height += (text.legend.empty() ? 0 : 10) + line + 10 + bar_height + line / 2;
  }
  const bool has_legend = !text.legend.empty() || bar;
  const int left = kPad + line + kPad + y_label_width + kTick + 6;
  const int top = kPad + line + kPad;
  const int right = has_legend ? kPad + legend_width + 2 * kPad : 2 * kPad;
  const int bottom = kTick + 6 + line + kPad + line + kPad;
  const int pw = area.width, ph = area.height;
  RgbImage image = RgbImage::filled(
      left + pw + right, std::max(top + ph + bottom, top + legend_height + kPad), kWhite);
  for (int y = 0; y < ph; ++y) {
    for (int x = 0; x < pw; ++x) image.set(left + x, top + y, area.at(x, y));
  }
  // Frame, just outside the raster.
  drawLine(image, left - 0.5, top - 0.5, left + pw + 0.5, top - 0.5, kBlack, 1);
  drawLine(image, left - 0.5, top + ph + 0.5, left + pw + 0.5, top + ph + 0.5, kBlack, 1);
  drawLine(image, left - 0.5, top - 0.5, left - 0.5, top + ph + 0.5, kBlack, 1);
  drawLine(image, left + pw + 0.5, top - 0.5, left + pw + 0.5, top + ph + 0.5, kBlack, 1);
  const auto px = [&](double v) { return left + (v - x0) / (x1 - x0) * pw; };
  const auto py = [&](double v) { return top + (y1 - v) / (y1 - y0) * ph; };
  // Title, centred over the plot (cut if it would run past the image).
  const std::string title = fitText(text.title, image.width - 2 * kPad, kScale);
  drawText(image,
           std::clamp(left + (pw - textWidth(title, kScale)) / 2, kPad,
                      std::max(kPad, image.width - kPad - textWidth(title, kScale))),
           kPad, title, kBlack, kScale);
  // y ticks and values.
  for (const auto& [v, s] : y_labels) {
    const double y = py(v);
    drawLine(image, left - kTick, y, left - 1, y, kBlack, 1);  // outside the raster
    drawText(image, left - kTick - 6 - textWidth(s, kScale),
             static_cast<int>(std::lround(y)) - line / 2 + 1, s, kBlack, kScale);
  }
  // x ticks and values: every k-th value when they would overlap; categories cut to fit.
  double spacing = pw;
  for (std::size_t i = 1; i < x_labels.size(); ++i) {
    spacing = std::min(spacing, std::abs(px(x_labels[i].first) - px(x_labels[i - 1].first)));
  }
  int widest = 0;
  for (const auto& [v, s] : x_labels) widest = std::max(widest, textWidth(s, kScale));
  std::size_t every = 1;
  if (text.categories.empty()) {
    while (every < x_labels.size() && spacing * static_cast<double>(every) < widest + 12) ++every;
  }
  for (std::size_t i = 0; i < x_labels.size(); ++i) {
    const double x = px(x_labels[i].first);
    drawLine(image, x, top + ph, x, top + ph + kTick, kBlack, 1);
    if (i % every) continue;
    const std::string s = text.categories.empty()
                              ? x_labels[i].second
                              : fitText(x_labels[i].second, static_cast<int>(spacing) - 8, kScale);
    const int w = textWidth(s, kScale);
    drawText(image,
             std::clamp(static_cast<int>(std::lround(x)) - w / 2, 0, std::max(0, image.width - w)),
             top + ph + kTick + 6, s, kBlack, kScale);
  }
  // Axis titles.
  const std::string x_label = fitText(text.x_label, image.width - 2 * kPad, kScale);
  drawText(image, std::max(kPad, left + (pw - textWidth(x_label, kScale)) / 2),
           top + ph + kTick + 6 + line + kPad, x_label, kBlack, kScale);
  const std::string y_label = fitText(text.y_label, image.height - 2 * kPad, kScale);
  drawTextUp(image, kPad,
             std::min(image.height - kPad, top + (ph + textWidth(y_label, kScale)) / 2), y_label,
             kBlack, kScale);
  // Legend: a mark and a text per entry, then the colour bar.
  const int lx = left + pw + 2 * kPad;
  int ly = top;
  for (const LegendEntry& e : text.legend) {
    ly += e.space_before;
    switch (e.mark) {
      case LegendEntry::Mark::kSwatch:
        for (int y = 0; y < line; ++y) {
          for (int x = 0; x < kMark; ++x) {
            const bool edge = x == 0 || y == 0 || x == kMark - 1 || y == line - 1;
            image.set(lx + x, ly + y, edge ? Rgb{90, 90, 90} : e.colour);
          }
        }
        break;
      case LegendEntry::Mark::kLine:
        drawLine(image, lx, ly + line / 2, lx + kMark, ly + line / 2, e.colour, 3);
        break;
      case LegendEntry::Mark::kCross:
        drawLine(image, lx + 6, ly + 4, lx + 12, ly + 10, e.colour, 2);
        drawLine(image, lx + 6, ly + 10, lx + 12, ly + 4, e.colour, 2);
        break;
      case LegendEntry::Mark::kNone:
        break;
    }
    drawText(image, e.mark == LegendEntry::Mark::kNone ? lx : lx + kMark + 8, ly, e.text,
             e.text_colour, kScale);
    ly += line + 10;
  }
  if (bar) {
    if (!text.legend.empty()) ly += 10;
    drawText(image, lx, ly, text.colour_bar, kBlack, kScale);
    ly += line + 10;
    for (int y = 0; y < bar_height; ++y) {
      const Rgb c = grey(1.0 - static_cast<double>(y) / std::max(bar_height - 1, 1));
      for (int x = 0; x < kMark; ++x) image.set(lx + x, ly + y, c);
    }
    drawLine(image, lx - 0.5, ly - 0.5, lx + kMark + 0.5, ly - 0.5, kBlack, 1);
    drawLine(image, lx - 0.5, ly + bar_height + 0.5, lx + kMark + 0.5, ly + bar_height + 0.5,
             kBlack, 1);
    drawLine(image, lx - 0.5, ly - 0.5, lx - 0.5, ly + bar_height + 0.5, kBlack, 1);
    drawLine(image, lx + kMark + 0.5, ly - 0.5, lx + kMark + 0.5, ly + bar_height + 0.5, kBlack, 1);
    for (const auto& [v, s] : bar_labels) {
      const double y = ly + (1.0 - v) * (bar_height - 1) + 0.5;
      drawLine(image, lx + kMark, y, lx + kMark + kTick, y, kBlack, 1);
      drawText(image, lx + kMark + kTick + 6, static_cast<int>(std::lround(y)) - line / 2 + 1, s,
               kBlack, kScale);
    }
  }
  return {std::move(image), left, top};
}

}  // namespace scanplan::cli
