#pragma once
// Labelled figures drawn with cairo: a plot (a data raster and/or lines and marks in axis units)
// framed with title, axes, "nice" ticks, legend and colour bar, rendered to PNG pixels and to
// true vector SVG and PDF from one drawing function; and rows of captioned views (path.png,
// cloud.png). Text is DejaVu Sans.

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "cli/plot/image_io.h"

namespace scanplan::cli {

/// One line of a figure's legend: a mark in `colour`, then `text`.
struct LegendEntry {
  enum class Mark {
    kSwatch,  ///< a filled square (a colour of the raster)
    kLine,    ///< a short thick line (a path or a line through means)
    kCross,   ///< an × (a point)
    kNone,    ///< text only
  };
  Rgb colour;
  std::string text;
  Mark mark = Mark::kSwatch;
  Rgb text_colour{0, 0, 0};
  int space_before = 0;  ///< extra pixels above this line
};

/// The words and axes around a plot.
struct FigureLabels {
  std::string title, x_label, y_label;
  /// Axis values at the plot area's left and right edges, and at its bottom and top edges. A
  /// flat or non-finite range is widened as axisRange does (so there are always ticks).
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  /// Non-empty: x ticks at 0, 1, … labelled with these (each cut to its room) instead of numbers.
  std::vector<std::string> categories;
  /// Non-empty: y ticks at these values (in y0 … y1 units) with these labels instead of "nice"
  /// numbers (an axis that is not linear in what it shows).
  std::vector<std::pair<double, std::string>> y_marks;
  /// Right of the plot, top to bottom.
  std::vector<LegendEntry> legend;
  /// Non-empty: under the legend, a grey bar from f = 0 (black, "forbidden") to 1 (white,
  /// "free"), the grey() scale, with this title.
  std::string colour_bar;
};

/// Lines or crosses over the plot area, in axis units (x0 … x1, y0 … y1), clipped to the area.
struct Overlay {
  enum class Kind {
    kLine,     ///< a polyline; a non-finite point breaks it
    kCrosses,  ///< an × of ±3 px at each point
  };
  Kind kind = Kind::kLine;
  std::vector<std::pair<double, double>> points;
  Rgb colour;
  double width_px = 2.0;
};

/// A plot and its labels.
struct Figure {
  FigureLabels labels;
  /// The plot area pixel for pixel (top row first); empty: a white area of plot_width ×
  /// plot_height px.
  RgbImage raster;
  int plot_width = 720, plot_height = 480;
  /// Light grey lines across the area at the ticks, under the overlays.
  bool grid = false;
  std::vector<Overlay> overlays;  ///< drawn in order, over the raster
};

/// Where things are in a rendered figure, in pixels.
struct FigureLayout {
  int width = 0, height = 0;
  /// The plot area: the raster's top-left pixel and size; a 1 px black frame lies just outside.
  int area_x = 0, area_y = 0, area_width = 0, area_height = 0;
};

/// The layout renderFigure, figureSvg and figurePdf share: the title above, tick values and axis
/// titles left and below, the legend (and colour bar) right. Throws InputError for a raster
/// whose bytes do not match its size.
FigureLayout layoutFigure(const Figure& figure);
/// The figure's pixels (the PNG): the raster copied exactly into the plot area, text
/// antialiased. Deterministic.
RgbImage renderFigure(const Figure& figure);
/// The figure as SVG: text and lines as vector paths, the raster an embedded PNG at its pixel
/// size; the title in <title> and every other word in <desc>. Same figure → same bytes.
std::string figureSvg(const Figure& figure, const WriteSettings& settings = {});
/// The figure as a one-page vector PDF. Same figure → same bytes.
std::string figurePdf(const Figure& figure);
/// `stem`.png and `stem`.svg in `dir`, each written atomically.
void writeFigureFiles(const std::filesystem::path& dir,
                      const std::string& stem,
                      const Figure& figure,
                      const WriteSettings& settings = {});

/// A row of views of one scene (e.g. iso, top, front) under a title line, for the three-view
/// pictures (path.png, cloud.png).
struct ViewRow {
  std::string title;
  std::vector<RgbImage> views;  ///< side by side, each with its caption (ViewGrid::captions)
  /// Non-empty: a horizontal colour scale after the title (the colours from 0 to 1, evenly),
  /// with `scale_from` and `scale_to` written at its ends; left out when the row is too narrow
  /// for it after the title.
  std::vector<Rgb> scale;
  std::string scale_from, scale_to;
};

/// A stacked bar of shares (e.g. why the area is not covered): each segment's width its
/// fraction of the bar, its label inside when it fits.
struct BreakdownBar {
  std::string title;
  struct Segment {
    Rgb colour;
    double fraction = 0.0;  ///< of the whole bar, [0, 1]
    std::string label;
  };
  std::vector<Segment> segments;
};

/// Rows of views with a caption over each view and legend lines under the whole.
struct ViewGrid {
  std::vector<std::string> captions;  ///< one per column
  std::vector<ViewRow> rows;
  std::vector<LegendEntry> legend;  ///< under the views, left to right
  std::vector<BreakdownBar> bars;   ///< under the legend, one line each
};

/// The grid drawn into a white image: for each row its title (and colour scale), the view
/// captions, the views pixel for pixel; the legend, then the bars. Deterministic.
RgbImage drawViewGrid(const ViewGrid& grid);

}  // namespace scanplan::cli
