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
#include <optional>

#include <fmt/format.h>
#include <png.h>
#include <Eigen/Geometry>

#include <scanplan/kinematics/error.h>
#include "cli/io/output.h"

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
  const std::size_t size = 3 * pixelCount(std::max(w, 0), std::max(h, 0));
  if (fill_colour.r == fill_colour.g && fill_colour.g == fill_colour.b) {
    image.rgb.assign(size, fill_colour.r);  // a grey: one byte repeated (a memset)
    return image;
  }
  image.rgb.resize(size);
  // One pixel, then the filled part copied onto the rest, doubling each time.
  std::size_t filled = std::min<std::size_t>(3, size);
  const std::array<std::uint8_t, 3> pixel{fill_colour.r, fill_colour.g, fill_colour.b};
  std::copy_n(pixel.begin(), filled, image.rgb.begin());
  while (filled < size) {
    const std::size_t n = std::min(filled, size - filled);
    std::copy_n(image.rgb.begin(), n, image.rgb.begin() + static_cast<std::ptrdiff_t>(filled));
    filled += n;
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

static_assert(PngSettings{}.filters == PNG_FILTER_UP);
static_assert(WriteSettings::reference().png.filters == PNG_ALL_FILTERS);
static_assert(WriteSettings{}.views.filters == PNG_FILTER_NONE);

std::string encodePng(const RgbImage& image, const PngSettings& settings) {
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
  png_set_compression_level(png, std::clamp(settings.level, 0, 9));
  png_set_filter(png, PNG_FILTER_TYPE_BASE, settings.filters);
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

void writePng(const std::filesystem::path& file,
              const RgbImage& image,
              const PngSettings& settings) {
  std::string bytes;
  try {
    bytes = encodePng(image, settings);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", file.string(), e.what()));
  }
  writeFileAtomically(file, bytes);
}

void writeNpy(const std::filesystem::path& file,
              const std::vector<float>& data,
              const std::vector<std::size_t>& shape,
              bool stream) {
  checkShape(file, data.size(), shape);
  const std::string header = npyHeader("<f4", shape);
  if (stream && std::endian::native == std::endian::little) {
    // '<f4' is the machine's own float: the values go to the file as they lie in memory.
    writeFileAtomically(
        file, {header, {reinterpret_cast<const char*>(data.data()), sizeof(float) * data.size()}});
    return;
  }
  std::string out = header;
  out.reserve(out.size() + 4 * data.size());
  for (const float v : data) {
    const auto bits = std::bit_cast<std::uint32_t>(v);
    for (int byte = 0; byte < 4; ++byte) out += static_cast<char>((bits >> (8 * byte)) & 0xffU);
  }
  writeFileAtomically(file, out);
}

void writeNpy(const std::filesystem::path& file,
              const std::vector<std::uint8_t>& data,
              const std::vector<std::size_t>& shape,
              bool stream) {
  checkShape(file, data.size(), shape);
  const std::string header = npyHeader("|u1", shape);
  if (stream) {
    writeFileAtomically(file, {header, {reinterpret_cast<const char*>(data.data()), data.size()}});
    return;
  }
  writeFileAtomically(file, header + std::string(data.begin(), data.end()));
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
  RgbImage out;
  out.width = image.width * factor_x;
  out.height = image.height * factor_y;
  out.rgb.resize(3 * pixelCount(out.width, out.height));
  const std::size_t row_bytes = 3 * static_cast<std::size_t>(out.width);
  auto to = out.rgb.begin();
  for (int y = 0; y < image.height; ++y) {
    // The row widened once, then copied factor_y - 1 times below itself.
    const auto row = to;
    auto from = image.rgb.begin() + static_cast<std::ptrdiff_t>(3 * pixelIndex(image.width, 0, y));
    for (int x = 0; x < image.width; ++x, from += 3) {
      for (int k = 0; k < factor_x; ++k) to = std::copy_n(from, 3, to);
    }
    for (int k = 1; k < factor_y; ++k) to = std::copy_n(row, row_bytes, to);
  }
  return out;
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

namespace {

void checkRenderRequest(const RenderRequest& request) {
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
}

// The scene in view coordinates, and the bounding box of everything in view (markers and dots
// too; the dots, often millions, are turned again where they are drawn rather than kept).
struct ViewScene {
  std::vector<Eigen::Vector3d> mesh, path;
  Eigen::AlignedBox3d box;
};

// The scene turned by R_view; the dots only in its box (see extendByDots).
ViewScene viewScene(const RenderRequest& request, const Eigen::Matrix3d& R_view) {
  ViewScene scene;
  const auto project = [&](const std::vector<Eigen::Vector3d>& in,
                           std::vector<Eigen::Vector3d>& out) {
    for (const Eigen::Vector3d& p : in) {
      out.push_back(R_view * p);
      if (out.back().allFinite()) scene.box.extend(out.back());
    }
  };
  project(request.vertices, scene.mesh);
  project(request.polyline, scene.path);
  for (const auto& marker : request.markers) {
    const Eigen::Vector3d p = R_view * marker.first;
    if (p.allFinite()) scene.box.extend(p);
  }
  return scene;
}

// View coordinates → screen pixels: x right, y down, depth kept.
struct ScreenFit {
  int w, h;
  Eigen::Vector3d size, centre;  // of the box in view
  double scale;                  // pixels per view unit
  Eigen::Vector3d toScreen(const Eigen::Vector3d& p) const {
    return {0.5 * w + (p.x() - centre.x()) * scale, 0.5 * h - (p.y() - centre.y()) * scale, p.z()};
  }
};

// Fits a non-empty box in view coordinates to a w × h image with a margin.
ScreenFit fitToScreen(const Eigen::AlignedBox3d& box, int w, int h) {
  const double margin = 0.05 * std::min(w, h) + 5;
  const Eigen::Vector3d size = box.sizes().cwiseMax(1e-12), centre = box.center();
  const double scale =
      std::max(1e-12, std::min((w - 2 * margin) / size.x(), (h - 2 * margin) / size.y()));
  return {w, h, size, centre, scale};
}

double edgeFunction(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double x, double y) {
  return (b.x() - a.x()) * (y - a.y()) - (b.y() - a.y()) * (x - a.x());
}

// The fill of triangle `ti` (its colour, else grey) at a Lambert shade.
Rgb triangleFill(const RenderRequest& request, std::size_t ti, double shade) {
  return ti < request.triangle_colours.size()
             ? Rgb{toByte(shade * request.triangle_colours[ti].r),
                   toByte(shade * request.triangle_colours[ti].g),
                   toByte(shade * request.triangle_colours[ti].b)}
             : Rgb{toByte(235.0 * shade), toByte(235.0 * shade), toByte(235.0 * shade)};
}

// One edge p → q of a triangle on screen, to narrow each line of pixels across its bounding box
// (a row, or a column for a tall triangle) to those that may lie inside: where the edge function
// has the sign of the triangle's area. The exact test at each pixel decides; the margin is far
// above the rounding of the crossing (~1e-10 px at these sizes), and an edge (nearly) along the
// lines narrows nothing.
class LineEdge {
 public:
  // `columns`: the lines are columns (x fixed, y varies), else rows.
  LineEdge(const Eigen::Vector3d& p, const Eigen::Vector3d& q, bool positive, bool columns) {
    const double po = columns ? p.x() : p.y(), pi = columns ? p.y() : p.x();
    const double qo = columns ? q.x() : q.y(), qi = columns ? q.y() : q.x();
    const double d = qo - po;
    if (!(std::abs(d) >= 1e-2)) return;
    o0_ = po;
    i0_ = pi;
    slope_ = (qi - pi) / d;
    // edgeFunction(p, q, x, y) = (q.x - p.x)(y - p.y) - (q.y - p.y)(x - p.x) grows along a row
    // where q.y < p.y, along a column where q.x > p.x.
    const bool grows = columns ? d > 0 : d < 0;
    side_ = grows == positive ? 1 : -1;
  }
  // [lo, hi] narrowed to the pixels whose centres may be inside on the line whose centre is at
  // `o` (y of a row, x of a column).
  void narrow(double o, int& lo, int& hi) const {
    if (side_ == 0) return;
    const double at = std::clamp(i0_ + (o - o0_) * slope_ - 0.5, lo - 2.0, hi + 2.0);
    if (side_ > 0) {
      lo = std::max(lo, static_cast<int>(std::ceil(at - kMargin)));
    } else {
      hi = std::min(hi, static_cast<int>(std::floor(at + kMargin)));
    }
  }

 private:
  static constexpr double kMargin = 1e-4;  // px
  double o0_ = 0, i0_ = 0, slope_ = 0;
  int side_ = 0;  // +1: inside beyond the crossing, −1: before it, 0: no narrowing
};

// Mesh: edge functions at pixel centres, z-buffer keeps the largest depth (nearest). A triangle's
// pixels are visited row by row, or column by column when it is taller than wide (the mesh's
// slivers): each pixel once either way, so the picture is the same.
void drawMesh(const RenderRequest& request,
              const std::vector<Eigen::Vector3d>& mesh,
              double scale,
              std::vector<double>& depth,
              RgbImage& image) {
  const int w = image.width, h = image.height;
  for (const Eigen::Vector3i& t : request.triangles) {
    const Eigen::Vector3d& a = mesh[static_cast<std::size_t>(t.x())];
    const Eigen::Vector3d& b = mesh[static_cast<std::size_t>(t.y())];
    const Eigen::Vector3d& c = mesh[static_cast<std::size_t>(t.z())];
    const double area = edgeFunction(a, b, c.x(), c.y());
    if (!(std::abs(area) > 1e-12) || !a.allFinite() || !b.allFinite() || !c.allFinite()) continue;
    // Screen differences mapped back to view axes (times `scale`) for the Lambert term.
    const Eigen::Vector3d normal = (b - a)
                                       .cwiseProduct(Eigen::Vector3d(1, -1, scale))
                                       .cross((c - a).cwiseProduct(Eigen::Vector3d(1, -1, scale)));
    const double lambert = std::abs(normal.z()) / normal.norm();
    const double shade = 0.2 + 0.8 * lambert;
    const std::size_t ti = static_cast<std::size_t>(&t - request.triangles.data());
    const Rgb fill = triangleFill(request, ti, shade);
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(w - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(h - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    const auto pixel = [&](int x, int y) {
      const double sx = x + 0.5, sy = y + 0.5;
      const double wa = edgeFunction(b, c, sx, sy) / area, wb = edgeFunction(c, a, sx, sy) / area;
      const double wc = 1.0 - wa - wb;
      if (wa < 0 || wb < 0 || wc < 0) return;
      const double z = wa * a.z() + wb * b.z() + wc * c.z();
      double& zbuf = depth[pixelIndex(w, x, y)];
      if (z > zbuf) {
        zbuf = z;
        image.set(x, y, fill);
      }
    };
    const bool columns = (x1 - x0) < (y1 - y0);
    const bool positive = area > 0;
    const LineEdge ea(b, c, positive, columns), eb(c, a, positive, columns),
        ec(a, b, positive, columns);
    const int o0 = columns ? x0 : y0, o1 = columns ? x1 : y1;
    for (int o = o0; o <= o1; ++o) {
      int lo = columns ? y0 : x0, hi = columns ? y1 : x1;
      ea.narrow(o + 0.5, lo, hi);
      eb.narrow(o + 0.5, lo, hi);
      ec.narrow(o + 0.5, lo, hi);
      for (int i = lo; i <= hi; ++i) columns ? pixel(o, i) : pixel(i, o);
    }
  }
}

// One view being drawn.
struct View {
  Eigen::Matrix3d R_view;
  ViewScene scene;
  std::optional<ScreenFit> fit;  // none: nothing in view
  double tolerance = 0;          // depth within which a dot or the path counts as on the mesh
  std::vector<double> depth;     // z-buffer: the largest depth (nearest) so far
  RgbImage image;
};

// A view's rotation as plain rows: q_i = (R_i0 p_0 + R_i1 p_1) + R_i2 p_2, the sums in the order
// Eigen's 3 × 3 product makes them (the same bits), with nothing else loaded per dot.
struct Rows {
  double r[9];
  explicit Rows(const Eigen::Matrix3d& R) {
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) r[3 * i + k] = R(i, k);
  }
  double row(int i, const Eigen::Vector3d& p) const {
    return r[3 * i] * p.x() + r[3 * i + 1] * p.y() + r[3 * i + 2] * p.z();
  }
};

// The dots in every view's box: one pass over them for all views (they are read from memory
// once, not once a view).
void extendByDots(const std::vector<Eigen::Vector3d>& dots, std::vector<View>& views) {
  struct Extent {
    Rows R;
    Eigen::Vector3d lo, hi;
  };
  std::vector<Extent> extents;
  for (const View& v : views)
    extents.push_back({Rows(v.R_view), v.scene.box.min(), v.scene.box.max()});
  for (const Eigen::Vector3d& p : dots) {
    for (Extent& e : extents) {
      const Eigen::Vector3d q(e.R.row(0, p), e.R.row(1, p), e.R.row(2, p));
      if (!q.allFinite()) continue;
      e.lo = e.lo.cwiseMin(q);
      e.hi = e.hi.cwiseMax(q);
    }
  }
  for (std::size_t k = 0; k < views.size(); ++k) {
    views[k].scene.box = Eigen::AlignedBox3d(extents[k].lo, extents[k].hi);
  }
}

// One view's dot drawing: its rotation, its fit to the screen, its buffers.
struct DotView {
  Rows R;
  double cx, cy, scale, half_w, half_h, tolerance;
  int w, h;
  double* depth;
  std::uint8_t* rgb;
};

// Dots: 1 px, the nearest wins; a mesh surface in front (closer than the view's tolerance) hides
// them. All views in one pass over the dots. The pixel is the floor of the screen position
// (ScreenFit::toScreen, the same arithmetic), taken as a truncation once it is known to be in
// [0, w) × [0, h).
void drawDots(const RenderRequest& request, std::vector<View>& views) {
  std::vector<DotView> shown;
  for (View& v : views) {
    if (!v.fit) continue;
    const ScreenFit& f = *v.fit;
    shown.push_back({Rows(v.R_view), f.centre.x(), f.centre.y(), f.scale, 0.5 * f.w, 0.5 * f.h,
                     v.tolerance, v.image.width, v.image.height, v.depth.data(),
                     v.image.rgb.data()});
  }
  const std::vector<Eigen::Vector3d>& dots = request.dots;
  for (std::size_t i = 0; i < dots.size(); ++i) {
    const Rgb colour = i < request.dot_colours.size() ? request.dot_colours[i] : Rgb{};
    for (const DotView& v : shown) {
      const double sx = v.half_w + (v.R.row(0, dots[i]) - v.cx) * v.scale;
      const double sy = v.half_h - (v.R.row(1, dots[i]) - v.cy) * v.scale;
      const double z = v.R.row(2, dots[i]);
      if (!(sx >= 0 && sx < v.w && sy >= 0 && sy < v.h) || !std::isfinite(z)) continue;
      const std::size_t at = pixelIndex(v.w, static_cast<int>(sx), static_cast<int>(sy));
      double& zbuf = v.depth[at];
      if (z + v.tolerance < zbuf) continue;
      zbuf = std::max(zbuf, z);
      v.rgb[3 * at] = colour.r;
      v.rgb[3 * at + 1] = colour.g;
      v.rgb[3 * at + 2] = colour.b;
    }
  }
}

// Path: 2 px wide, stamped every half pixel; behind the mesh (by more than `tolerance`) in a
// lighter tint.
void drawPath(const std::vector<Eigen::Vector3d>& path,
              Rgb colour,
              double tolerance,
              const std::vector<double>& depth,
              RgbImage& image) {
  const int w = image.width, h = image.height;
  const Rgb tint{toByte(0.4 * colour.r + 153), toByte(0.4 * colour.g + 153),
                 toByte(0.4 * colour.b + 153)};
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
          if (p.z() >= depth[at] - tolerance) {
            path_visible[at] = true;
            image.set(x, y, colour);
          } else if (!path_visible[at]) {
            image.set(x, y, tint);
          }
        }
      }
    }
  }
}

// Markers: 7 px squares with a black outline, on top.
void drawMarkers(const RenderRequest& request,
                 const Eigen::Matrix3d& R_view,
                 const ScreenFit& fit,
                 RgbImage& image) {
  const int w = image.width, h = image.height;
  for (const auto& [point, marker_colour] : request.markers) {
    const Eigen::Vector3d p = fit.toScreen(R_view * point);
    if (!p.allFinite()) continue;
    const int cx = static_cast<int>(std::floor(p.x())), cy = static_cast<int>(std::floor(p.y()));
    for (int y = std::max(0, cy - 4); y <= std::min(h - 1, cy + 4); ++y) {
      for (int x = std::max(0, cx - 4); x <= std::min(w - 1, cx + 4); ++x) {
        const bool border = std::abs(x - cx) == 4 || std::abs(y - cy) == 4;
        image.set(x, y, border ? Rgb{0, 0, 0} : marker_colour);
      }
    }
  }
}

// The scale bar: `length` in the points' unit at the fit's scale, 12 px from the bottom-left.
void drawScaleBar(double length, const ScreenFit& fit, RgbImage& image) {
  const int px = static_cast<int>(std::lround(length * fit.scale));
  if (length <= 0.0 || px < 4) return;
  const int x0 = 12, y0 = image.height - 14;
  for (int x = x0; x <= std::min(image.width - 1, x0 + px); ++x) {
    for (int dy = -1; dy <= 1; ++dy) image.set(x, y0 + dy, Rgb{0, 0, 0});
  }
  for (const int x : {x0, std::min(image.width - 1, x0 + px)}) {
    for (int y = y0 - 6; y <= y0 + 6; ++y) {
      if (y >= 0 && y < image.height) image.set(x, y, Rgb{0, 0, 0});
    }
  }
}

}  // namespace

RgbImage renderScene(const RenderRequest& request) {
  return std::move(renderScenes(request, {request.R_view}).front());
}

std::vector<RgbImage> renderScenes(const RenderRequest& request,
                                   const std::vector<Eigen::Matrix3d>& R_views) {
  checkRenderRequest(request);
  const int w = request.width, h = request.height;
  std::vector<View> views(R_views.size());
  for (std::size_t k = 0; k < views.size(); ++k) {
    views[k].R_view = R_views[k];
    views[k].scene = viewScene(request, R_views[k]);
    views[k].image = RgbImage::filled(w, h, request.background);
  }
  extendByDots(request.dots, views);
  for (View& v : views) {
    // Fit the view: bounding box of everything in view coordinates.
    if (v.scene.box.isEmpty()) continue;
    v.fit = fitToScreen(v.scene.box, w, h);
    for (auto& p : v.scene.mesh) p = v.fit->toScreen(p);
    for (auto& p : v.scene.path) p = v.fit->toScreen(p);
    v.depth.assign(pixelCount(w, h), -std::numeric_limits<double>::infinity());
    drawMesh(request, v.scene.mesh, v.fit->scale, v.depth, v.image);
    v.tolerance = 1e-3 * v.fit->size.norm();
  }
  drawDots(request, views);
  std::vector<RgbImage> images;
  for (View& v : views) {
    if (v.fit) {
      drawPath(v.scene.path, request.polyline_colour, v.tolerance, v.depth, v.image);
      drawMarkers(request, v.R_view, *v.fit, v.image);
      drawScaleBar(request.scale_bar, *v.fit, v.image);
    }
    images.push_back(std::move(v.image));
  }
  return images;
}

std::array<NamedView, 3> partViews() {
  return {{{"iso", (Eigen::Matrix3d() << 0.7071, -0.7071, 0, 0.4082, 0.4082, 0.8165, -0.5774,
                    -0.5774, 0.5774)
                       .finished()},
           {"top", Eigen::Matrix3d::Identity()},
           {"front", (Eigen::Matrix3d() << 1, 0, 0, 0, 0, 1, 0, -1, 0).finished()}}};
}

std::vector<Eigen::Matrix3d> partViewRotations() {
  std::vector<Eigen::Matrix3d> R;
  for (const NamedView& view : partViews()) R.push_back(view.R_view);
  return R;
}

}  // namespace scanplan::cli
