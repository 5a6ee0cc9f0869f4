#pragma once
// Text in raster images without a font library: a built-in 5 × 8 bitmap font (printable ASCII,
// plus ° and ²), drawn with nearest-neighbour scaling. Used to label the PNG plots.

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "cli/plot/figure.h"
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

}  // namespace scanplan::cli
