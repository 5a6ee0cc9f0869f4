#include "cli/image_io.h"

#include "kinematics/error.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
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

SvgFigure mapFigure() {
  SvgFigure figure;
  figure.png_file = "maps/coverage.png";
  figure.png_width = 1000;
  figure.png_height = 360;
  figure.title = "Coverage & overlap <per pass>";
  figure.x_label = "table angle (deg)";
  figure.y_label = "height (mm)";
  figure.x_min = 0;
  figure.x_max = 360;
  figure.y_min = -1;
  figure.y_max = 1;
  figure.legend = {{categoryColour(0), "seen"}, {categoryColour(1), "missed"}};
  return figure;
}

TEST(Svg, FigureHasImageTicksEscapedTextAndLegend) {
  const std::string svg = svgFigure(mapFigure());
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_NE(svg.find("href=\"maps/coverage.png\""), std::string::npos);
  EXPECT_NE(svg.find("image-rendering: pixelated"), std::string::npos);
  // 1000 × 360 scaled by 0.72 to fit 720 × 480.
  EXPECT_NE(svg.find("width=\"720.0\" height=\"259.2\""), std::string::npos);
  // 0..360: step 50 gives 8 ticks; -1..1: step 0.5 gives 5 ticks with one decimal.
  for (const char* tick : {">0<", ">50<", ">350<", ">-1.0<", ">-0.5<", ">0.0<", ">1.0<"}) {
    EXPECT_NE(svg.find(tick), std::string::npos) << tick;
  }
  EXPECT_EQ(svg.find(">400<"), std::string::npos);
  EXPECT_NE(svg.find("Coverage &amp; overlap &lt;per pass&gt;"), std::string::npos);
  EXPECT_NE(svg.find("table angle (deg)"), std::string::npos);
  EXPECT_NE(svg.find("fill=\"rgb(86,180,233)\""), std::string::npos);
  EXPECT_NE(svg.find(">missed<"), std::string::npos);
}

TEST(Svg, TextIsWellFormed) {
  SvgFigure figure = mapFigure();
  figure.x_min = 0.0012;  // reversed, small range
  figure.x_max = -0.0031;
  const std::string svg = svgFigure(figure);
  // Every '&' starts an entity, and tags balance: each '<' has its '>' before the next '<'.
  for (std::size_t at = svg.find('&'); at != std::string::npos; at = svg.find('&', at + 1)) {
    const std::string entity = svg.substr(at, svg.find(';', at) - at + 1);
    EXPECT_TRUE(entity == "&amp;" || entity == "&lt;" || entity == "&gt;" || entity == "&quot;")
        << entity;
  }
  int open = 0;
  for (const char c : svg) {
    if (c == '<') {
      EXPECT_EQ(open++, 0);
    } else if (c == '>') {
      EXPECT_EQ(--open, 0);
    }
  }
  // Span 0.0043: steps 0.002 give two ticks, 0.001 five (-0.003 … 0.001), three decimals.
  EXPECT_NE(svg.find(">-0.003<"), std::string::npos);
  EXPECT_NE(svg.find(">0.001<"), std::string::npos);
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

}  // namespace
}  // namespace scanplan::cli
