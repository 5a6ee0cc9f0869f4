#pragma once
// Internal to cli/plot: a small drawing surface over cairo (text in DejaVu Sans, lines, rasters)
// and the three outputs of one drawing function: pixels, SVG and PDF. Only cli/plot/*.cpp
// include this header; nothing outside the folder sees cairo.

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <cairo.h>

#include "cli/plot/image_io.h"

namespace scanplan::cli::detail {

/// The font of every figure, found by name through fontconfig (fonts-dejavu-core).
inline constexpr const char* kFontFamily = "DejaVu Sans";
/// DejaVu Sans: the height of a capital (and of a digit) as a fraction of the font size; used to
/// centre a line of text vertically on a point.
inline constexpr double kCapHeight = 0.73;

enum class Align { kLeft, kCentre, kRight };

/// A cairo context with the figure font selected (no hinted metrics: the same text has the same
/// width on every surface, so one layout serves the PNG, the SVG and the PDF). Lengths in
/// figure pixels, y down.
class Canvas {
 public:
  /// Draws on `surface` (kept alive by this canvas); scale: figure pixels → surface units.
  explicit Canvas(cairo_surface_t* surface, double scale = 1.0);
  Canvas(const Canvas&) = delete;
  Canvas& operator=(const Canvas&) = delete;
  ~Canvas();

  /// A canvas that only measures text.
  static Canvas measuring();

  /// The advance width of `text` at font size `size` (px).
  double textWidth(std::string_view text, double size) const;
  /// The longest prefix of `text` (with ".." when cut) at most `width` wide; whole UTF-8
  /// characters only.
  std::string fitText(const std::string& text, double width, double size) const;
  /// One line of text, its baseline at y; `up`: turned 90° anticlockwise about (x, y), reading
  /// bottom to top (alignment then along the turned line).
  void text(double x,
            double y,
            std::string_view text,
            double size,
            Rgb colour,
            Align align = Align::kLeft,
            bool up = false);
  /// A straight segment `width` px wide with butt ends; non-finite ends draw nothing.
  void line(double x0, double y0, double x1, double y1, Rgb colour, double width);
  /// Connected segments through the points (round joins); a non-finite point breaks the line.
  void polyline(const std::vector<std::pair<double, double>>& points, Rgb colour, double width);
  void fillRect(double x, double y, double w, double h, Rgb colour);
  /// The rectangle's outline, 1 px wide, drawn on the pixels just outside [x, x + w) × [y, y + h)
  /// for whole-pixel x, y, w, h.
  void frame(double x, double y, double w, double h, Rgb colour);
  /// The raster's pixels at (x, y), one figure pixel each, never smoothed.
  void image(const RgbImage& raster, double x, double y);
  /// Rasters drawn from now on carry their PNG encoded with `settings`, which a vector surface
  /// (SVG) embeds as it is instead of encoding the pixels itself.
  void attachPng(const PngSettings& settings) { raster_png_ = settings; }
  cairo_t* context() { return cr_; }

 private:
  cairo_surface_t* surface_;
  cairo_t* cr_;
  std::optional<PngSettings> raster_png_;
};

using Drawing = std::function<void(Canvas&)>;

/// The drawing rendered into a white width × height raster (grey antialiasing). Deterministic.
RgbImage renderPixels(int width, int height, const Drawing& draw);
/// The drawing as SVG 1.1: text as glyph outlines, lines as paths, rasters as embedded PNG
/// images; the size in px equals the raster's. `title` and `description` go into <title> and
/// <desc> (the figure's words, for search and screen readers). Same drawing → same bytes.
/// `raster_png`: rasters embedded as PNGs encoded with these settings (else cairo encodes them,
/// level 6 with every filter).
std::string renderSvg(int width,
                      int height,
                      const Drawing& draw,
                      const std::string& title,
                      const std::string& description,
                      const std::optional<PngSettings>& raster_png = PngSettings{});
/// The drawing as a one-page PDF (vector, fonts embedded), without a creation date: same
/// drawing → same bytes.
std::string renderPdf(int width, int height, const Drawing& draw);

}  // namespace scanplan::cli::detail
