#include <algorithm>

#include "cli/plot/canvas.h"
#include "cli/plot/figure.h"

namespace scanplan::cli {
namespace {

using detail::Align;
using detail::Canvas;
using detail::kCapHeight;

constexpr double kText = 15;
constexpr int kLine = 20, kPad = 10, kScaleWidth = 200;
constexpr Rgb kBlack{0, 0, 0}, kCaption{90, 90, 90};

double centredBaseline(double y) { return y + 0.5 * kCapHeight * kText; }

// The row's title and, when it fits after it, its colour scale between its end labels.
void drawRowTitle(Canvas& c, const ViewRow& row, int width, int y) {
  const std::string title = c.fitText(row.title, width - 2 * kPad, kText);
  c.text(kPad, centredBaseline(y + kLine / 2.0), title, kText, kBlack);
  double x = kPad + c.textWidth(title, kText);
  const double labels = c.textWidth(row.scale_from, kText) + c.textWidth(row.scale_to, kText);
  if (row.scale.empty() || x + 3 * kPad + kScaleWidth + labels > width) return;
  x += 2 * kPad;
  c.text(x, centredBaseline(y + kLine / 2.0), row.scale_from, kText, kBlack);
  x += c.textWidth(row.scale_from, kText) + 6;
  cairo_t* cr = c.context();
  cairo_pattern_t* ramp = cairo_pattern_create_linear(x, 0, x + kScaleWidth, 0);
  const std::size_t n = row.scale.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Rgb& s = row.scale[i];
    cairo_pattern_add_color_stop_rgb(
        ramp, n > 1 ? static_cast<double>(i) / static_cast<double>(n - 1) : 0.0, s.r / 255.0,
        s.g / 255.0, s.b / 255.0);
  }
  cairo_rectangle(cr, x, y + 2, kScaleWidth, kLine - 4);
  cairo_set_source(cr, ramp);
  cairo_fill(cr);
  cairo_pattern_destroy(ramp);
  c.text(x + kScaleWidth + 6, centredBaseline(y + kLine / 2.0), row.scale_to, kText, kBlack);
}

void drawLegendLine(Canvas& c, const std::vector<LegendEntry>& legend, int y) {
  double x = kPad;
  for (const LegendEntry& e : legend) {
    if (e.mark == LegendEntry::Mark::kSwatch) {
      c.fillRect(x, y + 2, kLine - 4, kLine - 4, e.colour);
      x += kLine + 2;
    } else if (e.mark == LegendEntry::Mark::kLine) {
      c.line(x, y + kLine / 2.0, x + 24, y + kLine / 2.0, e.colour, 3);
      x += 30;
    }
    c.text(x, centredBaseline(y + kLine / 2.0), e.text, kText, e.text_colour);
    x += c.textWidth(e.text, kText) + 2 * kPad;
  }
}

// The bar's title, then the bar across the width: segments in order, their labels inside
// where they fit (white on dark colours).
void drawBar(Canvas& c, const BreakdownBar& bar, int width, int y) {
  c.text(kPad, centredBaseline(y + kLine / 2.0), bar.title, kText, kBlack);
  const double x0 = kPad + c.textWidth(bar.title, kText) + kPad;
  const double w = std::max(0.0, width - kPad - x0);
  double x = x0;
  for (const BreakdownBar::Segment& s : bar.segments) {
    const double sw = w * std::clamp(s.fraction, 0.0, 1.0);
    if (sw <= 0.0) continue;
    c.fillRect(x, y, sw, kLine + 4, s.colour);
    const bool dark = 0.299 * s.colour.r + 0.587 * s.colour.g + 0.114 * s.colour.b < 140.0;
    if (c.textWidth(s.label, kText - 2) + 6 <= sw) {
      c.text(x + sw / 2.0, centredBaseline(y + (kLine + 4) / 2.0), s.label, kText - 2,
             dark ? Rgb{255, 255, 255} : kBlack, Align::kCentre);
    }
    x += sw;
  }
  c.frame(x0, y, w, kLine + 4, Rgb{120, 120, 120});
}

}  // namespace

RgbImage drawViewGrid(const ViewGrid& grid) {
  int width = 0, height = kPad;
  for (const ViewRow& row : grid.rows) {
    int w = 0, h = 0;
    for (const RgbImage& v : row.views) {
      w += v.width;
      h = std::max(h, v.height);
    }
    width = std::max(width, w);
    height += kLine + kPad + kLine + 4 + h + kPad;
  }
  if (!grid.legend.empty()) height += kLine + kPad;
  height += static_cast<int>(grid.bars.size()) * (kLine + 4 + kPad);
  return detail::renderPixels(std::max(width, 1), height, [&](Canvas& c) {
    int y = kPad;
    for (const ViewRow& row : grid.rows) {
      drawRowTitle(c, row, width, y);
      y += kLine + kPad;
      int column_x = 0, tallest = 0;
      for (std::size_t i = 0; i < row.views.size(); ++i) {
        const RgbImage& view = row.views[i];
        if (i < grid.captions.size()) {
          c.text(column_x + view.width / 2.0, centredBaseline(y + kLine / 2.0),
                 c.fitText(grid.captions[i], view.width - 8, kText), kText, kCaption,
                 Align::kCentre);
        }
        c.image(view, column_x, y + kLine + 4);
        column_x += view.width;
        tallest = std::max(tallest, view.height);
      }
      y += kLine + 4 + tallest + kPad;
    }
    if (!grid.legend.empty()) {
      drawLegendLine(c, grid.legend, y);
      y += kLine + kPad;
    }
    for (const BreakdownBar& bar : grid.bars) {
      drawBar(c, bar, width, y);
      y += kLine + 4 + kPad;
    }
  });
}

}  // namespace scanplan::cli
