#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "cli/io/write_settings.h"

namespace scanplan::cli {

/// An 8-bit sRGB colour.
struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  friend bool operator==(const Rgb&, const Rgb&) = default;
};

/// An 8-bit RGB raster: row-major, top row first, 3 bytes per pixel.
struct RgbImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;

  /// A width × height image filled with `fill`.
  static RgbImage filled(int w, int h, Rgb fill = {});
  /// Pixel (x, y), x to the right and y down from the top-left corner; no bounds check.
  void set(int x, int y, Rgb c);
  Rgb at(int x, int y) const;
};

/// Nearest-neighbour enlargement by integer factors ≥ 1 (x and y). Throws InputError when the
/// result would exceed 2^28 pixels.
RgbImage upscale(const RgbImage& image, int factor_x, int factor_y);
/// PNG bytes (8-bit RGB, no text or time chunks, the compression of `settings`): the same image
/// and settings always give the same bytes. Throws InputError for an empty or inconsistent
/// image.
std::string encodePng(const RgbImage& image, const PngSettings& settings = {});
/// encodePng written atomically to `file`; errors name the file.
void writePng(const std::filesystem::path& file,
              const RgbImage& image,
              const PngSettings& settings = {});

/// Writes a NumPy .npy file, format 1.0, C order, byte for byte as numpy.save writes it
/// (dtype '<f4' or '|u1'). Throws InputError when data.size() ≠ the product of `shape`.
/// `stream`: the values go to the file straight from `data` on a little-endian machine
/// (WriteSettings::stream_binary), else through a copy of the whole file.
void writeNpy(const std::filesystem::path& file,
              const std::vector<float>& data,
              const std::vector<std::size_t>& shape,
              bool stream = true);
void writeNpy(const std::filesystem::path& file,
              const std::vector<std::uint8_t>& data,
              const std::vector<std::size_t>& shape,
              bool stream = true);

/// Grey level for a fraction: 0 → black, 1 → white, clamped; NaN → dark red (kNanColour).
Rgb grey(double f);
inline constexpr Rgb kNanColour{139, 0, 0};
/// Okabe–Ito colour-blind-safe palette, k modulo 8 (orange, sky blue, bluish green, yellow,
/// blue, vermillion, reddish purple, black).
Rgb categoryColour(int k);

/// Axis tick values and the decimals to print them with.
struct Ticks {
  std::vector<double> values;
  int decimals = 0;
};
/// The largest step of 1, 2 or 5 × 10^k giving at least five ticks in [a, b] (at most ~12,
/// never more than kMaxTicks); none for an empty, non-finite or flat range (see flatRange).
Ticks niceTicks(double a, double b);
inline constexpr std::size_t kMaxTicks = 50;
/// A tick value as text: fixed with the ticks' decimals, or in exponent form when that would be
/// long (|v| ≥ 1e9 or more than 9 decimals).
std::string tickLabel(const Ticks& ticks, double v);

/// True when [a, b] has no width worth an axis: equal ends, or a span below 1e-9 of the values'
/// magnitude (values that differ only by rounding, e.g. 25.46247875282346 and
/// 25.462478752823472), or a non-finite end.
bool flatRange(double a, double b);
/// An axis range showing data in [lo, hi] (either order): `pad` × the span added on each side;
/// a flat range is centred on its value, ± max(0.5, 10 % of it). Non-finite ends are ignored
/// ([0, 1] when both are), and the values are clamped so that the span stays finite. The result
/// has lo < hi and is never flat.
std::pair<double, double> axisRange(double lo, double hi, double pad = 0.08);

/// An orthographic picture of a mesh and a path.
struct RenderRequest {
  int width = 800, height = 600;
  /// Rows: the screen x (right), screen y (up) and depth (toward the viewer) directions,
  /// expressed in the frame of the points below.
  Eigen::Matrix3d R_view = Eigen::Matrix3d::Identity();
  /// Mesh in any frame (same frame as the polyline and markers); any length unit.
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> triangles;
  /// Optional per-triangle colours (else grey), shaded like the grey.
  std::vector<Rgb> triangle_colours;
  /// Points drawn 1 px, nearest first per pixel, hidden by the mesh in front of them.
  std::vector<Eigen::Vector3d> dots;
  std::vector<Rgb> dot_colours;  ///< one per dot (else black)
  /// Drawn 2 px wide on top of the mesh; lighter where the mesh hides it.
  std::vector<Eigen::Vector3d> polyline;
  Rgb polyline_colour{0, 114, 178};
  /// Small squares drawn on top of everything.
  std::vector<std::pair<Eigen::Vector3d, Rgb>> markers;
  /// > 0: a black scale bar this long (the points' unit) in the bottom-left corner, with end
  /// ticks; the caller says its length in a legend.
  double scale_bar = 0.0;
  Rgb background{255, 255, 255};
};
/// Fits the view to the bounding box of mesh, polyline and markers with a margin, and draws
/// the mesh Lambert-shaded in grey (light from the viewer) with a z-buffer. Deterministic.
/// Throws InputError for a non-positive size or a triangle index out of range.
RgbImage renderScene(const RenderRequest& request);
/// renderScene for each of `R_views` in turn (request.R_view is not used): the same images, the
/// dots read once for all views.
std::vector<RgbImage> renderScenes(const RenderRequest& request,
                                   const std::vector<Eigen::Matrix3d>& R_views);

/// A named view direction for renderScene (R_view) of a z-up frame.
struct NamedView {
  const char* name;
  Eigen::Matrix3d R_view;
};
/// The three views of the path and cloud pictures: iso (from +x −y +z), top (looking down z),
/// front (looking along +y).
std::array<NamedView, 3> partViews();
/// The rotations of partViews(), for renderScenes.
std::vector<Eigen::Matrix3d> partViewRotations();

}  // namespace scanplan::cli
