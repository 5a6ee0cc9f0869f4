#include "cli/plot/image_io.h"
#include "tests/io_support.h"

#include <scanplan/config/job.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/planner/config_map.h>
#include "cli/commands/commands.h"
#include "tests/image_support.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <ostream>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace scanplan::cli {

using test::decodePng;
using test::NpyArray;
using test::readNpy;

// Printed by gtest when a colour comparison fails.
void PrintTo(const Rgb& c, std::ostream* os) {
  *os << "rgb(" << int{c.r} << ", " << int{c.g} << ", " << int{c.b} << ")";
}

namespace {

namespace fs = std::filesystem;

const Rgb kWhite{255, 255, 255};

std::string readBytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

RgbImage randomImage(int width, int height, std::mt19937& rng) {
  RgbImage image = RgbImage::filled(width, height);
  std::uniform_int_distribution<int> byte(0, 255);
  for (auto& v : image.rgb) v = static_cast<std::uint8_t>(byte(rng));
  return image;
}

class ImageIoFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("scanplan_test_image_io_" + std::string(info->name()) +
                                        "_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path dir_;
};

TEST(RgbImage, SetAndAtAddressRowMajorTopRowFirst) {
  RgbImage image = RgbImage::filled(4, 3, {1, 2, 3});
  ASSERT_EQ(image.rgb.size(), 36u);
  image.set(3, 1, {10, 20, 30});
  // Pixel (3, 1) is pixel 1 * 4 + 3 = 7, bytes 21..23.
  EXPECT_EQ(image.rgb[21], 10);
  EXPECT_EQ(image.rgb[22], 20);
  EXPECT_EQ(image.rgb[23], 30);
  EXPECT_EQ(image.at(3, 1), (Rgb{10, 20, 30}));
  EXPECT_EQ(image.at(0, 0), (Rgb{1, 2, 3}));
}

TEST(Png, EncodeDecodeRoundTripReturnsTheSameImage) {
  std::mt19937 rng(7);
  for (const auto& [w, h] : {std::pair{1, 1}, std::pair{37, 23}, std::pair{300, 2}}) {
    const RgbImage image = randomImage(w, h, rng);
    const RgbImage back = decodePng(encodePng(image));
    EXPECT_EQ(back.width, w);
    EXPECT_EQ(back.height, h);
    EXPECT_EQ(back.rgb, image.rgb) << w << " × " << h;
  }
}

TEST(Png, BytesStartWithThePngSignature) {
  const std::string bytes = encodePng(RgbImage::filled(5, 4, {9, 8, 7}));
  const std::string signature("\x89PNG\r\n\x1a\n", 8);
  ASSERT_GE(bytes.size(), 8u);
  EXPECT_EQ(bytes.substr(0, 8), signature);
  // No time or text chunks: the output depends on the pixels only.
  EXPECT_EQ(bytes.find("tIME"), std::string::npos);
  EXPECT_EQ(bytes.find("tEXt"), std::string::npos);
}

TEST(Png, InconsistentImagesAndBadDataThrow) {
  RgbImage image = RgbImage::filled(3, 3);
  image.rgb.pop_back();
  EXPECT_THROW(encodePng(image), InputError);
  EXPECT_THROW(encodePng(RgbImage{}), InputError);
  // libpng's default user limit is 1,000,000 px per row: exercises its error (longjmp) path.
  EXPECT_THROW(encodePng(RgbImage::filled(1'000'001, 1)), InputError);
  EXPECT_THROW(decodePng("not a png"), InputError);
  const std::string truncated = encodePng(RgbImage::filled(20, 20, {1, 2, 3})).substr(0, 40);
  EXPECT_THROW(decodePng(truncated), InputError);
}

TEST_F(ImageIoFiles, WritingAPngTwiceGivesIdenticalFiles) {
  std::mt19937 rng(11);
  const RgbImage image = randomImage(64, 48, rng);
  writePng(dir_ / "a.png", image);
  writePng(dir_ / "b.png", image);
  const std::string a = readBytes(dir_ / "a.png");
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, readBytes(dir_ / "b.png"));
  EXPECT_EQ(decodePng(a).rgb, image.rgb);
  EXPECT_FALSE(fs::exists(dir_ / "a.png.tmp"));
}

TEST_F(ImageIoFiles, PngErrorNamesTheFile) {
  try {
    writePng(dir_ / "bad.png", RgbImage{});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.png"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "bad.png"));
}

TEST_F(ImageIoFiles, NpyHeaderIsWhatNumpyWritesForShape234Float32) {
  std::vector<float> data(24);
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<float>(i);
  data[1] = 1.0f;
  data[2] = -2.5f;
  writeNpy(dir_ / "a.npy", data, {2, 3, 4});
  const std::string bytes = readBytes(dir_ / "a.npy");

  // numpy.lib.format._wrap_header: dict text is 62 characters; numpy 1.24+ appends
  // 21 - len("2") = 20 growth spaces, older numpy none, and both then pad magic (6) +
  // version (2) + length (2) + text + '\n' up to 128 bytes: 10 + 62 + 55 + 1 = 128.
  // The length field is 128 - 10 = 118 = 0x76, little-endian.
  const std::string dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3, 4), }";
  ASSERT_EQ(dict.size(), 62u);
  const std::string expected_header =
      std::string("\x93NUMPY\x01\x00\x76\x00", 10) + dict + std::string(55, ' ') + "\n";
  ASSERT_EQ(expected_header.size(), 128u);
  ASSERT_EQ(bytes.size(), 128u + 24u * 4u);
  EXPECT_EQ(bytes.substr(0, 128), expected_header);

  // IEEE 754 little-endian: 1.0f = 0x3f800000, -2.5f = 0xc0200000.
  EXPECT_EQ(bytes.substr(128, 4), std::string("\x00\x00\x00\x00", 4));
  EXPECT_EQ(bytes.substr(132, 4), std::string("\x00\x00\x80\x3f", 4));
  EXPECT_EQ(bytes.substr(136, 4), std::string("\x00\x00\x20\xc0", 4));

  const NpyArray array = readNpy(dir_ / "a.npy");
  EXPECT_EQ(array.descr, "<f4");
  EXPECT_EQ(array.shape, (std::vector<std::size_t>{2, 3, 4}));
  ASSERT_EQ(array.raw.size(), 96u);
  std::vector<float> back(24);
  std::memcpy(back.data(), array.raw.data(), array.raw.size());
  EXPECT_EQ(back, data);
}

TEST_F(ImageIoFiles, NpyUint8RoundTripWithOneDimensionalShape) {
  const std::vector<std::uint8_t> data{0, 1, 127, 200, 255};
  writeNpy(dir_ / "u.npy", data, {5});
  const std::string bytes = readBytes(dir_ / "u.npy");
  // A 1-tuple prints with a trailing comma in Python.
  EXPECT_NE(bytes.find("{'descr': '|u1', 'fortran_order': False, 'shape': (5,), }"),
            std::string::npos);
  const NpyArray array = readNpy(dir_ / "u.npy");
  EXPECT_EQ(array.descr, "|u1");
  EXPECT_EQ(array.shape, (std::vector<std::size_t>{5}));
  EXPECT_EQ(array.raw, std::string(data.begin(), data.end()));
}

TEST_F(ImageIoFiles, NpyHeadersAreAlignedTo64BytesForManyShapes) {
  const std::vector<std::vector<std::size_t>> shapes{
      {}, {0}, {7}, {1000, 360}, {123456789, 0, 3}, {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 0}};
  for (const auto& shape : shapes) {
    std::size_t count = 1;
    for (const std::size_t n : shape) count *= n;
    writeNpy(dir_ / "s.npy", std::vector<float>(count, 0.5f), shape);
    const std::string bytes = readBytes(dir_ / "s.npy");
    ASSERT_GE(bytes.size(), 10u);
    const std::size_t header =
        10u + static_cast<unsigned char>(bytes[8]) + 256u * static_cast<unsigned char>(bytes[9]);
    EXPECT_EQ(header % 64, 0u) << bytes.substr(10, header - 10);
    EXPECT_EQ(bytes[header - 1], '\n');
    EXPECT_EQ(bytes.size(), header + 4 * count);
    EXPECT_EQ(readNpy(dir_ / "s.npy").shape, shape);
  }
  // The scalar shape prints as "()".
  writeNpy(dir_ / "s.npy", std::vector<float>{1.0f}, {});
  EXPECT_NE(readBytes(dir_ / "s.npy").find("'shape': (), }"), std::string::npos);
}

TEST_F(ImageIoFiles, NpySizeMismatchThrowsNamingTheFile) {
  try {
    writeNpy(dir_ / "m.npy", std::vector<float>(5), {2, 3});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("m.npy"), std::string::npos) << e.what();
  }
  EXPECT_THROW(writeNpy(dir_ / "m.npy", std::vector<std::uint8_t>(7), {2, 3}), InputError);
  EXPECT_FALSE(fs::exists(dir_ / "m.npy"));
  EXPECT_THROW(readNpy(dir_ / "missing.npy"), InputError);
  std::ofstream(dir_ / "junk.npy", std::ios::binary) << "hello";
  EXPECT_THROW(readNpy(dir_ / "junk.npy"), InputError);
}

TEST(Colours, GreyClampsAndMarksNan) {
  EXPECT_EQ(grey(0.0), (Rgb{0, 0, 0}));
  EXPECT_EQ(grey(1.0), kWhite);
  EXPECT_EQ(grey(-3.0), (Rgb{0, 0, 0}));
  EXPECT_EQ(grey(7.0), kWhite);
  EXPECT_EQ(grey(0.5), (Rgb{128, 128, 128}));  // round(127.5)
  const Rgb nan = grey(std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(nan, kNanColour);
  EXPECT_FALSE(nan.r == nan.g && nan.g == nan.b) << "NaN must not look like a grey level";
}

TEST(Colours, CategoryPaletteHasEightDistinctColoursAndWraps) {
  std::set<std::tuple<int, int, int>> seen;
  for (int k = 0; k < 8; ++k) {
    const Rgb c = categoryColour(k);
    seen.emplace(c.r, c.g, c.b);
    EXPECT_EQ(categoryColour(k + 8), c);
    EXPECT_EQ(categoryColour(k - 8), c);
  }
  EXPECT_EQ(seen.size(), 8u);
  EXPECT_EQ(categoryColour(0), (Rgb{230, 159, 0}));  // Okabe–Ito orange
}

// One big triangle in the plane z = 0 facing the viewer (identity view: depth = world z).
// The fit maps the box [-1, 1]² to 125 px at the centre of a 200 × 150 image:
// margin = 0.05 · 150 + 5 = 12.5 px, scale = min(175, 125) / 2 = 62.5 px per unit.
RenderRequest triangleScene() {
  RenderRequest request;
  request.width = 200;
  request.height = 150;
  request.vertices = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
  request.triangles = {{0, 1, 2}};
  return request;
}

TEST(Render, TriangleFacingTheViewerFillsItsCentreAndLeavesCornersEmpty) {
  const RgbImage image = renderScene(triangleScene());
  ASSERT_EQ(image.width, 200);
  ASSERT_EQ(image.height, 150);
  // Facing the viewer: full Lambert term, a light grey distinct from the white background.
  const Rgb centre = image.at(100, 75);
  EXPECT_NE(centre, kWhite);
  EXPECT_EQ(centre.r, centre.g);
  EXPECT_GT(centre.r, 200);
  for (const auto& [x, y] :
       {std::pair{0, 0}, std::pair{199, 0}, std::pair{0, 149}, std::pair{199, 149}}) {
    EXPECT_EQ(image.at(x, y), kWhite) << x << ", " << y;
  }
  // Apex at world (0, 1) → pixel row 75 - 62.5 = 12.5; base at row 137.5.
  EXPECT_NE(image.at(100, 14), kWhite);
  EXPECT_EQ(image.at(100, 10), kWhite);
  EXPECT_NE(image.at(100, 136), kWhite);
  EXPECT_EQ(image.at(100, 139), kWhite);
}

TEST(Render, TiltedTriangleIsDarkerThanOneFacingTheViewer) {
  RenderRequest request = triangleScene();
  const Rgb facing = renderScene(request).at(100, 75);
  for (auto& v : request.vertices) v.z() = 2.0 * v.x();  // normal ∝ (-2, 0, 1): cos = 1/√5
  const Rgb tilted = renderScene(request).at(100, 75);
  EXPECT_LT(tilted.r, facing.r);
  EXPECT_NE(tilted, kWhite);
}

TEST(Render, PolylineInFrontHasItsColourAndBehindIsTinted) {
  RenderRequest request = triangleScene();
  request.polyline_colour = {213, 94, 0};
  // A horizontal line through the image centre (row 75 boundary): rows 74 and 75 are drawn.
  request.polyline = {{-1, 0, 0.5}, {1, 0, 0.5}};
  const RgbImage front = renderScene(request);
  EXPECT_EQ(front.at(100, 74), request.polyline_colour);
  EXPECT_EQ(front.at(100, 75), request.polyline_colour);
  EXPECT_EQ(front.at(60, 75), request.polyline_colour);  // outside the triangle
  EXPECT_NE(front.at(100, 72), request.polyline_colour);

  request.polyline = {{-1, 0, -0.5}, {1, 0, -0.5}};
  const RgbImage behind = renderScene(request);
  const Rgb hidden = behind.at(100, 75);
  EXPECT_NE(hidden, request.polyline_colour);
  EXPECT_NE(hidden, front.at(100, 72)) << "hidden path must still show";
  // At world x = 0.9 (pixel 156) the triangle (|x| ≤ 0.5 at y = 0) does not cover the path.
  EXPECT_EQ(behind.at(156, 75), request.polyline_colour);
}

TEST(Render, MarkersAreDrawnOnTop) {
  RenderRequest request = triangleScene();
  request.markers = {{Eigen::Vector3d(0, 0, -5), Rgb{0, 158, 115}}};
  const RgbImage image = renderScene(request);
  EXPECT_EQ(image.at(100, 75), (Rgb{0, 158, 115}));
  EXPECT_EQ(image.at(104, 75), (Rgb{0, 0, 0}));  // outline
}

TEST(Render, ViewRotationAndDeterminism) {
  // The same triangle seen along world -x: view rows map world (y, z, x) to screen (x, y, depth).
  RenderRequest request = triangleScene();
  for (auto& v : request.vertices) v = Eigen::Vector3d(v.z(), v.x(), v.y());
  request.R_view << 0, 1, 0, 0, 0, 1, 1, 0, 0;
  const RgbImage a = renderScene(request);
  EXPECT_EQ(a.rgb, renderScene(triangleScene()).rgb);
  EXPECT_EQ(a.rgb, renderScene(request).rgb);
}

TEST(Render, BadRequestsThrowAndEmptySceneIsBackground) {
  RenderRequest request = triangleScene();
  request.triangles.push_back({0, 1, 3});
  EXPECT_THROW(renderScene(request), InputError);
  request = triangleScene();
  request.width = 0;
  EXPECT_THROW(renderScene(request), InputError);
  RenderRequest empty;
  empty.width = 8;
  empty.height = 6;
  empty.background = {1, 2, 3};
  EXPECT_EQ(renderScene(empty).rgb, RgbImage::filled(8, 6, {1, 2, 3}).rgb);
}

// ---- axis ticks and ranges on degenerate data -------------------------------------------------

// Ticks are few, finite, increasing and inside the range.
void expectSaneTicks(double a, double b) {
  SCOPED_TRACE(::testing::Message() << "[" << a << ", " << b << "]");
  const Ticks ticks = niceTicks(a, b);
  ASSERT_LE(ticks.values.size(), kMaxTicks);
  const double lo = std::min(a, b), hi = std::max(a, b), slack = 1e-6 * (hi - lo);
  for (std::size_t i = 0; i < ticks.values.size(); ++i) {
    EXPECT_TRUE(std::isfinite(ticks.values[i]));
    EXPECT_GE(ticks.values[i], lo - slack);
    EXPECT_LE(ticks.values[i], hi + slack);
    if (i) {
      EXPECT_GT(ticks.values[i], ticks.values[i - 1]);
    }
    EXPECT_LT(tickLabel(ticks, ticks.values[i]).size(), 30u) << tickLabel(ticks, ticks.values[i]);
  }
}

TEST(Ticks, ValuesThatDifferOnlyByRoundingHaveNoTicks) {
  // Two planners' J, equal but for the last bits (a batch report died here with bad_alloc:
  // steps of 1e-16 at 25.46 are below the spacing of doubles, the tick loop never ended).
  const double a = 25.46247875282346, b = 25.462478752823472;
  ASSERT_NE(a, b);
  EXPECT_TRUE(flatRange(a, b));
  EXPECT_TRUE(niceTicks(a, b).values.empty());
  EXPECT_TRUE(niceTicks(b, a).values.empty());
  // The same at other magnitudes, and just above the flat threshold ticks come back.
  for (const double v : {1e-300, 1e-12, 1.0, 3.7e8, 1e15, 1e300}) {
    EXPECT_TRUE(niceTicks(v, v * (1 + 1e-12)).values.empty()) << v;
    EXPECT_TRUE(niceTicks(-v, -v * (1 + 1e-12)).values.empty()) << v;
    expectSaneTicks(v, v * (1 + 1e-7));
    EXPECT_FALSE(niceTicks(v, v * (1 + 1e-7)).values.empty()) << v;
  }
}

TEST(Ticks, ZeroNonFiniteAndHugeRangesGiveFewOrNoTicks) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double big = std::numeric_limits<double>::max();
  for (const auto& [a, b] : std::vector<std::pair<double, double>>{
           {0, 0}, {5, 5}, {nan, 1}, {1, nan}, {nan, nan}, {0, inf}, {-inf, inf}, {-big, big}}) {
    EXPECT_TRUE(niceTicks(a, b).values.empty()) << a << " " << b;
  }
  for (const auto& [a, b] : std::vector<std::pair<double, double>>{{0, big},
                                                                   {-big, 0},
                                                                   {0, 1e-310},
                                                                   {-1e-300, 1e-300},
                                                                   {1e15, 1e15 + 1e7},
                                                                   {0.0012, -0.0031},
                                                                   {0, 109.4}}) {
    expectSaneTicks(a, b);
    EXPECT_GE(niceTicks(a, b).values.size(), 5u) << a << " " << b;
  }
  // Random ranges over the whole exponent range.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> mantissa(-10, 10), exponent(-300, 300), gap(-15, 2);
  for (int i = 0; i < 20000; ++i) {
    const double a = mantissa(rng) * std::pow(10.0, exponent(rng));
    const double b = a + (std::abs(a) + 1e-300) * std::pow(10.0, gap(rng)) * mantissa(rng);
    expectSaneTicks(a, b);
    if (::testing::Test::HasFailure()) break;
  }
}

TEST(Ticks, LabelsAreFixedForOrdinaryValuesAndShortForHugeOnes) {
  const Ticks ticks = niceTicks(-1, 1);
  EXPECT_EQ(tickLabel(ticks, -0.5), "-0.5");
  const Ticks huge = niceTicks(0, 1e300);
  ASSERT_FALSE(huge.values.empty());
  EXPECT_EQ(tickLabel(huge, huge.values[1]), "2e+299");
}

TEST(AxisRange, FlatNonFiniteAndHugeDataGiveAFiniteRangeWithTicks) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double big = std::numeric_limits<double>::max();
  EXPECT_EQ(axisRange(0, 10), (std::pair{-0.8, 10.8}));
  EXPECT_EQ(axisRange(10, 0), (std::pair{-0.8, 10.8}));
  EXPECT_EQ(axisRange(3, 3), (std::pair{2.5, 3.5}));
  EXPECT_EQ(axisRange(nan, nan), (std::pair{0.0, 1.0}));
  EXPECT_EQ(axisRange(-inf, inf), (std::pair{0.0, 1.0}));
  for (const auto& [a, b] :
       std::vector<std::pair<double, double>>{{25.46247875282346, 25.462478752823472},
                                              {0, 0},
                                              {nan, 4},
                                              {4, inf},
                                              {-big, big},
                                              {big, big},
                                              {-big, -big},
                                              {1e-300, 1e-300},
                                              {1e300, 1e300 * (1 + 1e-15)}}) {
    SCOPED_TRACE(::testing::Message() << a << " " << b);
    const auto [lo, hi] = axisRange(a, b);
    EXPECT_TRUE(std::isfinite(lo) && std::isfinite(hi));
    EXPECT_TRUE(std::isfinite(hi - lo));
    EXPECT_LT(lo, hi);
    EXPECT_FALSE(flatRange(lo, hi));
    expectSaneTicks(lo, hi);
    EXPECT_FALSE(niceTicks(lo, hi).values.empty());
    if (std::isfinite(a) && std::abs(a) < big / 4) {
      EXPECT_LE(lo, a);
      EXPECT_GE(hi, a);
    }
  }
  // The rounding-equal J values: centred, padded by 10 % of the value.
  const auto [lo, hi] = axisRange(25.46247875282346, 25.462478752823472);
  EXPECT_NEAR(lo, 25.4624787528 - 2.54624787528, 1e-9);
  EXPECT_NEAR(hi, 25.4624787528 + 2.54624787528, 1e-9);
}

// ---- the configuration-map figures (map and plan commands) -----------------------------------

// A synthetic 36-angle × 10-sample map with every f level, a NaN cell and every limit code.
planner::ConfigMap syntheticMap() {
  planner::ConfigMap map;
  for (int a = 0; a < 36; ++a) map.angles.push_back(deg(10.0 * a));
  for (int t = 0; t < 10; ++t) map.times.push_back(0.5 * t);
  map.branches = {kinematics::IkBranch::fromIndex(0)};
  for (int a = 0; a < 36; ++a) {
    for (int t = 0; t < 10; ++t) {
      map.f.push_back(static_cast<float>((7 * a + 3 * t) % 11) / 10.0f);
      map.limit.push_back(static_cast<std::uint8_t>((a + t) % planner::kLimitCount));
    }
  }
  map.f[map.index(0, 20, 4)] = std::numeric_limits<float>::quiet_NaN();
  map.joint = map.singularity = map.clearance = map.f;
  return map;
}

using test::Crop;
using test::darkPixels;
using test::plotArea;

bool hasPixel(const RgbImage& image, int x0, int y0, int x1, int y1, Rgb colour) {
  for (int y = std::max(y0, 0); y < std::min(y1, image.height); ++y) {
    for (int x = std::max(x0, 0); x < std::min(x1, image.width); ++x) {
      if (image.at(x, y) == colour) return true;
    }
  }
  return false;
}

TEST_F(ImageIoFiles, MapFiguresAreLabelledAndTheirRasterKeepsEveryCellsColour) {
  const planner::ConfigMap map = syntheticMap();
  const config::JobSpec job;  // a named job: GCC 12 misreads a JobSpec{} temporary as uninitialised
  writeMapOutputs(dir_, job, map);

  // configmap.png: the 10 × 36 map enlarged to 1000 × 432 (100 × 12 px per cell: ~1000 px wide,
  // 40 % as tall), framed with text; the SVG is the same figure in vectors around that raster.
  const RgbImage png = decodePng(readBytes(dir_ / "configmap.png"));
  const std::string svg = readBytes(dir_ / "configmap.svg");
  const Crop c = plotArea(png);
  ASSERT_EQ(c.w, 1000);
  ASSERT_EQ(c.h, 432);
  EXPECT_GT(c.x, 40);
  EXPECT_GT(c.y, 20);
  EXPECT_GT(png.width, c.x + c.w + 100) << "a legend column";
  EXPECT_LT(png.width, c.x + c.w + 400);
  EXPECT_GT(png.height, c.y + c.h + 40) << "x ticks and axis title";
  EXPECT_LT(png.height, c.y + c.h + 200);
  // The SVG: the PNG's size in px (0.75 pt each), the raster embedded at its size, text as
  // glyph outlines.
  std::array<char, 64> view_box{};
  std::snprintf(view_box.data(), view_box.size(), "viewBox=\"0 0 %g %g\"", 0.75 * png.width,
                0.75 * png.height);
  EXPECT_NE(svg.find(view_box.data()), std::string::npos) << view_box.data();
  EXPECT_NE(svg.find("<image id=\"image1\" width=\"1000\" height=\"432\""), std::string::npos);
  EXPECT_NE(svg.find("<symbol overflow=\"visible\" id=\"glyph"), std::string::npos);
  // Every pixel of the raster is its cell's grey (time →, angle ↑; NaN dark red).
  int wrong = 0;
  for (int y = 0; y < c.h; ++y) {
    for (int x = 0; x < c.w; ++x) {
      const std::size_t cell =
          map.index(0, static_cast<std::size_t>(35 - y / 12), static_cast<std::size_t>(x / 100));
      wrong += png.at(c.x + x, c.y + y) == grey(map.f[cell]) ? 0 : 1;
    }
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(png.at(c.x + 450, c.y + (35 - 20) * 12 + 6), kNanColour);
  // Text in the margins: title above, tick values and axis title left and below, the colour
  // bar's labels right; the frame is just outside the raster.
  EXPECT_GT(darkPixels(png, 0, 0, png.width, c.y - 4), 200) << "title";
  EXPECT_GT(darkPixels(png, 0, c.y, c.x - 8, c.y + c.h), 200) << "y values and title";
  EXPECT_GT(darkPixels(png, 0, c.y + c.h + 8, png.width, png.height), 200) << "x values, title";
  EXPECT_GT(darkPixels(png, c.x + c.w + 4, 0, png.width, png.height), 100) << "colour bar";
  std::set<int> greys;  // the colour bar: every grey level from black to white
  for (int y = 0; y < png.height; ++y) {
    for (int x = c.x + c.w + 4; x < png.width; ++x) {
      const Rgb p = png.at(x, y);
      if (p.r == p.g && p.g == p.b) greys.insert(p.r);
    }
  }
  EXPECT_GT(greys.size(), 150u) << "colour bar";
  EXPECT_EQ(png.at(c.x - 1, c.y + 100), (Rgb{0, 0, 0}));
  EXPECT_EQ(png.at(c.x + c.w, c.y + 100), (Rgb{0, 0, 0}));
  // The SVG names its axes and bar in its description.
  EXPECT_NE(svg.find("<desc>x: time (s); y: table angle (deg); colour bar: f; x ticks: 0, 1, 2, "
                     "3, 4; y ticks: 0, 50, 100, 150, 200, 250, 300, 350</desc>"),
            std::string::npos)
      << "angle ticks up to 360 deg";

  // configmap_why.png: the same frame, each cell the colour of its limit (darker = lower f),
  // and a legend swatch per limit.
  const RgbImage why = decodePng(readBytes(dir_ / "configmap_why.png"));
  const Crop cw = plotArea(why);
  ASSERT_EQ(cw.w, 1000);
  ASSERT_EQ(cw.h, 432);
  for (int a = 0; a < 36; ++a) {
    for (int t = 0; t < 10; ++t) {
      const std::size_t i = map.index(0, static_cast<std::size_t>(a), static_cast<std::size_t>(t));
      const Rgb base = categoryColour(map.limit[i] + 1);
      const double f = std::isnan(map.f[i]) ? 0.0 : map.f[i];
      const double s = 0.45 + 0.55 * f;
      const Rgb expected{static_cast<std::uint8_t>(base.r * s),
                         static_cast<std::uint8_t>(base.g * s),
                         static_cast<std::uint8_t>(base.b * s)};
      EXPECT_EQ(why.at(cw.x + 100 * t + 50, cw.y + 12 * (35 - a) + 6), expected) << a << " " << t;
    }
  }
  for (int k = 1; k <= planner::kLimitCount; ++k) {
    EXPECT_TRUE(hasPixel(why, cw.x + cw.w + 4, 0, why.width, why.height, categoryColour(k)))
        << "legend swatch " << k;
  }
  EXPECT_GT(darkPixels(why, cw.x + cw.w + 4, 0, why.width, why.height), 200) << "legend text";
}

TEST_F(ImageIoFiles, PathFigureHasALineLegendAndDegenerateMapsStillGiveFigures) {
  const planner::ConfigMap map = syntheticMap();
  RgbImage raster = RgbImage::filled(10, 36, {200, 200, 200});
  writeFigure(dir_, "configmap_path", raster, map, "Table-angle path",
              {{categoryColour(5), "ray J 27.39 s"}, {categoryColour(4), "dp J 25.49 s"}});
  const RgbImage png = decodePng(readBytes(dir_ / "configmap_path.png"));
  const Crop c = plotArea(png);
  ASSERT_EQ(c.w, 1000);
  EXPECT_TRUE(hasPixel(png, c.x + c.w + 4, 0, png.width, png.height, categoryColour(5)));
  EXPECT_TRUE(hasPixel(png, c.x + c.w + 4, 0, png.width, png.height, categoryColour(4)));
  EXPECT_NE(readBytes(dir_ / "configmap_path.svg").find("; dp J 25.49 s;"), std::string::npos);

  // One sample and one angle (flat axes), and an all-NaN map: figures, no error.
  planner::ConfigMap tiny;
  tiny.angles = {0.0};
  tiny.times = {3.0};
  tiny.branches = {kinematics::IkBranch::fromIndex(0)};
  tiny.f = {std::numeric_limits<float>::quiet_NaN()};
  tiny.joint = tiny.singularity = tiny.clearance = tiny.f;
  tiny.limit = {0};
  const config::JobSpec job;
  ASSERT_NO_THROW(writeMapOutputs(dir_, job, tiny));
  const RgbImage one = decodePng(readBytes(dir_ / "configmap.png"));
  const Crop c1 = plotArea(one);
  EXPECT_EQ(c1.w, 1000);
  EXPECT_EQ(c1.h, 400);
  EXPECT_EQ(one.at(c1.x + 500, c1.y + 200), kNanColour);
  EXPECT_GT(darkPixels(one, 0, c1.y, c1.x - 8, c1.y + c1.h), 100) << "y ticks of a flat range";
  const std::string svg = readBytes(dir_ / "configmap.svg");
  EXPECT_EQ(svg.find("nan"), std::string::npos);
  EXPECT_EQ(svg.find("inf"), std::string::npos);
}

}  // namespace
}  // namespace scanplan::cli

namespace scanplan::cli {
namespace {

std::size_t countColour(const RgbImage& image, int y, const Rgb& colour) {
  std::size_t n = 0;
  for (int x = 0; x < image.width; ++x) {
    const Rgb p = image.at(x, y);
    n += p.r == colour.r && p.g == colour.g && p.b == colour.b ? 1 : 0;
  }
  return n;
}

// The scale bar is as long as the scene's own lengths: a 1 × 1 square seen from the top spans
// twice the pixels of a bar of 0.5.
TEST(ScaleBar, IsAsLongAsTheScenesLengthsAndNiceLengthsAreRound) {
  RenderRequest r;
  r.width = 400;
  r.height = 300;
  r.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  r.triangles = {{0, 1, 2}, {0, 2, 3}};
  r.triangle_colours = {Rgb{10, 200, 10}, Rgb{10, 200, 10}};
  r.scale_bar = 0.5;
  const RgbImage image = renderScene(r);
  std::size_t square = 0;
  for (int x = 0; x < image.width; ++x) {
    const Rgb p = image.at(x, image.height / 2);
    square += p.g > 100 && p.r < 60 ? 1 : 0;
  }
  const std::size_t bar = countColour(image, image.height - 14, Rgb{0, 0, 0});
  ASSERT_GT(square, 100u);
  EXPECT_NEAR(static_cast<double>(bar), 0.5 * static_cast<double>(square), 3.0);
  EXPECT_EQ(niceLength(0.37), 0.2);
  EXPECT_EQ(niceLength(0.05), 0.05);
  EXPECT_EQ(niceLength(0.099), 0.05);
  EXPECT_NEAR(niceLength(0.0023), 0.002, 1e-15);
}

// A breakdown bar's segments take their fractions of the bar.
TEST(BreakdownBarFigure, SegmentsTakeTheirShareOfTheBar) {
  ViewGrid grid;
  ViewRow& row = grid.rows.emplace_back();
  row.title = "t";
  row.views = {RgbImage::filled(600, 50, Rgb{255, 255, 255})};
  const std::array<Rgb, 3> colours{Rgb{230, 159, 0}, Rgb{150, 150, 150}, Rgb{0, 114, 178}};
  const std::array<double, 3> shares{0.1, 0.6, 0.3};
  BreakdownBar& bar = grid.bars.emplace_back();
  bar.title = "Why:";
  for (std::size_t i = 0; i < 3; ++i) bar.segments.push_back({colours[i], shares[i], ""});
  const RgbImage image = drawViewGrid(grid);
  // The bar's middle row: the last rows of the image hold the bar (then the padding).
  const int y = image.height - 10 - 12;
  std::array<double, 3> px{};
  double total = 0.0;
  for (std::size_t i = 0; i < 3; ++i) {
    px[i] = static_cast<double>(countColour(image, y, colours[i]));
    total += px[i];
  }
  ASSERT_GT(total, 400.0);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(px[i] / total, shares[i], 0.01) << i;
}

}  // namespace
}  // namespace scanplan::cli
