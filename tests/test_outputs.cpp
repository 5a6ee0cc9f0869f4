// The fast output writers against the ones they replaced (WriteSettings::reference):
// the same files — byte for byte, or pixel for pixel where only PNG compression differs —, the
// streamed and pieced atomic writes, and the views drawn together as each is drawn alone.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/pipeline/plan_scan.h>
#include "cli/commands/commands.h"
#include "cli/io/output.h"
#include "cli/plot/image_io.h"
#include "io_support.h"
#include "test_support.h"

namespace {

using namespace scanplan;
namespace fs = std::filesystem;

class Outputs : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("scanplan_test_outputs_" + std::string(info->name()) + "_" +
                                        std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path dir_;
};

std::string readBytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// The files under `dir`, by their path relative to it.
std::map<std::string, std::string> filesUnder(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) files[fs::relative(e.path(), dir).string()] = readBytes(e.path());
  }
  return files;
}

std::string base64Decode(const std::string& text) {
  static const std::string kDigits =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  unsigned value = 0;
  int bits = -8;
  for (const char c : text) {
    const std::size_t digit = kDigits.find(c);
    if (digit == std::string::npos) continue;  // padding, line breaks
    value = (value << 6) + static_cast<unsigned>(digit);
    bits += 6;
    if (bits >= 0) {
      out += static_cast<char>((value >> bits) & 0xffU);
      bits -= 8;
    }
  }
  return out;
}

// An SVG's text with its embedded PNGs taken out, and those PNGs decoded.
struct SplitSvg {
  std::string text;
  std::vector<cli::RgbImage> images;
};

SplitSvg splitSvg(const std::string& svg) {
  const std::string kData = "data:image/png;base64,";
  SplitSvg split;
  std::size_t at = 0;
  for (std::size_t start; (start = svg.find(kData, at)) != std::string::npos;) {
    split.text += svg.substr(at, start - at);
    const std::size_t end = svg.find('"', start);
    const std::size_t first = start + kData.size();
    split.images.push_back(test::decodePng(base64Decode(svg.substr(first, end - first))));
    at = end;
  }
  split.text += svg.substr(at);
  return split;
}

::testing::AssertionResult samePixels(const cli::RgbImage& a, const cli::RgbImage& b) {
  if (a.width == b.width && a.height == b.height && a.rgb == b.rgb) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << a.width << " x " << a.height << " vs " << b.width << " x "
                                       << b.height << ", pixels differ";
}

TEST_F(Outputs, TodaysWritersGiveTheReferencesFilesByteForByteOrPixelForPixel) {
  // The light demo with the simulation: every kind of file `plan` writes but the certificate's.
  std::vector<std::string> overrides = test::kLightDemo;
  overrides.push_back("map.branch=RIGHTY ABOVE NOFLIP");
  overrides.push_back("map.angle_step_deg=2");
  const config::JobSpec job =
      config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", overrides);
  const pipeline::ScanProblem problem = config::toProblem(job);
  const pipeline::ScanPlan plan = pipeline::planScan(problem);
  ASSERT_TRUE(plan.planned() && plan.simulation) << plan.reason;
  cli::writePlanOutputs(dir_ / "today", job, problem, plan);
  cli::writePlanOutputs(dir_ / "reference", job, problem, plan, cli::WriteSettings::reference());

  const auto today = filesUnder(dir_ / "today"), reference = filesUnder(dir_ / "reference");
  ASSERT_EQ(today.size(), reference.size());
  int pngs = 0, svgs = 0;
  for (const auto& [name, bytes] : reference) {
    ASSERT_TRUE(today.contains(name)) << name;
    const std::string& ours = today.at(name);
    const std::string ext = fs::path(name).extension().string();
    if (ext == ".png") {
      ++pngs;
      EXPECT_TRUE(samePixels(test::decodePng(ours), test::decodePng(bytes))) << name;
      // Level 2 with the Up filter (the 3D views without a filter): larger than level 6 with
      // every filter, within reason.
      EXPECT_LT(ours.size(), bytes.size() * 3 / 2) << name;
    } else if (ext == ".svg") {
      ++svgs;
      const SplitSvg a = splitSvg(ours), b = splitSvg(bytes);
      EXPECT_EQ(a.text, b.text) << name;
      ASSERT_EQ(a.images.size(), 1u) << name;
      ASSERT_EQ(b.images.size(), 1u) << name;
      EXPECT_TRUE(samePixels(a.images[0], b.images[0])) << name;
    } else {
      EXPECT_TRUE(ours == bytes) << name << ": " << ours.size() << " vs " << bytes.size()
                                 << " bytes";
    }
  }
  EXPECT_EQ(pngs, 7)
      << "path, configmap, configmap_why, configmap_cylinder, configmap_path, cloud, cell";
  EXPECT_EQ(svgs, 3);
  EXPECT_TRUE(today.contains("cloud.ply") && today.contains("configmap.npy"));
}

TEST_F(Outputs, ViewsDrawnTogetherAreEachAsDrawnAlone) {
  // A tetrahedron, dots on and off it, a path around it and markers: every drawing step.
  cli::RenderRequest r;
  r.width = 160;
  r.height = 120;
  r.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  r.triangles = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
  r.triangle_colours = {{200, 0, 0}, {0, 200, 0}};
  for (int i = 0; i < 400; ++i) {
    const double u = i / 400.0;
    r.dots.emplace_back(u, 0.5 * (1 - u), 0.3 + 0.8 * u * (1 - u));
    r.dot_colours.push_back({static_cast<std::uint8_t>(i % 256), 10, 200});
  }
  r.dots.emplace_back(std::numeric_limits<double>::quiet_NaN(), 0, 0);
  for (int i = 0; i <= 40; ++i)
    r.polyline.emplace_back(1.2 * std::cos(i * 0.2), 1.2 * std::sin(i * 0.2), 0.5);
  r.markers = {{r.polyline.front(), {0, 158, 115}}, {r.polyline.back(), {213, 94, 0}}};
  const std::vector<Eigen::Matrix3d> views = cli::partViewRotations();
  const std::vector<cli::RgbImage> together = cli::renderScenes(r, views);
  ASSERT_EQ(together.size(), views.size());
  for (std::size_t k = 0; k < views.size(); ++k) {
    r.R_view = views[k];
    EXPECT_TRUE(samePixels(together[k], cli::renderScene(r))) << "view " << k;
    int drawn = 0;
    for (int y = 0; y < r.height; ++y)
      for (int x = 0; x < r.width; ++x) drawn += together[k].at(x, y) == r.background ? 0 : 1;
    EXPECT_GT(drawn, 1000) << "view " << k << ": the scene is in the picture";
  }
  EXPECT_TRUE(cli::renderScenes(r, {}).empty());
}

// Dots alone (no mesh) drawn the straightforward way: each dot turned by Eigen, fitted to the
// screen as renderScene documents it (the box of the turned dots, a 5 % + 5 px margin), its pixel
// the floor of its position, the nearest (within 1e-3 of the box diagonal) drawn last.
cli::RgbImage drawDotsPlainly(const cli::RenderRequest& r) {
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& p : r.dots) {
    if ((r.R_view * p).allFinite()) box.extend(r.R_view * p);
  }
  const double margin = 0.05 * std::min(r.width, r.height) + 5;
  const Eigen::Vector3d size = box.sizes().cwiseMax(1e-12), centre = box.center();
  const double scale = std::max(
      1e-12, std::min((r.width - 2 * margin) / size.x(), (r.height - 2 * margin) / size.y()));
  const double tolerance = 1e-3 * size.norm();
  cli::RgbImage image = cli::RgbImage::filled(r.width, r.height, r.background);
  std::vector<double> depth(static_cast<std::size_t>(r.width * r.height),
                            -std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < r.dots.size(); ++i) {
    const Eigen::Vector3d q = r.R_view * r.dots[i];
    const Eigen::Vector3d s(0.5 * r.width + (q.x() - centre.x()) * scale,
                            0.5 * r.height - (q.y() - centre.y()) * scale, q.z());
    if (!s.allFinite()) continue;
    const int x = static_cast<int>(std::floor(s.x())), y = static_cast<int>(std::floor(s.y()));
    if (x < 0 || y < 0 || x >= r.width || y >= r.height) continue;
    double& z = depth[static_cast<std::size_t>(y * r.width + x)];
    if (s.z() + tolerance < z) continue;
    z = std::max(z, s.z());
    image.set(x, y, r.dot_colours[i]);
  }
  return image;
}

TEST_F(Outputs, DotsAreDrawnAsTheStraightforwardWayDrawsThem) {
  // A noisy sphere of 60 000 dots on 200 × 150 pixels: many dots to a pixel, near and far ones.
  cli::RenderRequest r;
  r.width = 200;
  r.height = 150;
  std::mt19937 random(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int i = 0; i < 60'000; ++i) {
    const Eigen::Vector3d d(normal(random), normal(random), normal(random));
    r.dots.push_back(d.normalized() * (1.0 + 0.01 * normal(random)) + Eigen::Vector3d(3, -2, 1));
    r.dot_colours.push_back({static_cast<std::uint8_t>(i % 251), static_cast<std::uint8_t>(i / 251),
                             static_cast<std::uint8_t>(i % 7)});
  }
  r.dots.emplace_back(std::numeric_limits<double>::quiet_NaN(), 0, 0);
  r.dot_colours.push_back({255, 0, 0});
  const std::vector<Eigen::Matrix3d> views = cli::partViewRotations();
  const std::vector<cli::RgbImage> drawn = cli::renderScenes(r, views);
  for (std::size_t k = 0; k < views.size(); ++k) {
    r.R_view = views[k];
    EXPECT_TRUE(samePixels(drawn[k], drawDotsPlainly(r))) << "view " << k;
  }
}

// A mesh drawn the straightforward way, in view coordinates already fitted to the screen: every
// pixel of each triangle's bounding box tested at its centre with the barycentric weights, the
// nearest kept, the grey Lambert shade of renderScene's documentation.
cli::RgbImage drawMeshPlainly(const std::vector<Eigen::Vector3d>& v,
                              const std::vector<Eigen::Vector3i>& triangles,
                              int w,
                              int h) {
  const auto edge = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b, double x, double y) {
    return (b.x() - a.x()) * (y - a.y()) - (b.y() - a.y()) * (x - a.x());
  };
  cli::RgbImage image = cli::RgbImage::filled(w, h, {255, 255, 255});
  std::vector<double> depth(static_cast<std::size_t>(w * h),
                            -std::numeric_limits<double>::infinity());
  for (const Eigen::Vector3i& t : triangles) {
    const Eigen::Vector3d &a = v[static_cast<std::size_t>(t.x())],
                          &b = v[static_cast<std::size_t>(t.y())],
                          &c = v[static_cast<std::size_t>(t.z())];
    const double area = edge(a, b, c.x(), c.y());
    if (!(std::abs(area) > 1e-12)) continue;
    const Eigen::Vector3d n = (b - a)
                                  .cwiseProduct(Eigen::Vector3d(1, -1, 1))
                                  .cross((c - a).cwiseProduct(Eigen::Vector3d(1, -1, 1)));
    const double shade = 0.2 + 0.8 * std::abs(n.z()) / n.norm();
    const auto grey = static_cast<std::uint8_t>(std::lround(std::clamp(235.0 * shade, 0.0, 255.0)));
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(w - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(h - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const double wa = edge(b, c, x + 0.5, y + 0.5) / area,
                     wb = edge(c, a, x + 0.5, y + 0.5) / area, wc = 1.0 - wa - wb;
        if (wa < 0 || wb < 0 || wc < 0) continue;
        const double z = wa * a.z() + wb * b.z() + wc * c.z();
        double& zbuf = depth[static_cast<std::size_t>(y * w + x)];
        if (z > zbuf) {
          zbuf = z;
          image.set(x, y, {grey, grey, grey});
        }
      }
    }
  }
  return image;
}

TEST_F(Outputs, MeshIsDrawnAsTheStraightforwardWayDrawsIt) {
  // Random triangles of every shape — slivers along rows and columns, edges through pixel
  // centres, tiny ones and ones across the picture, both windings — over one another, in the
  // box [0, w] × [-h, 0] that two markers fix: with renderScene's margin (5 % of 110 + 5 px on
  // a 140 × 110 picture), one view unit is one pixel.
  const int w = 119, h = 89;
  std::mt19937 random(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto inside = [&](Eigen::Vector3d p) {
    p.x() = std::clamp(p.x(), 0.0, double{w});
    p.y() = std::clamp(p.y(), 0.0, double{h});
    return p;
  };
  std::vector<Eigen::Vector3d> points;  // x right, y down, as on the screen
  std::vector<Eigen::Vector3i> triangles;
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d a(u(random) * w, u(random) * h, u(random));
    const double size = std::pow(10.0, 2.5 * u(random) - 1.0);  // 0.1 .. 30 px
    const double long_side = i % 3 == 0 ? 20 * size : size;
    Eigen::Vector3d b = inside(a + Eigen::Vector3d((u(random) - 0.5) * long_side,
                                                   (u(random) - 0.5) * size, u(random) - 0.5));
    Eigen::Vector3d c = inside(a + Eigen::Vector3d((u(random) - 0.5) * size,
                                                   (u(random) - 0.5) * long_side, u(random) - 0.5));
    if (i % 5 == 0) {  // edges through pixel centres and along a row
      b.x() = std::min(std::floor(b.x()) + 0.5, w - 0.5);
      c.y() = std::min(std::floor(c.y()) + 0.5, h - 0.5);
      b.y() = a.y();
    }
    const int k = static_cast<int>(points.size());
    points.insert(points.end(), {a, b, c});
    triangles.emplace_back(k, i % 2 ? k + 1 : k + 2, i % 2 ? k + 2 : k + 1);
  }
  cli::RenderRequest r;
  r.width = 140;
  r.height = 110;
  for (const Eigen::Vector3d& p : points) r.vertices.emplace_back(p.x(), -p.y(), p.z());
  r.triangles = triangles;
  r.markers = {{Eigen::Vector3d(0, 0, 0), {0, 0, 0}}, {Eigen::Vector3d(w, -h, 0), {0, 0, 0}}};
  const cli::RgbImage drawn = cli::renderScene(r);
  // The screen positions as renderScene computes them (scale 1, centre (w/2, -h/2)).
  std::vector<Eigen::Vector3d> screen;
  for (const Eigen::Vector3d& p : r.vertices) {
    screen.emplace_back(0.5 * r.width + (p.x() - 0.5 * w), 0.5 * r.height - (p.y() + 0.5 * h),
                        p.z());
  }
  const cli::RgbImage plain = drawMeshPlainly(screen, triangles, r.width, r.height);
  int differ = 0, drawn_pixels = 0;
  for (int y = 0; y < r.height; ++y) {
    for (int x = 0; x < r.width; ++x) {
      const bool marker = (std::abs(x - 10) <= 5 && std::abs(y - 10) <= 5) ||
                          (std::abs(x - 10 - w) <= 5 && std::abs(y - 10 - h) <= 5);
      if (marker) continue;
      differ += drawn.at(x, y) == plain.at(x, y) ? 0 : 1;
      drawn_pixels += drawn.at(x, y) == cli::Rgb{255, 255, 255} ? 0 : 1;
    }
  }
  EXPECT_EQ(differ, 0);
  EXPECT_GT(drawn_pixels, w * h / 2);
}

TEST_F(Outputs, FilledAndUpscaledImagesHoldThePixelsSetOneByOne) {
  for (const cli::Rgb fill : {cli::Rgb{255, 255, 255}, cli::Rgb{0, 114, 178}}) {
    for (const auto& [w, h] : {std::pair{1, 1}, {7, 3}, {480, 2}, {0, 4}}) {
      const cli::RgbImage image = cli::RgbImage::filled(w, h, fill);
      ASSERT_EQ(image.rgb.size(), 3u * static_cast<std::size_t>(w * h));
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) ASSERT_EQ(image.at(x, y), fill) << x << " " << y;
    }
  }
  cli::RgbImage image = cli::RgbImage::filled(5, 4);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      image.set(x, y, {static_cast<std::uint8_t>(40 * x), static_cast<std::uint8_t>(60 * y), 7});
    }
  }
  for (const auto& [fx, fy] : {std::pair{1, 1}, {3, 1}, {1, 2}, {4, 5}}) {
    const cli::RgbImage big = cli::upscale(image, fx, fy);
    ASSERT_EQ(big.width, image.width * fx);
    ASSERT_EQ(big.height, image.height * fy);
    for (int y = 0; y < big.height; ++y) {
      for (int x = 0; x < big.width; ++x) {
        ASSERT_EQ(big.at(x, y), image.at(x / fx, y / fy))
            << fx << " " << fy << " " << x << " " << y;
      }
    }
  }
}

TEST_F(Outputs, EveryPngSettingDecodesToTheSamePixels) {
  cli::RgbImage image = cli::RgbImage::filled(37, 23, {250, 250, 250});
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      if ((x * y) % 7 < 3) {
        image.set(x, y, {static_cast<std::uint8_t>(7 * x), static_cast<std::uint8_t>(11 * y), 90});
      }
    }
  }
  for (const cli::PngSettings s : {cli::PngSettings{}, cli::WriteSettings::reference().png,
                                   cli::PngSettings{0, 0x08}, cli::PngSettings{9, 0x80}}) {
    const std::string png = cli::encodePng(image, s);
    EXPECT_TRUE(samePixels(test::decodePng(png), image)) << s.level << " " << s.filters;
    EXPECT_EQ(cli::encodePng(image, s), png) << "the same bytes every time";
  }
}

TEST_F(Outputs, StreamedAndPiecedFilesHoldWhatWasWrittenAndNoTemporary) {
  std::string big;
  for (int i = 0; i < 300'000; ++i) big += static_cast<char>(i * 31 % 251);
  cli::writeFileAtomically(dir_ / "streamed.bin", [&](std::ostream& out) {
    out << "head ";
    out.write(big.data(), static_cast<std::streamsize>(big.size()));        // straight through
    for (int i = 0; i < 100'000; ++i) out.put(static_cast<char>(i % 256));  // buffered
  });
  std::string want = "head " + big;
  for (int i = 0; i < 100'000; ++i) want += static_cast<char>(i % 256);
  EXPECT_TRUE(readBytes(dir_ / "streamed.bin") == want);
  cli::writeFileAtomically(dir_ / "pieces.bin", {"a", "", big, "z"});
  EXPECT_TRUE(readBytes(dir_ / "pieces.bin") == "a" + big + "z");
  for (const auto& e : fs::directory_iterator(dir_)) {
    EXPECT_EQ(e.path().extension(), ".bin") << e.path();
  }
}

TEST_F(Outputs, AFailingStreamLeavesNoFileAndANamedError) {
  EXPECT_THROW(cli::writeFileAtomically(dir_ / "thrown.bin",
                                        [](std::ostream& out) {
                                          out << "partial";
                                          throw std::runtime_error("stop");
                                        }),
               std::runtime_error);
  EXPECT_TRUE(fs::is_empty(dir_));
  std::ofstream(dir_ / "file") << "a file where a folder should be";
  try {
    cli::writeFileAtomically(dir_ / "file" / "x.ply", [](std::ostream& out) { out << "x"; });
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("x.ply: cannot write the file: Not a directory"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
