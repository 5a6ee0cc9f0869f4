#pragma once
// Text in raster images without a font library: a built-in 5 × 8 bitmap font (printable ASCII,
// plus ° and ²), drawn with nearest-neighbour scaling. Used to label the PNG plots.

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "cli/plot/image_io.h"

namespace scanplan::cli {

/// One character cell at scale 1: 5 glyph columns + 1 space, 8 glyph rows (the last one for
/// descenders) + 1 space. Glyph row 6 is the baseline row of capitals and digits.
inline constexpr int kGlyphWidth = 5, kGlyphHeight = 8;
inline constexpr int kCellWidth = kGlyphWidth + 1, kCellHeight = kGlyphHeight + 1;

/// Horizontal text, its top-left corner at (x, y), every font pixel a scale × scale square
/// (scale < 1 draws as 1). UTF-8: ° and ² have glyphs, other non-ASCII characters and control
/// characters draw as '?'. Clipped to the image. Returns the x just after the last cell.
int drawText(RgbImage& image, int x, int y, std::string_view text, Rgb colour, int scale = 2);

/// The same text turned 90° anticlockwise (reading bottom to top, as a y-axis title), the
/// bottom-left corner of its first character at (x, y): it occupies
/// [x, x + textHeight) × (y − textWidth, y]. Returns the y just above the last cell.
int drawTextUp(RgbImage& image, int x, int y, std::string_view text, Rgb colour, int scale = 2);

/// The size drawText gives `text` (cells × scale; no trailing space column counted).
int textWidth(std::string_view text, int scale = 2);
inline int textHeight(int scale = 2) { return kGlyphHeight * (scale < 1 ? 1 : scale); }

/// The longest prefix of `text` (with ".." when cut) that fits `width` pixels at `scale`.
std::string fitText(const std::string& text, int width, int scale = 2);

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

/// What labelFigure writes around a plot's data raster.
struct FigureLabels {
  std::string title, x_label, y_label;
  /// Axis values at the raster's left and right edges, and at its bottom and top edges. A flat
  /// or non-finite range is widened as axisRange does (so there are always ticks).
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

/// A labelled figure and where its data raster sits in it.
struct LabelledFigure {
  RgbImage image;
  int area_x = 0, area_y = 0;  ///< the raster's top-left pixel; it keeps its size
};

/// The raster `area` copied pixel for pixel into a white figure and framed: the title above,
/// tick marks and values (1, 2, 5 × 10^k) and axis titles below and left, the legend (and colour
/// bar) right, all in the bitmap font at scale 2. Deterministic. An empty raster is drawn as a
/// 1 × 1 white one; a raster whose bytes do not match its size throws InputError.
LabelledFigure labelFigure(const RgbImage& area, const FigureLabels& labels);

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

/// Rows of views with a caption over each view and legend lines under the whole.
struct ViewGrid {
  std::vector<std::string> captions;  ///< one per column
  std::vector<ViewRow> rows;
  std::vector<LegendEntry> legend;  ///< under the views, left to right
};

/// The grid drawn into a white image in the bitmap font at scale 2: for each row its title (and
/// colour scale), the view captions, the views pixel for pixel; the legend last. Deterministic.
RgbImage drawViewGrid(const ViewGrid& grid);

}  // namespace scanplan::cli
