#include "cli/plot/image_io.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>

#include <fmt/format.h>
#include <png.h>
#include <Eigen/Geometry>

#include "cli/io/output.h"
#include "kinematics/error.h"

namespace scanplan::cli {
namespace {

std::size_t pixelCount(int width, int height) {
  return static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
}

std::size_t pixelIndex(int width, int x, int y) {
  return static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
         static_cast<std::size_t>(x);
}

void checkImage(const RgbImage& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != 3 * pixelCount(image.width, image.height)) {
    throw InputError(
        fmt::format("PNG image: {} × {} with {} bytes: expected a positive size "
                    "and 3 bytes per pixel",
                    image.width, image.height, image.rgb.size()));
  }
}

// libpng reports errors by longjmp; the callbacks below hold no objects with destructors at
// the jump, so it only unwinds libpng's C frames.
struct PngSink {
  std::string* out = nullptr;
  std::array<char, 200> message{};
};

void onPngError(png_structp png, png_const_charp message) {
  auto* sink = static_cast<PngSink*>(png_get_error_ptr(png));
  std::snprintf(sink->message.data(), sink->message.size(), "%s", message);
  png_longjmp(png, 1);
}

void onPngWarning(png_structp /*png*/, png_const_charp /*message*/) {}

void onPngWrite(png_structp png, png_bytep data, png_size_t size) {
  auto* sink = static_cast<PngSink*>(png_get_io_ptr(png));
  bool ok = true;
  try {
    sink->out->append(reinterpret_cast<const char*>(data), size);
  } catch (...) {
    ok = false;
  }
  if (!ok) png_error(png, "out of memory");
}

void onPngFlush(png_structp /*png*/) {}

std::string npyHeader(const std::string& descr, const std::vector<std::size_t>& shape) {
  std::string shape_text = "(";
  for (std::size_t i = 0; i < shape.size(); ++i) {
    shape_text += (i ? ", " : "") + std::to_string(shape[i]);
  }
  shape_text += shape.size() == 1 ? ",)" : ")";
  std::string dict =
      "{'descr': '" + descr + "', 'fortran_order': False, 'shape': " + shape_text + ", }";
  // numpy leaves room to grow axis 0 in place (format.GROWTH_AXIS_MAX_DIGITS = 21), then pads
  // magic (8) + length (2) + text + '\n' to a multiple of 64, a full 64 when already aligned.
  if (!shape.empty()) dict.append(21 - std::to_string(shape[0]).size(), ' ');
  const std::size_t text_length = dict.size() + 1;
  const std::size_t padded = text_length + 64 - (10 + text_length) % 64;
  std::string out = "\x93NUMPY";
  out += '\x01';
  out += '\x00';
  out += static_cast<char>(padded & 0xffU);
  out += static_cast<char>((padded >> 8) & 0xffU);
  return out + dict + std::string(padded - text_length, ' ') + "\n";
}

void checkShape(const std::filesystem::path& file,
                std::size_t size,
                const std::vector<std::size_t>& shape) {
  std::size_t product = 1;
  for (const std::size_t n : shape) product *= n;
  if (product != size) {
    throw InputError(fmt::format("{}: {} values for an array of shape ({}): expected {}",
                                 file.string(), size, fmt::join(shape, ", "), product));
  }
}

std::string xmlEscape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    out += c == '&'   ? "&amp;"
           : c == '<' ? "&lt;"
           : c == '>' ? "&gt;"
           : c == '"' ? "&quot;"
                      : std::string(1, c);
  }
  return out;
}

std::uint8_t toByte(double v) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 255.0)));
}

}  // namespace

bool flatRange(double a, double b) {
  if (!std::isfinite(a) || !std::isfinite(b)) return true;
  const double span = std::abs(b - a);
  return !(span > 1e-9 * std::max(std::abs(a), std::abs(b)));  // an infinite span is not flat
}

std::pair<double, double> axisRange(double lo, double hi, double pad) {
  if (!std::isfinite(lo) && !std::isfinite(hi)) return {0.0, 1.0};
  if (!std::isfinite(lo)) lo = hi;
  if (!std::isfinite(hi)) hi = lo;
  if (lo > hi) std::swap(lo, hi);
  // A quarter of the largest double: spans, pads and their sums stay finite.
  constexpr double kLimit = std::numeric_limits<double>::max() / 4;
  lo = std::clamp(lo, -kLimit, kLimit);
  hi = std::clamp(hi, -kLimit, kLimit);
  pad = std::isfinite(pad) ? std::clamp(pad, 0.0, 1.0) : 0.0;
  if (flatRange(lo, hi)) {
    const double mid = 0.5 * lo + 0.5 * hi;
    const double half = std::max(0.5, 0.1 * std::abs(mid));
    return {mid - half, mid + half};
  }
  const double span = hi - lo;
  return {lo - pad * span, hi + pad * span};
}

Ticks niceTicks(double a, double b) {
  Ticks ticks;
  const double lo = std::min(a, b), hi = std::max(a, b);
  // A flat range (also one whose ends differ only by rounding: the steps below would be
  // smaller than the spacing of doubles there) has no ticks.
  if (!std::isfinite(hi - lo) || !(hi - lo > 0) || flatRange(lo, hi)) return ticks;
  const int k = static_cast<int>(std::floor(std::log10(hi - lo)));
  for (int e = k + 1; e >= k - 2; --e) {
    for (const double m : {5.0, 2.0, 1.0}) {
      const double step = m * std::pow(10.0, e);
      if (!std::isfinite(step) || !(step > 0)) continue;
      const double first = std::ceil(lo / step - 1e-9), last = std::floor(hi / step + 1e-9);
      if (!std::isfinite(first) || !std::isfinite(last)) continue;
      const double count = last - first + 1;
      if (count < 5) continue;
      if (count > static_cast<double>(kMaxTicks)) return ticks;  // cannot happen; never loop
      for (int i = 0; i < static_cast<int>(count); ++i) {
        ticks.values.push_back((first + i) * step + 0.0);  // + 0.0: no "-0"
      }
      ticks.decimals = std::max(0, -e);
      return ticks;
    }
  }
  return ticks;
}

std::string tickLabel(const Ticks& ticks, double v) {
  double largest = 0.0;
  for (const double t : ticks.values) largest = std::max(largest, std::abs(t));
  if (std::isfinite(v) && largest < 1e9 && std::abs(v) < 1e9 && ticks.decimals <= 9) {
    return fmt::format("{:.{}f}", v, std::max(ticks.decimals, 0));
  }
  return fmt::format("{:.12g}", v);
}

RgbImage RgbImage::filled(int w, int h, Rgb fill_colour) {
  RgbImage image;
  image.width = w;
  image.height = h;
  image.rgb.resize(3 * pixelCount(std::max(w, 0), std::max(h, 0)));
  for (std::size_t i = 0; i < image.rgb.size(); i += 3) {
    image.rgb[i] = fill_colour.r;
    image.rgb[i + 1] = fill_colour.g;
    image.rgb[i + 2] = fill_colour.b;
  }
  return image;
}

void RgbImage::set(int x, int y, Rgb c) {
  const std::size_t i = 3 * pixelIndex(width, x, y);
  rgb[i] = c.r;
  rgb[i + 1] = c.g;
  rgb[i + 2] = c.b;
}

Rgb RgbImage::at(int x, int y) const {
  const std::size_t i = 3 * pixelIndex(width, x, y);
  return {rgb[i], rgb[i + 1], rgb[i + 2]};
}

std::string encodePng(const RgbImage& image) {
  checkImage(image);
  std::string out;
  PngSink sink;
  sink.out = &out;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &sink, onPngError, onPngWarning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (info == nullptr) {
    png_destroy_write_struct(&png, nullptr);
    throw InputError("PNG encoding: cannot initialise libpng");
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw InputError(fmt::format("PNG encoding: {}", sink.message.data()));
  }
  png_set_write_fn(png, &sink, onPngWrite, onPngFlush);
  // Fixed settings and no tIME/tEXt chunks, so the bytes depend on the pixels only.
  png_set_compression_level(png, 6);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_ALL_FILTERS);
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.width),
               static_cast<png_uint_32>(image.height), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_BASE, PNG_FILTER_TYPE_BASE);
  png_write_info(png, info);
  for (int y = 0; y < image.height; ++y) {
    png_write_row(png, image.rgb.data() + 3 * pixelIndex(image.width, 0, y));
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

void writePng(const std::filesystem::path& file, const RgbImage& image) {
  std::string bytes;
  try {
    bytes = encodePng(image);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", file.string(), e.what()));
  }
  writeFileAtomically(file, bytes);
}

void writeNpy(const std::filesystem::path& file,
              const std::vector<float>& data,
              const std::vector<std::size_t>& shape) {
  checkShape(file, data.size(), shape);
  std::string out = npyHeader("<f4", shape);
  out.reserve(out.size() + 4 * data.size());
  for (const float v : data) {
    const auto bits = std::bit_cast<std::uint32_t>(v);
    for (int byte = 0; byte < 4; ++byte) out += static_cast<char>((bits >> (8 * byte)) & 0xffU);
  }
  writeFileAtomically(file, out);
}

void writeNpy(const std::filesystem::path& file,
              const std::vector<std::uint8_t>& data,
              const std::vector<std::size_t>& shape) {
  checkShape(file, data.size(), shape);
  std::string out = npyHeader("|u1", shape);
  out.append(data.begin(), data.end());
  writeFileAtomically(file, out);
}

Rgb grey(double f) {
  if (std::isnan(f)) return kNanColour;
  const std::uint8_t v = toByte(255.0 * std::clamp(f, 0.0, 1.0));
  return {v, v, v};
}

RgbImage upscale(const RgbImage& image, int factor_x, int factor_y) {
  factor_x = std::max(factor_x, 1);
  factor_y = std::max(factor_y, 1);
  const double pixels =
      static_cast<double>(image.width) * factor_x * static_cast<double>(image.height) * factor_y;
  if (pixels > static_cast<double>(1 << 28)) {
    throw InputError(fmt::format("image {} × {} enlarged {} × {}: expected at most 2^28 pixels",
                                 image.width, image.height, factor_x, factor_y));
  }
  RgbImage out = RgbImage::filled(image.width * factor_x, image.height * factor_y);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) out.set(x, y, image.at(x / factor_x, y / factor_y));
  return out;
}

void drawLine(RgbImage& image, double x0, double y0, double x1, double y1, Rgb colour, int width) {
  if (!std::isfinite(x0) || !std::isfinite(y0) || !std::isfinite(x1) || !std::isfinite(y1)) return;
  width = std::clamp(width, 1, 64);
  // Clipped (Cohen–Sutherland, in long double: differences of far ends neither overflow nor
  // lose the image) to the image grown by the pen, so the stamps below are at most as many as
  // the image's diagonal needs however far away the ends are.
  using Real = long double;
  const Real margin = width + 1, x_lo = -margin, x_hi = image.width + margin, y_lo = -margin,
             y_hi = image.height + margin;
  Real ax = x0, ay = y0, bx = x1, by = y1;
  const auto outcode = [&](Real x, Real y) {
    return (x < x_lo ? 1 : x > x_hi ? 2 : 0) | (y < y_lo ? 4 : y > y_hi ? 8 : 0);
  };
  int ca = outcode(ax, ay), cb = outcode(bx, by);
  for (int i = 0; i < 8 && (ca | cb) != 0; ++i) {
    if ((ca & cb) != 0) return;  // wholly on the outer side of one edge
    const int c = ca != 0 ? ca : cb;
    Real x = 0, y = 0;
    if ((c & 8) != 0) {
      y = y_hi;
      x = ax + (bx - ax) * ((y_hi - ay) / (by - ay));
    } else if ((c & 4) != 0) {
      y = y_lo;
      x = ax + (bx - ax) * ((y_lo - ay) / (by - ay));
    } else if ((c & 2) != 0) {
      x = x_hi;
      y = ay + (by - ay) * ((x_hi - ax) / (bx - ax));
    } else {
      x = x_lo;
      y = ay + (by - ay) * ((x_lo - ax) / (bx - ax));
    }
    if (c == ca) {
      ax = x;
      ay = y;
      ca = outcode(ax, ay);
    } else {
      bx = x;
      by = y;
      cb = outcode(bx, by);
    }
  }
  if ((ca | cb) != 0) return;
  const double sx0 = static_cast<double>(ax), sy0 = static_cast<double>(ay);
  const double sx1 = static_cast<double>(bx), sy1 = static_cast<double>(by);
  const double length = std::hypot(sx1 - sx0, sy1 - sy0);
  const int steps = std::max(1, static_cast<int>(std::ceil(2.0 * length)));
  const int half = width / 2, extra = width % 2 == 0 ? 1 : 0;
  for (int i = 0; i <= steps; ++i) {
    const double s = static_cast<double>(i) / steps;
    const int cx = static_cast<int>(std::floor(sx0 + s * (sx1 - sx0)));
    const int cy = static_cast<int>(std::floor(sy0 + s * (sy1 - sy0)));
    for (int ddy = -half; ddy <= half - extra; ++ddy)
      for (int ddx = -half; ddx <= half - extra; ++ddx) {
        const int x = cx + ddx, y = cy + ddy;
        if (x >= 0 && y >= 0 && x < image.width && y < image.height) image.set(x, y, colour);
      }
  }
}

Rgb categoryColour(int k) {
  // Okabe & Ito (2008), "Color Universal Design"; black last, since maps are mostly grey.
  static constexpr std::array<Rgb, 8> kPalette{{{230, 159, 0},
                                                {86, 180, 233},
                                                {0, 158, 115},
                                                {240, 228, 66},
                                                {0, 114, 178},
                                                {213, 94, 0},
                                                {204, 121, 167},
                                                {0, 0, 0}}};
  return kPalette[static_cast<std::size_t>(((k % 8) + 8) % 8)];
}

std::string svgFigure(const SvgFigure& figure) {
  // Character widths are estimates (7 px per character at 12 px sans-serif).
  constexpr double kChar = 7.0, kTick = 5.0;
  const bool cropped = figure.crop_width > 0 && figure.crop_height > 0;
  const int shown_width = cropped ? figure.crop_width : figure.png_width;
  const int shown_height = cropped ? figure.crop_height : figure.png_height;
  const double scale =
      std::min(720.0 / std::max(shown_width, 1), 480.0 / std::max(shown_height, 1));
  const double pw = scale * std::max(shown_width, 1), ph = scale * std::max(shown_height, 1);
  // A flat or non-finite range would put every tick and coordinate at infinity.
  const auto range = [](double a, double b) {
    return flatRange(a, b) || !std::isfinite(b - a) ? axisRange(a, b, 0.0) : std::pair{a, b};
  };
  const std::pair<double, double> x_range = range(figure.x_min, figure.x_max);
  const std::pair<double, double> y_range = range(figure.y_min, figure.y_max);
  const double x_min = x_range.first, x_max = x_range.second;
  const double y_min = y_range.first, y_max = y_range.second;
  const Ticks x_ticks = niceTicks(x_min, x_max);
  const Ticks y_ticks = niceTicks(y_min, y_max);
  const auto label = [](const Ticks& t, double v) { return tickLabel(t, v); };
  std::size_t y_chars = 1, legend_chars = 0;
  for (const double v : y_ticks.values) y_chars = std::max(y_chars, label(y_ticks, v).size());
  for (const auto& entry : figure.legend)
    legend_chars = std::max(legend_chars, entry.second.size());
  const double left = 34 + kTick + 4 + kChar * static_cast<double>(y_chars);
  const double top = figure.title.empty() ? 16 : 44;
  const double right = figure.legend.empty() ? 24 : 44 + kChar * static_cast<double>(legend_chars);
  const double width = left + pw + right;
  const double height =
      std::max(top + ph + 56, top + 20.0 * static_cast<double>(figure.legend.size()) + 16);
  const auto px = [&](double v) { return left + (v - x_min) / (x_max - x_min) * pw; };
  const auto py = [&](double v) { return top + (y_max - v) / (y_max - y_min) * ph; };

  std::string s = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" "
      "width=\"{0:.0f}\" height=\"{1:.0f}\" viewBox=\"0 0 {0:.0f} {1:.0f}\" "
      "font-family=\"sans-serif\" font-size=\"12\">\n"
      "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
      std::ceil(width), std::ceil(height));
  if (!figure.title.empty()) {
    s += fmt::format(
        "<text x=\"{:.1f}\" y=\"26\" text-anchor=\"middle\" font-size=\"16\">{}"
        "</text>\n",
        left + pw / 2, xmlEscape(figure.title));
  }
  const std::string href = xmlEscape(figure.png_file);
  if (cropped) {
    // A viewport onto the crop rectangle of the whole image (a nested svg clips to it).
    s += fmt::format(
        "<svg x=\"{1:.1f}\" y=\"{2:.1f}\" width=\"{3:.1f}\" height=\"{4:.1f}\" "
        "viewBox=\"{5} {6} {7} {8}\" preserveAspectRatio=\"none\" overflow=\"hidden\">"
        "<image href=\"{0}\" xlink:href=\"{0}\" x=\"0\" y=\"0\" width=\"{9}\" height=\"{10}\" "
        "preserveAspectRatio=\"none\" image-rendering=\"optimizeSpeed\" "
        "style=\"image-rendering: pixelated\"/></svg>\n",
        href, left, top, pw, ph, figure.crop_x, figure.crop_y, figure.crop_width,
        figure.crop_height, std::max(figure.png_width, 1), std::max(figure.png_height, 1));
  } else {
    s += fmt::format(
        "<image href=\"{0}\" xlink:href=\"{0}\" x=\"{1:.1f}\" y=\"{2:.1f}\" width=\"{3:.1f}\" "
        "height=\"{4:.1f}\" preserveAspectRatio=\"none\" image-rendering=\"optimizeSpeed\" "
        "style=\"image-rendering: pixelated\"/>\n",
        href, left, top, pw, ph);
  }
  s += fmt::format(
      "<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"none\" "
      "stroke=\"black\"/>\n",
      left, top, pw, ph);
  for (const double v : x_ticks.values) {
    const double x = px(v);
    s += fmt::format(
        "<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{0:.1f}\" y2=\"{2:.1f}\" "
        "stroke=\"black\"/><text x=\"{0:.1f}\" y=\"{3:.1f}\" "
        "text-anchor=\"middle\">{4}</text>\n",
        x, top + ph, top + ph + kTick, top + ph + kTick + 13, label(x_ticks, v));
  }
  for (const double v : y_ticks.values) {
    const double y = py(v);
    s += fmt::format(
        "<line x1=\"{0:.1f}\" y1=\"{2:.1f}\" x2=\"{1:.1f}\" y2=\"{2:.1f}\" "
        "stroke=\"black\"/><text x=\"{3:.1f}\" y=\"{4:.1f}\" "
        "text-anchor=\"end\">{5}</text>\n",
        left - kTick, left, y, left - kTick - 3, y + 4, label(y_ticks, v));
  }
  if (!figure.x_label.empty()) {
    s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>\n",
                     left + pw / 2, top + ph + 42, xmlEscape(figure.x_label));
  }
  if (!figure.y_label.empty()) {
    s += fmt::format(
        "<text transform=\"translate(16 {:.1f}) rotate(-90)\" "
        "text-anchor=\"middle\">{}</text>\n",
        top + ph / 2, xmlEscape(figure.y_label));
  }
  for (std::size_t i = 0; i < figure.legend.size(); ++i) {
    const double x = left + pw + 16, y = top + 20.0 * static_cast<double>(i);
    s += fmt::format(
        "<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"14\" height=\"14\" fill=\"{}\" "
        "stroke=\"black\" stroke-width=\"0.5\"/><text x=\"{:.1f}\" y=\"{:.1f}\">{}"
        "</text>\n",
        x, y,
        fmt::format("rgb({},{},{})", figure.legend[i].first.r, figure.legend[i].first.g,
                    figure.legend[i].first.b),
        x + 20, y + 11, xmlEscape(figure.legend[i].second));
  }
  return s + "</svg>\n";
}

RgbImage renderScene(const RenderRequest& request) {
  const int w = request.width, h = request.height;
  if (w <= 0 || h <= 0) {
    throw InputError(fmt::format("render: image size {} × {}: expected positive", w, h));
  }
  const auto n_vertices = static_cast<int>(request.vertices.size());
  for (const Eigen::Vector3i& t : request.triangles) {
    if (t.minCoeff() < 0 || t.maxCoeff() >= n_vertices) {
      throw InputError(
          fmt::format("render: triangle ({}, {}, {}): expected vertex indices in "
                      "[0, {})",
                      t.x(), t.y(), t.z(), n_vertices));
    }
  }
  RgbImage image = RgbImage::filled(w, h, request.background);

  // Fit the view: bounding box of everything in view coordinates.
  std::vector<Eigen::Vector3d> mesh, path;
  Eigen::AlignedBox3d box;
  const auto project = [&](const std::vector<Eigen::Vector3d>& in,
                           std::vector<Eigen::Vector3d>& out) {
    for (const Eigen::Vector3d& p : in) {
      out.push_back(request.R_view * p);
      if (out.back().allFinite()) box.extend(out.back());
    }
  };
  std::vector<Eigen::Vector3d> dots;
  project(request.vertices, mesh);
  project(request.polyline, path);
  project(request.dots, dots);
  for (const auto& marker : request.markers) {
    const Eigen::Vector3d p = request.R_view * marker.first;
    if (p.allFinite()) box.extend(p);
  }
  if (box.isEmpty()) return image;
  const double margin = 0.05 * std::min(w, h) + 5;
  const Eigen::Vector3d size = box.sizes().cwiseMax(1e-12), centre = box.center();
  const double scale =
      std::max(1e-12, std::min((w - 2 * margin) / size.x(), (h - 2 * margin) / size.y()));
  const auto toScreen = [&](const Eigen::Vector3d& p) -> Eigen::Vector3d {
    return {0.5 * w + (p.x() - centre.x()) * scale, 0.5 * h - (p.y() - centre.y()) * scale, p.z()};
  };
  for (auto& p : mesh) p = toScreen(p);
  for (auto& p : path) p = toScreen(p);
  for (auto& p : dots) p = toScreen(p);

  // Mesh: edge functions at pixel centres, z-buffer keeps the largest depth (nearest).
  std::vector<double> depth(pixelCount(w, h), -std::numeric_limits<double>::infinity());
  const auto edge = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b, double x, double y) {
    return (b.x() - a.x()) * (y - a.y()) - (b.y() - a.y()) * (x - a.x());
  };
  for (const Eigen::Vector3i& t : request.triangles) {
    const Eigen::Vector3d& a = mesh[static_cast<std::size_t>(t.x())];
    const Eigen::Vector3d& b = mesh[static_cast<std::size_t>(t.y())];
    const Eigen::Vector3d& c = mesh[static_cast<std::size_t>(t.z())];
    const double area = edge(a, b, c.x(), c.y());
    if (!(std::abs(area) > 1e-12) || !a.allFinite() || !b.allFinite() || !c.allFinite()) continue;
    // Screen differences mapped back to view axes (times `scale`) for the Lambert term.
    const Eigen::Vector3d normal = (b - a)
                                       .cwiseProduct(Eigen::Vector3d(1, -1, scale))
                                       .cross((c - a).cwiseProduct(Eigen::Vector3d(1, -1, scale)));
    const double lambert = std::abs(normal.z()) / normal.norm();
    const double shade = 0.2 + 0.8 * lambert;
    const std::size_t ti = static_cast<std::size_t>(&t - request.triangles.data());
    const Rgb fill = ti < request.triangle_colours.size()
                         ? Rgb{toByte(shade * request.triangle_colours[ti].r),
                               toByte(shade * request.triangle_colours[ti].g),
                               toByte(shade * request.triangle_colours[ti].b)}
                         : Rgb{toByte(235.0 * shade), toByte(235.0 * shade), toByte(235.0 * shade)};
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(w - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(h - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const double sx = x + 0.5, sy = y + 0.5;
        const double wa = edge(b, c, sx, sy) / area, wb = edge(c, a, sx, sy) / area;
        const double wc = 1.0 - wa - wb;
        if (wa < 0 || wb < 0 || wc < 0) continue;
        const double z = wa * a.z() + wb * b.z() + wc * c.z();
        double& zbuf = depth[pixelIndex(w, x, y)];
        if (z > zbuf) {
          zbuf = z;
          image.set(x, y, fill);
        }
      }
    }
  }

  // Dots: 1 px, the nearest wins; a mesh surface in front hides them.
  const double dot_tolerance = 1e-3 * size.norm();
  for (std::size_t i = 0; i < dots.size(); ++i) {
    const Eigen::Vector3d& p = dots[i];
    if (!p.allFinite()) continue;
    const int x = static_cast<int>(std::floor(p.x())), y = static_cast<int>(std::floor(p.y()));
    if (x < 0 || y < 0 || x >= w || y >= h) continue;
    double& zbuf = depth[pixelIndex(w, x, y)];
    if (p.z() + dot_tolerance < zbuf) continue;
    zbuf = std::max(zbuf, p.z());
    image.set(x, y, i < request.dot_colours.size() ? request.dot_colours[i] : Rgb{});
  }

  // Path: 2 px wide, stamped every half pixel; behind the mesh in a lighter tint.
  const Rgb colour = request.polyline_colour;
  const Rgb tint{toByte(0.4 * colour.r + 153), toByte(0.4 * colour.g + 153),
                 toByte(0.4 * colour.b + 153)};
  const double depth_tolerance = 1e-3 * size.norm();
  std::vector<bool> path_visible(pixelCount(w, h), false);
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const Eigen::Vector3d p0 = path[i], d = path[i + 1] - p0;
    if (!p0.allFinite() || !d.allFinite()) continue;
    const int steps = static_cast<int>(std::ceil(2 * d.head<2>().norm())) + 1;
    for (int k = 0; k <= steps; ++k) {
      const Eigen::Vector3d p = p0 + d * (static_cast<double>(k) / steps);
      const int ix0 = std::max(0, static_cast<int>(std::ceil(p.x() - 1.5)));
      const int ix1 = std::min(w - 1, static_cast<int>(std::floor(p.x() + 0.5)));
      const int iy0 = std::max(0, static_cast<int>(std::ceil(p.y() - 1.5)));
      const int iy1 = std::min(h - 1, static_cast<int>(std::floor(p.y() + 0.5)));
      for (int y = iy0; y <= iy1; ++y) {
        for (int x = ix0; x <= ix1; ++x) {
          const std::size_t at = pixelIndex(w, x, y);
          if (p.z() >= depth[at] - depth_tolerance) {
            path_visible[at] = true;
            image.set(x, y, colour);
          } else if (!path_visible[at]) {
            image.set(x, y, tint);
          }
        }
      }
    }
  }

  // Markers: 7 px squares with a black outline, on top.
  for (const auto& [point, marker_colour] : request.markers) {
    const Eigen::Vector3d p = toScreen(request.R_view * point);
    if (!p.allFinite()) continue;
    const int cx = static_cast<int>(std::floor(p.x())), cy = static_cast<int>(std::floor(p.y()));
    for (int y = std::max(0, cy - 4); y <= std::min(h - 1, cy + 4); ++y) {
      for (int x = std::max(0, cx - 4); x <= std::min(w - 1, cx + 4); ++x) {
        const bool border = std::abs(x - cx) == 4 || std::abs(y - cy) == 4;
        image.set(x, y, border ? Rgb{0, 0, 0} : marker_colour);
      }
    }
  }
  return image;
}

std::array<NamedView, 3> partViews() {
  return {{{"iso", (Eigen::Matrix3d() << 0.7071, -0.7071, 0, 0.4082, 0.4082, 0.8165, -0.5774,
                    -0.5774, 0.5774)
                       .finished()},
           {"top", Eigen::Matrix3d::Identity()},
           {"front", (Eigen::Matrix3d() << 1, 0, 0, 0, 0, 1, 0, -1, 0).finished()}}};
}

}  // namespace scanplan::cli
