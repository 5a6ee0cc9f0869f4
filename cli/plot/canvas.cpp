#include "cli/plot/canvas.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <memory>
#include <numbers>
#include <string>

#include <cairo-pdf.h>
#include <cairo-svg.h>
#include <fmt/format.h>

#include <scanplan/kinematics/error.h>

namespace scanplan::cli::detail {
namespace {

// SVG and PDF lengths are points (1/72 in), CSS pixels 1/96 in: 0.75 pt per figure pixel keeps
// a vector figure the size of its PNG on screen.
constexpr double kPointsPerPixel = 0.75;

using SurfacePtr = std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)>;

void setColour(cairo_t* cr, Rgb c) {
  cairo_set_source_rgb(cr, c.r / 255.0, c.g / 255.0, c.b / 255.0);
}

cairo_status_t appendToString(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

void check(cairo_status_t status, const char* what) {
  if (status != CAIRO_STATUS_SUCCESS) {
    throw InputError(fmt::format("figure ({}): {}", what, cairo_status_to_string(status)));
  }
}

// Draws on a vector surface writing into `out`, then finishes it (which writes the file).
void drawVector(cairo_surface_t* raw,
                const Drawing& draw,
                const char* what,
                const std::optional<PngSettings>& raster_png = std::nullopt) {
  SurfacePtr surface(raw, cairo_surface_destroy);
  check(cairo_surface_status(surface.get()), what);
  {
    Canvas canvas(surface.get(), kPointsPerPixel);
    if (raster_png) canvas.attachPng(*raster_png);
    draw(canvas);
    check(cairo_status(canvas.context()), what);
  }
  cairo_surface_finish(surface.get());
  check(cairo_surface_status(surface.get()), what);
}

// cairo names an SVG's surfaces and images by process-wide counters ("surface12", "image7"), so
// the second figure of a run would differ from the first: renumber them from 1 in order.
std::string renumberSvgIds(const std::string& svg) {
  std::string out;
  out.reserve(svg.size());
  std::map<std::string, int> numbers;
  std::map<std::string, int> next;
  std::size_t i = 0;
  while (i < svg.size()) {
    const char c = svg[i];
    const bool anchor = (c == '"' || c == '#') && i + 1 < svg.size();
    std::string prefix;
    if (anchor) {
      for (const char* p : {"surface", "image", "source"}) {
        if (svg.compare(i + 1, std::strlen(p), p) == 0) prefix = p;
      }
    }
    const std::size_t digits = i + 1 + prefix.size();
    if (prefix.empty() || digits >= svg.size() ||
        std::isdigit(static_cast<unsigned char>(svg[digits])) == 0) {
      out += c;
      ++i;
      continue;
    }
    std::size_t end = digits;
    while (end < svg.size() && std::isdigit(static_cast<unsigned char>(svg[end])) != 0) ++end;
    const std::string key = prefix + svg.substr(digits, end - digits);
    const auto [at, added] = numbers.emplace(key, 0);
    if (added) at->second = ++next[prefix];
    out += c + prefix + std::to_string(at->second);
    i = end;
  }
  return out;
}

std::string xmlEscape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    out += c == '&' ? "&amp;" : c == '<' ? "&lt;" : c == '>' ? "&gt;" : std::string(1, c);
  }
  return out;
}

}  // namespace

Canvas::Canvas(cairo_surface_t* surface, double scale)
    : surface_(cairo_surface_reference(surface)), cr_(cairo_create(surface)) {
  cairo_scale(cr_, scale, scale);
  cairo_select_font_face(cr_, kFontFamily, CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_font_options_t* options = cairo_font_options_create();
  cairo_font_options_set_hint_metrics(options, CAIRO_HINT_METRICS_OFF);
  cairo_font_options_set_hint_style(options, CAIRO_HINT_STYLE_SLIGHT);
  cairo_font_options_set_antialias(options, CAIRO_ANTIALIAS_GRAY);
  cairo_set_font_options(cr_, options);
  cairo_font_options_destroy(options);
  cairo_set_line_cap(cr_, CAIRO_LINE_CAP_BUTT);
  cairo_set_line_join(cr_, CAIRO_LINE_JOIN_ROUND);
}

Canvas::~Canvas() {
  cairo_destroy(cr_);
  cairo_surface_destroy(surface_);
}

Canvas Canvas::measuring() {
  SurfacePtr surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, 1, 1), cairo_surface_destroy);
  return Canvas(surface.get());
}

double Canvas::textWidth(std::string_view text, double size) const {
  if (text.empty()) return 0.0;
  cairo_set_font_size(cr_, size);
  const std::string s(text);
  cairo_text_extents_t extents;
  cairo_text_extents(cr_, s.c_str(), &extents);
  return extents.x_advance;
}

std::string Canvas::fitText(const std::string& text, double width, double size) const {
  if (textWidth(text, size) <= width) return text;
  std::string cut = text;
  while (!cut.empty() && textWidth(cut + "..", size) > width) {
    cut.pop_back();
    // Drop a whole UTF-8 character: continuation bytes, then the lead byte.
    while (!cut.empty() && (static_cast<unsigned char>(cut.back()) & 0xc0U) == 0x80U) {
      cut.pop_back();
    }
    if (!cut.empty() && static_cast<unsigned char>(cut.back()) >= 0xc0U) cut.pop_back();
  }
  return cut.empty() ? std::string() : cut + "..";
}

void Canvas::text(
    double x, double y, std::string_view text, double size, Rgb colour, Align align, bool up) {
  if (text.empty()) return;
  const double width = textWidth(text, size);
  const double shift = align == Align::kLeft ? 0.0 : align == Align::kCentre ? width / 2 : width;
  cairo_save(cr_);
  cairo_translate(cr_, x, y);
  if (up) cairo_rotate(cr_, -std::numbers::pi / 2);
  cairo_move_to(cr_, -shift, 0.0);
  setColour(cr_, colour);
  const std::string s(text);
  cairo_show_text(cr_, s.c_str());
  cairo_restore(cr_);
}

void Canvas::line(double x0, double y0, double x1, double y1, Rgb colour, double width) {
  if (!std::isfinite(x0) || !std::isfinite(y0) || !std::isfinite(x1) || !std::isfinite(y1)) return;
  cairo_move_to(cr_, x0, y0);
  cairo_line_to(cr_, x1, y1);
  cairo_set_line_width(cr_, width);
  setColour(cr_, colour);
  cairo_stroke(cr_);
}

void Canvas::polyline(const std::vector<std::pair<double, double>>& points,
                      Rgb colour,
                      double width) {
  bool open = false;
  for (const auto& [x, y] : points) {
    if (!std::isfinite(x) || !std::isfinite(y)) {
      open = false;
    } else if (open) {
      cairo_line_to(cr_, x, y);
    } else {
      cairo_move_to(cr_, x, y);
      open = true;
    }
  }
  cairo_set_line_width(cr_, width);
  setColour(cr_, colour);
  cairo_stroke(cr_);
}

void Canvas::fillRect(double x, double y, double w, double h, Rgb colour) {
  cairo_rectangle(cr_, x, y, w, h);
  setColour(cr_, colour);
  cairo_fill(cr_);
}

void Canvas::frame(double x, double y, double w, double h, Rgb colour) {
  cairo_save(cr_);
  cairo_rectangle(cr_, x - 0.5, y - 0.5, w + 1, h + 1);
  cairo_set_line_width(cr_, 1.0);
  cairo_set_line_join(cr_, CAIRO_LINE_JOIN_MITER);  // square corners, whole pixels
  setColour(cr_, colour);
  cairo_stroke(cr_);
  cairo_restore(cr_);
}

void Canvas::image(const RgbImage& raster, double x, double y) {
  if (raster.width <= 0 || raster.height <= 0) return;
  SurfacePtr surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, raster.width, raster.height),
                     cairo_surface_destroy);
  check(cairo_surface_status(surface.get()), "raster");
  cairo_surface_flush(surface.get());
  unsigned char* data = cairo_image_surface_get_data(surface.get());
  const int stride = cairo_image_surface_get_stride(surface.get());
  const std::uint8_t* rgb = raster.rgb.data();
  for (int row = 0; row < raster.height; ++row) {
    auto* pixels =
        reinterpret_cast<std::uint32_t*>(data + static_cast<std::ptrdiff_t>(row) * stride);
    for (int col = 0; col < raster.width; ++col, rgb += 3) {
      pixels[col] = std::uint32_t{rgb[0]} << 16 | std::uint32_t{rgb[1]} << 8 | rgb[2];
    }
  }
  cairo_surface_mark_dirty(surface.get());
  if (raster_png_) {
    // cairo's SVG surface embeds a PNG attached to the image as it is (its own encoder is
    // zlib level 6 with every filter, ~3× slower); the bytes are the same for the same pixels.
    auto png = std::make_unique<std::string>(encodePng(raster, *raster_png_));
    const auto* bytes = reinterpret_cast<const unsigned char*>(png->data());
    const unsigned long size = png->size();
    check(
        cairo_surface_set_mime_data(
            surface.get(), CAIRO_MIME_TYPE_PNG, bytes, size,
            [](void* p) { std::unique_ptr<std::string>(static_cast<std::string*>(p)); }, png.get()),
        "raster");
    png.release();  // owned by the surface now
  }
  cairo_save(cr_);
  cairo_set_source_surface(cr_, surface.get(), x, y);
  cairo_pattern_set_filter(cairo_get_source(cr_), CAIRO_FILTER_NEAREST);
  cairo_rectangle(cr_, x, y, raster.width, raster.height);
  cairo_fill(cr_);
  cairo_restore(cr_);
}

RgbImage renderPixels(int width, int height, const Drawing& draw) {
  if (width <= 0 || height <= 0 || static_cast<double>(width) * height > double{1 << 28}) {
    throw InputError(
        fmt::format("figure: {} × {} px: expected a positive size of at most 2^28 "
                    "pixels",
                    width, height));
  }
  SurfacePtr surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height),
                     cairo_surface_destroy);
  check(cairo_surface_status(surface.get()), "image");
  {
    Canvas canvas(surface.get());
    canvas.fillRect(0, 0, width, height, {255, 255, 255});
    draw(canvas);
    check(cairo_status(canvas.context()), "image");
  }
  cairo_surface_flush(surface.get());
  const unsigned char* data = cairo_image_surface_get_data(surface.get());
  const int stride = cairo_image_surface_get_stride(surface.get());
  RgbImage image = RgbImage::filled(width, height);
  std::uint8_t* rgb = image.rgb.data();
  for (int row = 0; row < height; ++row) {
    const auto* pixels =
        reinterpret_cast<const std::uint32_t*>(data + static_cast<std::ptrdiff_t>(row) * stride);
    for (int col = 0; col < width; ++col, rgb += 3) {
      const std::uint32_t p = pixels[col];
      rgb[0] = static_cast<std::uint8_t>(p >> 16 & 0xffU);
      rgb[1] = static_cast<std::uint8_t>(p >> 8 & 0xffU);
      rgb[2] = static_cast<std::uint8_t>(p & 0xffU);
    }
  }
  return image;
}

std::string renderSvg(int width,
                      int height,
                      const Drawing& draw,
                      const std::string& title,
                      const std::string& description,
                      const std::optional<PngSettings>& raster_png) {
  std::string svg;
  cairo_surface_t* surface = cairo_svg_surface_create_for_stream(
      appendToString, &svg, kPointsPerPixel * width, kPointsPerPixel * height);
  cairo_svg_surface_restrict_to_version(surface, CAIRO_SVG_VERSION_1_1);
  drawVector(
      surface,
      [&](Canvas& canvas) {
        canvas.fillRect(0, 0, width, height, {255, 255, 255});
        draw(canvas);
      },
      "SVG", raster_png);
  svg = renumberSvgIds(svg);
  // The words after the root element's start tag.
  const std::size_t root = svg.find("<svg");
  const std::size_t after = root == std::string::npos ? root : svg.find('>', root);
  if (after != std::string::npos) {
    svg.insert(after + 1, "\n<title>" + xmlEscape(title) + "</title>\n<desc>" +
                              xmlEscape(description) + "</desc>");
  }
  return svg;
}

std::string renderPdf(int width, int height, const Drawing& draw) {
  std::string pdf;
  cairo_surface_t* surface = cairo_pdf_surface_create_for_stream(
      appendToString, &pdf, kPointsPerPixel * width, kPointsPerPixel * height);
  // A fixed date instead of "now": the same figure gives the same bytes.
  cairo_pdf_surface_set_metadata(surface, CAIRO_PDF_METADATA_CREATE_DATE, "2000-01-01T00:00:00Z");
  drawVector(surface, draw, "PDF");
  return pdf;
}

}  // namespace scanplan::cli::detail
