#include "cli/plot/figure.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include <scanplan/kinematics/error.h>
#include "cli/io/output.h"
#include "cli/plot/canvas.h"

namespace scanplan::cli {
namespace {

using detail::Align;
using detail::Canvas;
using detail::kCapHeight;

// Font sizes and spacing, px.
constexpr double kText = 15, kTitle = 17;
constexpr int kLine = 20, kTick = 6, kPad = 12, kMark = 20;
constexpr Rgb kBlack{0, 0, 0}, kGrid{225, 225, 225}, kSwatchEdge{90, 90, 90};

// The baseline that centres a line of capitals and digits on y.
double centredBaseline(double y, double size) { return y + 0.5 * kCapHeight * size; }

// A 1 px line centred on a pixel, so that it stays crisp in the PNG.
double snap(double v) { return std::floor(v) + 0.5; }

struct Tick {
  double value;
  std::string text;
};

// Everything the drawing needs, computed once for every surface.
struct Plan {
  FigureLayout box;
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  std::vector<Tick> x_ticks, y_ticks;
  std::size_t every = 1;  // every k-th x tick labelled
  double spacing = 0;     // px between neighbouring x ticks
  int bar_height = 0;

  double px(double v) const { return box.area_x + (v - x0) / (x1 - x0) * box.area_width; }
  double py(double v) const { return box.area_y + (y1 - v) / (y1 - y0) * box.area_height; }
};

std::pair<double, double> shownRange(double a, double b) {
  return flatRange(a, b) || !std::isfinite(b - a) ? axisRange(a, b, 0.0) : std::pair{a, b};
}

void planTicks(const FigureLabels& text, Plan& plan) {
  if (text.y_marks.empty()) {
    const Ticks ticks = niceTicks(plan.y0, plan.y1);
    for (const double v : ticks.values) plan.y_ticks.push_back({v, tickLabel(ticks, v)});
  }
  for (const auto& [v, s] : text.y_marks) {
    if (std::isfinite(v) && v >= std::min(plan.y0, plan.y1) && v <= std::max(plan.y0, plan.y1)) {
      plan.y_ticks.push_back({v, s});
    }
  }
  if (text.categories.empty()) {
    const Ticks ticks = niceTicks(plan.x0, plan.x1);
    for (const double v : ticks.values) plan.x_ticks.push_back({v, tickLabel(ticks, v)});
  }
  for (std::size_t i = 0; i < text.categories.size(); ++i) {
    plan.x_ticks.push_back({static_cast<double>(i), text.categories[i]});
  }
}

// The legend column's width and height (entries, then the colour bar).
std::pair<double, int> legendSize(const Canvas& m, const FigureLabels& text, int bar_height) {
  double width = 0;
  int height = 0;
  for (const LegendEntry& e : text.legend) {
    const int indent = e.mark == LegendEntry::Mark::kNone ? 0 : kMark + 8;
    width = std::max(width, indent + m.textWidth(e.text, kText));
    height += e.space_before + kLine + 8;
  }
  if (!text.colour_bar.empty()) {
    width = std::max(width, m.textWidth(text.colour_bar, kText));
    for (const char* s : {"1 free", "0.5", "0 forbidden"}) {
      width = std::max(width, kMark + kTick + 4 + m.textWidth(s, kText));
    }
    height += (text.legend.empty() ? 0 : 10) + kLine + 8 + bar_height + kLine / 2;
  }
  return {width, height};
}

Plan planFigure(const Figure& figure) {
  const RgbImage& raster = figure.raster;
  if (raster.width > 0 && raster.height > 0 &&
      raster.rgb.size() !=
          3 * static_cast<std::size_t>(raster.width) * static_cast<std::size_t>(raster.height)) {
    throw InputError(fmt::format("figure: raster {} × {} with {} bytes: expected 3 per pixel",
                                 raster.width, raster.height, raster.rgb.size()));
  }
  const FigureLabels& text = figure.labels;
  Plan plan;
  std::tie(plan.x0, plan.x1) = shownRange(text.x0, text.x1);
  std::tie(plan.y0, plan.y1) = shownRange(text.y0, text.y1);
  planTicks(text, plan);
  const bool has_raster = raster.width > 0 && raster.height > 0;
  const int pw = std::max(1, has_raster ? raster.width : figure.plot_width);
  const int ph = std::max(1, has_raster ? raster.height : figure.plot_height);
  const Canvas m = Canvas::measuring();
  double y_label_width = 0;
  for (const Tick& t : plan.y_ticks)
    y_label_width = std::max(y_label_width, m.textWidth(t.text, kText));
  plan.bar_height = std::clamp(ph / 2, 80, 240);
  const auto [legend_width, legend_height] = legendSize(m, text, plan.bar_height);
  const bool has_legend = !text.legend.empty() || !text.colour_bar.empty();
  FigureLayout& box = plan.box;
  box.area_x = kPad + kLine + kPad + static_cast<int>(std::ceil(y_label_width)) + kTick + 4;
  box.area_y = kPad + kLine + kPad;
  box.area_width = pw;
  box.area_height = ph;
  const int right = has_legend ? 3 * kPad + static_cast<int>(std::ceil(legend_width)) : 2 * kPad;
  const int bottom = kTick + 4 + kLine + kPad / 2 + kLine + kPad;
  box.width = box.area_x + pw + right;
  box.height = std::max(box.area_y + ph + bottom, box.area_y + legend_height + kPad);

  plan.spacing = pw;
  for (std::size_t i = 1; i < plan.x_ticks.size(); ++i) {
    plan.spacing = std::min(plan.spacing, std::abs(plan.px(plan.x_ticks[i].value) -
                                                   plan.px(plan.x_ticks[i - 1].value)));
  }
  double widest = 0;
  for (const Tick& t : plan.x_ticks) widest = std::max(widest, m.textWidth(t.text, kText));
  if (text.categories.empty()) {
    while (plan.every < plan.x_ticks.size() &&
           plan.spacing * static_cast<double>(plan.every) < widest + 12) {
      ++plan.every;
    }
  }
  return plan;
}

// Title above, axis titles below and left.
void drawTitles(Canvas& c, const Plan& plan, const FigureLabels& text) {
  const FigureLayout& b = plan.box;
  const std::string title = c.fitText(text.title, b.width - 2 * kPad, kTitle);
  const double title_width = c.textWidth(title, kTitle);
  const double title_x = std::clamp(b.area_x + (b.area_width - title_width) / 2, double{kPad},
                                    std::max<double>(kPad, b.width - kPad - title_width));
  c.text(title_x, centredBaseline(kPad + kLine / 2.0, kTitle), title, kTitle, kBlack);
  const std::string x_label = c.fitText(text.x_label, b.width - 2 * kPad, kText);
  const double x_label_y = b.area_y + b.area_height + kTick + 4 + kLine + kPad / 2 + kLine / 2.0;
  c.text(std::max<double>(kPad + c.textWidth(x_label, kText) / 2, b.area_x + b.area_width / 2.0),
         centredBaseline(x_label_y, kText), x_label, kText, kBlack, Align::kCentre);
  const std::string y_label = c.fitText(text.y_label, b.height - 2 * kPad, kText);
  const double y_centre =
      std::min(b.area_y + b.area_height / 2.0, b.height - kPad - c.textWidth(y_label, kText) / 2);
  c.text(kPad + kCapHeight * kText + 1, y_centre, y_label, kText, kBlack, Align::kCentre, true);
}

void drawTicks(Canvas& c, const Plan& plan, const FigureLabels& text) {
  const FigureLayout& b = plan.box;
  for (const Tick& t : plan.y_ticks) {
    const double y = snap(plan.py(t.value));
    c.line(b.area_x - kTick, y, b.area_x - 1, y, kBlack, 1);
    c.text(b.area_x - kTick - 4, centredBaseline(y, kText), t.text, kText, kBlack, Align::kRight);
  }
  const double bottom = b.area_y + b.area_height;
  for (std::size_t i = 0; i < plan.x_ticks.size(); ++i) {
    const double x = snap(plan.px(plan.x_ticks[i].value));
    c.line(x, bottom + 1, x, bottom + 1 + kTick, kBlack, 1);
    if (i % plan.every != 0) continue;
    const std::string s = text.categories.empty()
                              ? plan.x_ticks[i].text
                              : c.fitText(plan.x_ticks[i].text, plan.spacing - 8, kText);
    const double half = c.textWidth(s, kText) / 2;
    c.text(std::clamp(x, half, std::max(half, b.width - half)),
           centredBaseline(bottom + kTick + 4 + kLine / 2.0, kText), s, kText, kBlack,
           Align::kCentre);
  }
}

void drawLegendMark(Canvas& c, const LegendEntry& e, double x, double y) {
  switch (e.mark) {
    case LegendEntry::Mark::kSwatch:
      c.fillRect(x, y + 2, kMark, kLine - 4, e.colour);
      c.frame(x + 1, y + 3, kMark - 2, kLine - 6, kSwatchEdge);
      break;
    case LegendEntry::Mark::kLine:
      c.line(x, y + kLine / 2.0, x + kMark, y + kLine / 2.0, e.colour, 3);
      break;
    case LegendEntry::Mark::kCross:
      c.line(x + 6, y + kLine / 2.0 - 4, x + 14, y + kLine / 2.0 + 4, e.colour, 2);
      c.line(x + 6, y + kLine / 2.0 + 4, x + 14, y + kLine / 2.0 - 4, e.colour, 2);
      break;
    case LegendEntry::Mark::kNone:
      break;
  }
}

void drawColourBar(Canvas& c, const std::string& title, double x, double y, int height) {
  c.text(x, centredBaseline(y + kLine / 2.0, kText), title, kText, kBlack);
  y += kLine + 8;
  // White (f = 1) at the top to black (f = 0), the grey() scale.
  cairo_t* cr = c.context();
  cairo_pattern_t* ramp = cairo_pattern_create_linear(0, y, 0, y + height);
  cairo_pattern_add_color_stop_rgb(ramp, 0, 1, 1, 1);
  cairo_pattern_add_color_stop_rgb(ramp, 1, 0, 0, 0);
  cairo_rectangle(cr, x, y, kMark, height);
  cairo_set_source(cr, ramp);
  cairo_fill(cr);
  cairo_pattern_destroy(ramp);
  c.frame(x, y, kMark, height, kBlack);
  for (const auto& [f, s] : {std::pair{1.0, "1 free"}, {0.5, "0.5"}, {0.0, "0 forbidden"}}) {
    const double ty = snap(y + (1.0 - f) * (height - 1));
    c.line(x + kMark, ty, x + kMark + kTick, ty, kBlack, 1);
    c.text(x + kMark + kTick + 4, centredBaseline(ty, kText), s, kText, kBlack);
  }
}

void drawLegend(Canvas& c, const Plan& plan, const FigureLabels& text) {
  const double x = plan.box.area_x + plan.box.area_width + 2 * kPad;
  double y = plan.box.area_y;
  for (const LegendEntry& e : text.legend) {
    y += e.space_before;
    drawLegendMark(c, e, x, y);
    const double tx = e.mark == LegendEntry::Mark::kNone ? x : x + kMark + 8;
    c.text(tx, centredBaseline(y + kLine / 2.0, kText), e.text, kText, e.text_colour);
    y += kLine + 8;
  }
  if (!text.colour_bar.empty()) {
    drawColourBar(c, text.colour_bar, x, y + (text.legend.empty() ? 0 : 10), plan.bar_height);
  }
}

void drawOverlays(Canvas& c, const Plan& plan, const Figure& figure) {
  const FigureLayout& b = plan.box;
  cairo_t* cr = c.context();
  cairo_save(cr);
  cairo_rectangle(cr, b.area_x, b.area_y, b.area_width, b.area_height);
  cairo_clip(cr);
  if (figure.grid) {
    for (const Tick& t : plan.y_ticks) {
      c.line(b.area_x, snap(plan.py(t.value)), b.area_x + b.area_width, snap(plan.py(t.value)),
             kGrid, 1);
    }
    for (const Tick& t : plan.x_ticks) {
      c.line(snap(plan.px(t.value)), b.area_y, snap(plan.px(t.value)), b.area_y + b.area_height,
             kGrid, 1);
    }
  }
  for (const Overlay& o : figure.overlays) {
    std::vector<std::pair<double, double>> points;
    for (const auto& [u, v] : o.points) points.emplace_back(plan.px(u), plan.py(v));
    if (o.kind == Overlay::Kind::kLine) {
      c.polyline(points, o.colour, o.width_px);
      continue;
    }
    for (const auto& [x, y] : points) {
      c.line(x - 3, y - 3, x + 3, y + 3, o.colour, o.width_px);
      c.line(x - 3, y + 3, x + 3, y - 3, o.colour, o.width_px);
    }
  }
  cairo_restore(cr);
}

void drawFigure(Canvas& c, const Plan& plan, const Figure& figure) {
  const FigureLayout& b = plan.box;
  if (figure.raster.width > 0 && figure.raster.height > 0) {
    c.image(figure.raster, b.area_x, b.area_y);
  }
  drawOverlays(c, plan, figure);
  c.frame(b.area_x, b.area_y, b.area_width, b.area_height, kBlack);
  drawTitles(c, plan, figure.labels);
  drawTicks(c, plan, figure.labels);
  drawLegend(c, plan, figure.labels);
}

// Every word of the figure but the title, for the SVG's <desc>.
std::string describe(const Plan& plan, const FigureLabels& text) {
  std::string s = fmt::format("x: {}; y: {}", text.x_label, text.y_label);
  for (const LegendEntry& e : text.legend) s += "; " + e.text;
  if (!text.colour_bar.empty()) s += "; colour bar: " + text.colour_bar;
  const auto list = [](const std::vector<Tick>& ticks) {
    std::string out;
    for (const Tick& t : ticks) out += (out.empty() ? "" : ", ") + t.text;
    return out;
  };
  return s + "; x ticks: " + list(plan.x_ticks) + "; y ticks: " + list(plan.y_ticks);
}

}  // namespace

FigureLayout layoutFigure(const Figure& figure) { return planFigure(figure).box; }

RgbImage renderFigure(const Figure& figure) {
  const Plan plan = planFigure(figure);
  return detail::renderPixels(plan.box.width, plan.box.height,
                              [&](Canvas& c) { drawFigure(c, plan, figure); });
}

std::string figureSvg(const Figure& figure, const WriteSettings& settings) {
  const Plan plan = planFigure(figure);
  return detail::renderSvg(
      plan.box.width, plan.box.height, [&](Canvas& c) { drawFigure(c, plan, figure); },
      figure.labels.title, describe(plan, figure.labels),
      settings.svg_raster_png ? std::optional(settings.png) : std::nullopt);
}

std::string figurePdf(const Figure& figure) {
  const Plan plan = planFigure(figure);
  return detail::renderPdf(plan.box.width, plan.box.height,
                           [&](Canvas& c) { drawFigure(c, plan, figure); });
}

void writeFigureFiles(const std::filesystem::path& dir,
                      const std::string& stem,
                      const Figure& figure,
                      const WriteSettings& settings) {
  writePng(dir / (stem + ".png"), renderFigure(figure), settings.png);
  writeFileAtomically(dir / (stem + ".svg"), figureSvg(figure, settings));
}

}  // namespace scanplan::cli
