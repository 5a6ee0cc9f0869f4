// The figures of a batch: each metric against each varied value, one colour per planner, as PNG
// and SVG.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "cli/batch/batch.h"
#include "cli/batch/batch_internal.h"
#include "cli/io/output.h"
#include "cli/plot/bitmap_font.h"
#include "cli/plot/image_io.h"

namespace scanplan::cli {

namespace fs = std::filesystem;

Rgb batchPlannerColour(const std::string& method) {
  if (method == "dp") return categoryColour(4);    // blue, as in `plan`'s figures
  if (method == "ompl") return categoryColour(2);  // bluish green
  if (method == "ray") return categoryColour(5);   // vermillion
  return categoryColour(7);
}

namespace detail {

namespace {

// A metric's name on an axis, with its unit.
std::string metricLabel(std::size_t metric) {
  switch (metric) {
    case kJ:
      return "J, objective (s)";
    case kCostF:
      return "J's f term (s)";
    case kCostOmega:
      return "J's omega term (s)";
    case kCostAlpha:
      return "J's alpha term (s)";
    case kGap:
      return "DP gap (%)";
    case kMinF:
      return "min f along the path";
    case kClearance:
      return "min clearance (mm)";
    case kOmega:
      return "max table speed (deg/s)";
    case kAlpha:
      return "max table acceleration (deg/s²)";
    case kCycle:
      return "cycle time (s)";
    case kCoverage:
      return "coverage (fraction of the part's area)";
    case kMapS:
      return "map time (s)";
    case kPlanS:
      return "plan time (s)";
    case kDpS:
      return "DP yardstick time (s)";
    case kValidationS:
      return "validation time (s)";
    case kSimulationS:
      return "simulation time (s)";
    default:
      return kBatchMetrics.at(metric);  // a metric added without a label here
  }
}

std::string base64(const std::string& bytes) {
  static constexpr char kDigits[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    std::uint32_t v = static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i])) << 16;
    if (i + 1 < bytes.size())
      v |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i + 1])) << 8;
    if (i + 2 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 2]);
    out += kDigits[(v >> 18) & 63];
    out += kDigits[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kDigits[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kDigits[v & 63] : '=';
  }
  return out;
}

}  // namespace

// One metric against one varied value: a point per case, a line through each planner's means;
// categorical values are placed at 0, 1, 2, … and the planners side by side at each.
// Returns false when no case has the metric.
bool writePlot(const fs::path& dir,
               const std::string& stem,
               const std::vector<BatchRow>& rows,
               const std::string& key,
               std::size_t metric) {
  std::vector<std::string> values;  // distinct values of `key`, in order of appearance
  bool numeric = true;
  for (const BatchRow& r : rows) {
    const std::string v = paramValue(r, key);
    if (std::find(values.begin(), values.end(), v) == values.end()) values.push_back(v);
    numeric = numeric && numberOf(v).has_value();
  }
  if (numeric) {
    std::sort(values.begin(), values.end(), [](const std::string& a, const std::string& b) {
      return *numberOf(a) < *numberOf(b);
    });
  }
  std::vector<std::string> methods;
  for (const BatchRow& r : rows) {
    if (std::find(methods.begin(), methods.end(), r.method) == methods.end()) {
      methods.push_back(r.method);
    }
  }
  const auto position = [&](const std::string& v) {
    if (numeric) return *numberOf(v);
    return static_cast<double>(std::find(values.begin(), values.end(), v) - values.begin());
  };
  // Padded axis ranges; values equal up to rounding (e.g. the same J from two planners) make a
  // flat range, centred on the value (axisRange), never one with ticks 1e-14 apart.
  const std::pair<double, double> x_range =
      axisRange(position(values.front()), position(values.back()));
  const double x0 = x_range.first, x1 = x_range.second;
  const double spread = (x1 - x0) * 0.012;  // planners side by side at one value
  double lowest = std::numeric_limits<double>::infinity(), highest = -lowest;
  for (const BatchRow& r : rows) {
    if (r.metrics[metric] && std::isfinite(*r.metrics[metric])) {
      lowest = std::min(lowest, *r.metrics[metric]);
      highest = std::max(highest, *r.metrics[metric]);
    }
  }
  if (!std::isfinite(lowest)) return false;
  const std::pair<double, double> y_range = axisRange(lowest, highest);
  const double y0 = y_range.first, y1 = y_range.second;
  constexpr int kW = 720, kH = 480;
  RgbImage image = RgbImage::filled(kW, kH, {255, 255, 255});
  const auto px = [&](double x) { return (x - x0) / (x1 - x0) * kW; };
  const auto py = [&](double y) { return (1.0 - (y - y0) / (y1 - y0)) * kH; };
  // Light grid lines at the ticks the axes get.
  constexpr Rgb kGrid{225, 225, 225};
  for (const double v : niceTicks(y0, y1).values) drawLine(image, 0, py(v), kW, py(v), kGrid, 1);
  std::vector<double> x_grid;
  if (numeric) {
    x_grid = niceTicks(x0, x1).values;
  } else {
    for (std::size_t i = 0; i < values.size(); ++i) x_grid.push_back(static_cast<double>(i));
  }
  for (const double v : x_grid) drawLine(image, px(v), 0, px(v), kH, kGrid, 1);
  std::vector<std::pair<Rgb, std::string>> legend;  // the planners (the SVG's legend)
  for (std::size_t mi = 0; mi < methods.size(); ++mi) {
    const Rgb colour = batchPlannerColour(methods[mi]);
    const double offset =
        (static_cast<double>(mi) - 0.5 * static_cast<double>(methods.size() - 1)) * spread;
    std::vector<std::pair<double, double>> means;
    for (const std::string& v : values) {
      Mean mean;
      for (const BatchRow& r : rows) {
        if (r.method != methods[mi] || paramValue(r, key) != v) continue;
        mean.add(r.metrics[metric]);
        if (r.metrics[metric] && std::isfinite(*r.metrics[metric])) {
          const double x = px(position(v) + offset), y = py(*r.metrics[metric]);
          drawLine(image, x - 3, y - 3, x + 3, y + 3, colour, 2);
          drawLine(image, x - 3, y + 3, x + 3, y - 3, colour, 2);
        }
      }
      // The mean of huge values can overflow: no point then (drawLine skips non-finite ends).
      if (mean.n) means.emplace_back(px(position(v) + offset), py(mean.sum / mean.n));
    }
    for (std::size_t i = 1; i < means.size(); ++i) {
      drawLine(image, means[i - 1].first, means[i - 1].second, means[i].first, means[i].second,
               colour, 2);
    }
    // In the legend when it has a value here (a planner whose cases all failed has none).
    if (!means.empty()) {
      legend.emplace_back(colour, methods[mi].empty() ? std::string("(none)") : methods[mi]);
    }
  }
  const std::string x_name = key.empty() ? std::string("all cases") : key;
  FigureLabels text;
  text.title = metricLabel(metric) + " against " + x_name;
  text.x_label = x_name;
  text.y_label = metricLabel(metric);
  text.x0 = x0;
  text.x1 = x1;
  text.y0 = y0;
  text.y1 = y1;
  if (!numeric) {
    text.categories = key.empty() ? std::vector<std::string>{"all"} : values;
    for (std::string& c : text.categories) {
      if (c.empty()) c = "(not set)";  // an explicit case without this key
    }
  }
  // A swatch and name per planner, then what the marks mean.
  constexpr Rgb kGreyText{90, 90, 90};
  for (const auto& [colour, name] : legend) text.legend.push_back({colour, name});
  text.legend.push_back({kGreyText, "case", LegendEntry::Mark::kCross, kGreyText, 10});
  text.legend.push_back({kGreyText, "mean", LegendEntry::Mark::kLine, kGreyText});
  writePng(dir / (stem + ".png"), labelFigure(image, text).image);
  // The SVG: the same data raster, embedded, with the axes and text as SVG text.
  SvgFigure figure;
  figure.png_file = "data:image/png;base64," + base64(encodePng(image));
  figure.png_width = kW;
  figure.png_height = kH;
  figure.title = text.title;
  figure.x_label = x_name;
  if (!numeric && !key.empty()) {
    figure.x_label += " (";
    for (std::size_t i = 0; i < values.size(); ++i) {
      figure.x_label += fmt::format("{}{} = {}", i ? ", " : "", i,
                                    values[i].empty() ? std::string("(not set)") : values[i]);
    }
    figure.x_label += ")";
  }
  figure.y_label = text.y_label;
  figure.x_min = x0;
  figure.x_max = x1;
  figure.y_min = y0;
  figure.y_max = y1;
  figure.legend = legend;
  writeFileAtomically(dir / (stem + ".svg"), svgFigure(figure));
  return true;
}

}  // namespace detail
}  // namespace scanplan::cli
