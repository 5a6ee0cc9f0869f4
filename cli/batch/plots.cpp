// The figures of a batch: each metric against each varied value, one colour per planner, as PNG
// and SVG.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "cli/batch/batch.h"
#include "cli/batch/batch_internal.h"
#include "cli/io/output.h"
#include "cli/plot/figure.h"
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

// What the axis shows of the cases: the distinct values of `key` in order (numbers sorted), and
// whether they are all numbers (else categories at 0, 1, 2, …).
struct XAxis {
  std::vector<std::string> values;
  bool numeric = true;
  double position(const std::string& v) const {
    if (numeric) return *numberOf(v);
    return static_cast<double>(std::find(values.begin(), values.end(), v) - values.begin());
  }
};

XAxis xAxis(const std::vector<BatchRow>& rows, const std::string& key) {
  XAxis axis;
  for (const BatchRow& r : rows) {
    const std::string v = paramValue(r, key);
    if (std::find(axis.values.begin(), axis.values.end(), v) == axis.values.end()) {
      axis.values.push_back(v);
    }
    axis.numeric = axis.numeric && numberOf(v).has_value();
  }
  if (axis.numeric) {
    std::sort(
        axis.values.begin(), axis.values.end(),
        [](const std::string& a, const std::string& b) { return *numberOf(a) < *numberOf(b); });
  }
  return axis;
}

// Per planner, a cross per case and a line through the means at each value (side by side at one
// value: 1.2 % of the axis apart); a legend swatch for each planner that has a value.
void addPlanners(Figure& figure,
                 const std::vector<BatchRow>& rows,
                 const std::string& key,
                 std::size_t metric,
                 const XAxis& axis) {
  std::vector<std::string> methods;
  for (const BatchRow& r : rows) {
    if (std::find(methods.begin(), methods.end(), r.method) == methods.end()) {
      methods.push_back(r.method);
    }
  }
  const double spread = (figure.labels.x1 - figure.labels.x0) * 0.012;
  std::vector<Overlay> means;
  for (std::size_t mi = 0; mi < methods.size(); ++mi) {
    const Rgb colour = batchPlannerColour(methods[mi]);
    const double offset =
        (static_cast<double>(mi) - 0.5 * static_cast<double>(methods.size() - 1)) * spread;
    Overlay cases{Overlay::Kind::kCrosses, {}, colour, 2.0};
    Overlay line{Overlay::Kind::kLine, {}, colour, 2.0};
    for (const std::string& v : axis.values) {
      Mean mean;
      for (const BatchRow& r : rows) {
        if (r.method != methods[mi] || paramValue(r, key) != v) continue;
        mean.add(r.metrics[metric]);
        if (r.metrics[metric] && std::isfinite(*r.metrics[metric])) {
          cases.points.emplace_back(axis.position(v) + offset, *r.metrics[metric]);
        }
      }
      // The mean of huge values can overflow: no point then (a non-finite point breaks a line).
      if (mean.n) line.points.emplace_back(axis.position(v) + offset, mean.sum / mean.n);
    }
    figure.overlays.push_back(std::move(cases));
    // In the legend when it has a value here (a planner whose cases all failed has none).
    if (!line.points.empty()) {
      figure.labels.legend.push_back(
          {colour, methods[mi].empty() ? std::string("(none)") : methods[mi]});
    }
    means.push_back(std::move(line));
  }
  for (Overlay& line : means) figure.overlays.push_back(std::move(line));
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
  const XAxis axis = xAxis(rows, key);
  double lowest = std::numeric_limits<double>::infinity(), highest = -lowest;
  for (const BatchRow& r : rows) {
    if (r.metrics[metric] && std::isfinite(*r.metrics[metric])) {
      lowest = std::min(lowest, *r.metrics[metric]);
      highest = std::max(highest, *r.metrics[metric]);
    }
  }
  if (!std::isfinite(lowest)) return false;
  // Padded axis ranges; values equal up to rounding (e.g. the same J from two planners) make a
  // flat range, centred on the value (axisRange), never one with ticks 1e-14 apart.
  Figure figure;
  FigureLabels& text = figure.labels;
  std::tie(text.x0, text.x1) =
      axisRange(axis.position(axis.values.front()), axis.position(axis.values.back()));
  std::tie(text.y0, text.y1) = axisRange(lowest, highest);
  figure.plot_width = 720;
  figure.plot_height = 480;
  figure.grid = true;  // light lines at the ticks
  const std::string x_name = key.empty() ? std::string("all cases") : key;
  text.title = metricLabel(metric) + " against " + x_name;
  text.x_label = x_name;
  text.y_label = metricLabel(metric);
  if (!axis.numeric) {
    text.categories = key.empty() ? std::vector<std::string>{"all"} : axis.values;
    for (std::string& c : text.categories) {
      if (c.empty()) c = "(not set)";  // an explicit case without this key
    }
  }
  // A swatch and name per planner, then what the marks mean.
  addPlanners(figure, rows, key, metric, axis);
  constexpr Rgb kGreyText{90, 90, 90};
  text.legend.push_back({kGreyText, "case", LegendEntry::Mark::kCross, kGreyText, 10});
  text.legend.push_back({kGreyText, "mean", LegendEntry::Mark::kLine, kGreyText});
  writeFigureFiles(dir, stem, figure);
  return true;
}

}  // namespace detail
}  // namespace scanplan::cli
