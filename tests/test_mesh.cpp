#include <scanplan/kinematics/mesh.h>

#include <scanplan/kinematics/error.h>

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <map>
#include <numbers>
#include <ostream>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

// assimp 5.2's ASCII STL reader throws "Invalid number of vertices" after allocating its mesh
// and node, and never frees them (twoVertices.ascii.stl below). Not ours to fix; keep
// LeakSanitizer builds (SCANPLAN_SANITIZE) green. Unused without the sanitizer runtime.
extern "C" const char* __lsan_default_suppressions() { return "leak:libassimp.so\n"; }

namespace scanplan::kinematics {
namespace {

namespace fs = std::filesystem;

// Files store float32 coordinates (~6e-8 relative); the writers below print 9 significant
// digits, which round-trips a float exactly, so only float rounding of inputs remains.
constexpr double kFloatTol = 1e-6;

const fs::path kSharedData = SCANPLAN_SHARED_DATA_DIR;

struct Facet {
  Eigen::Vector3d normal;
  Eigen::Vector3d a, b, c;
};

struct Soup {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> triangles;
};

// Corner i of the cube [0, s]³ is (x, y, z) = bits (0, 1, 2) of i; every face is two
// triangles counter-clockwise seen from outside (checked by hand: cross products point out).
Soup cube(double s) {
  Soup soup;
  for (int i = 0; i < 8; ++i) {
    soup.vertices.emplace_back(s * (i & 1), s * ((i >> 1) & 1), s * (i >> 2));
  }
  soup.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                    {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return soup;
}

// Unit corner tetrahedron: three right-angled faces of area 1/2 and one equilateral face of
// side √2, area √3/2.
Soup tetrahedron() {
  Soup soup;
  soup.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  soup.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return soup;
}
const double kTetrahedronArea = 1.5 + std::sqrt(3.0) / 2.0;

std::vector<Facet> facets(const Soup& soup) {
  std::vector<Facet> out;
  for (const auto& t : soup.triangles) {
    const auto& a = soup.vertices[static_cast<std::size_t>(t[0])];
    const auto& b = soup.vertices[static_cast<std::size_t>(t[1])];
    const auto& c = soup.vertices[static_cast<std::size_t>(t[2])];
    out.push_back({(b - a).cross(c - a).normalized(), a, b, c});
  }
  return out;
}

std::string asciiStl(const std::vector<Facet>& list) {
  std::ostringstream s;
  s.precision(9);
  const auto vec = [&](const Eigen::Vector3d& v) { s << v.x() << ' ' << v.y() << ' ' << v.z(); };
  s << "solid test\n";
  for (const auto& f : list) {
    s << " facet normal ";
    vec(f.normal);
    s << "\n  outer loop\n";
    for (const auto* v : {&f.a, &f.b, &f.c}) {
      s << "   vertex ";
      vec(*v);
      s << '\n';
    }
    s << "  endloop\n endfacet\n";
  }
  s << "endsolid test\n";
  return s.str();
}

// Little-endian layout of binary STL: 80-byte header, uint32 count, 50 bytes per facet.
std::string binaryStl(const std::vector<Facet>& list, std::uint32_t stated_count) {
  std::string out(80, ' ');
  out.replace(0, 11, "binary test");
  const auto put = [&](const void* p, std::size_t n) {
    out.append(static_cast<const char*>(p), n);
  };
  put(&stated_count, 4);
  for (const auto& f : list) {
    for (const auto* v : {&f.normal, &f.a, &f.b, &f.c}) {
      for (int i = 0; i < 3; ++i) {
        const auto x = static_cast<float>((*v)[i]);
        put(&x, 4);
      }
    }
    const std::uint16_t attributes = 0;
    put(&attributes, 2);
  }
  return out;
}

std::string obj(const Soup& soup) {
  std::ostringstream s;
  s.precision(9);
  for (const auto& v : soup.vertices) s << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
  for (const auto& t : soup.triangles) {
    s << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  }
  return s.str();
}

std::string off(const Soup& soup) {
  std::ostringstream s;
  s.precision(9);
  s << "OFF\n" << soup.vertices.size() << ' ' << soup.triangles.size() << " 0\n";
  for (const auto& v : soup.vertices) s << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
  for (const auto& t : soup.triangles) s << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
  return s.str();
}

std::string asciiPly(const Soup& soup) {
  std::ostringstream s;
  s.precision(9);
  s << "ply\nformat ascii 1.0\nelement vertex " << soup.vertices.size()
    << "\nproperty float x\nproperty float y\nproperty float z\nelement face "
    << soup.triangles.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const auto& v : soup.vertices) s << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
  for (const auto& t : soup.triangles) s << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
  return s.str();
}

::testing::AssertionResult containsAll(const std::string& text,
                                       std::initializer_list<std::string> words) {
  for (const auto& w : words) {
    if (text.find(w) == std::string::npos) {
      return ::testing::AssertionFailure() << "'" << w << "' not found in: " << text;
    }
  }
  return ::testing::AssertionSuccess();
}

// The InputError message, or a failure marker when nothing (or something else) was thrown.
std::string loadError(const fs::path& path, const MeshLoadOptions& options = {}) {
  try {
    loadMesh(path, options);
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("<unexpected exception> ") + e.what();
  }
  return "<no exception>";
}

::testing::AssertionResult boxNear(const Eigen::AlignedBox3d& actual,
                                   const Eigen::AlignedBox3d& expected,
                                   double tol) {
  if ((actual.min() - expected.min()).norm() <= tol * expected.diagonal().norm() &&
      (actual.max() - expected.max()).norm() <= tol * expected.diagonal().norm()) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure()
         << "bounds [" << actual.min().transpose() << "] – [" << actual.max().transpose()
         << "], expected [" << expected.min().transpose() << "] – [" << expected.max().transpose()
         << "]";
}

// Independent of isClosed(): counts undirected edge uses only, ignoring orientation.
bool everyEdgeUsedTwice(const TriangleMesh& mesh) {
  std::map<std::pair<int, int>, int> uses;
  for (const auto& t : mesh.triangles) {
    for (int i = 0; i < 3; ++i) {
      const int a = t[i];
      const int b = t[(i + 1) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  }
  for (const auto& [edge, n] : uses) {
    if (n != 2) return false;
  }
  return true;
}

class MeshLoadTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("scanplan_test_mesh_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path write(const std::string& name, const std::string& bytes) const {
    const fs::path path = dir_ / name;
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }

  fs::path dir_;
};

MeshLoadOptions inMetres(double scale = 1.0) { return {LengthUnit::kMetre, scale}; }

TEST(TriangleMesh, EmptyMeshHasEmptyBoundsNoAreaAndIsNotClosed) {
  const TriangleMesh mesh;
  EXPECT_TRUE(mesh.bounds().isEmpty());
  EXPECT_EQ(mesh.area(), 0.0);
  EXPECT_FALSE(mesh.isClosed());
}

TEST(TriangleMesh, CubeWithOneFlippedTriangleIsNotClosed) {
  const Soup soup = cube(1.0);
  TriangleMesh mesh{soup.vertices, soup.triangles};
  EXPECT_TRUE(mesh.isClosed());
  std::swap(mesh.triangles[5][1], mesh.triangles[5][2]);
  EXPECT_TRUE(everyEdgeUsedTwice(mesh));
  EXPECT_FALSE(mesh.isClosed());
}

// The volume by the winding: s³ for an outward cube wherever it stands (the origin outside it),
// −s³ for the same cube inside out.
TEST(TriangleMesh, SignedVolumeIsTheCubesAndNegativeInsideOut) {
  const Soup soup = cube(2.0);
  TriangleMesh mesh{soup.vertices, soup.triangles};
  EXPECT_NEAR(mesh.signedVolume(), 8.0, 1e-12);
  for (Eigen::Vector3d& v : mesh.vertices) v += Eigen::Vector3d(5.0, -3.0, 7.0);
  EXPECT_NEAR(mesh.signedVolume(), 8.0, 1e-9);
  for (Eigen::Vector3i& t : mesh.triangles) std::swap(t[1], t[2]);
  EXPECT_TRUE(mesh.isClosed()) << "consistently oriented, inward";
  EXPECT_NEAR(mesh.signedVolume(), -8.0, 1e-9);
}

// 12 facets carry 36 corners; welding must leave the 8 cube corners. Area 6·s², s = 20 mm.
TEST_F(MeshLoadTest, AsciiStlCubeWeldsToEightVerticesInMillimetres) {
  const auto loaded = loadMesh(write("cube.stl", asciiStl(facets(cube(20.0)))));
  EXPECT_EQ(loaded.mesh.vertices.size(), 8u);
  EXPECT_EQ(loaded.mesh.triangles.size(), 12u);
  EXPECT_TRUE(loaded.mesh.isClosed());
  EXPECT_NEAR(loaded.mesh.area(), 6 * 0.02 * 0.02, kFloatTol * 6 * 0.02 * 0.02);
  EXPECT_TRUE(boxNear(loaded.mesh.bounds(),
                      {Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(0.02)}, kFloatTol));
  EXPECT_TRUE(loaded.report.warnings.empty());
}

// Binary cube of side 1.5 in metres, scaled by 2: side 3 m, area 54 m².
TEST_F(MeshLoadTest, BinaryStlCubeInMetresWithScale) {
  const auto loaded =
      loadMesh(write("cube_bin.stl", binaryStl(facets(cube(1.5)), 12)), inMetres(2.0));
  EXPECT_EQ(loaded.mesh.vertices.size(), 8u);
  EXPECT_EQ(loaded.mesh.triangles.size(), 12u);
  EXPECT_TRUE(loaded.mesh.isClosed());
  EXPECT_NEAR(loaded.mesh.area(), 54.0, kFloatTol * 54.0);
  EXPECT_TRUE(boxNear(loaded.mesh.bounds(),
                      {Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(3.0)}, kFloatTol));
}

TEST_F(MeshLoadTest, UnitsAndScaleMultiply) {
  const auto path = write("cube.stl", asciiStl(facets(cube(10.0))));
  const std::pair<MeshLoadOptions, double> cases[] = {{{LengthUnit::kMillimetre, 1.0}, 0.01},
                                                      {{LengthUnit::kMetre, 1.0}, 10.0},
                                                      {{LengthUnit::kMillimetre, 2.5}, 0.025},
                                                      {{LengthUnit::kMetre, 0.1}, 1.0}};
  for (const auto& [options, side] : cases) {
    SCOPED_TRACE(side);
    EXPECT_TRUE(boxNear(loadMesh(path, options).mesh.bounds(),
                        {Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(side)}, kFloatTol));
  }
}

// Welding, closedness and area must not depend on where the part sits (FCL's varying world
// frames): the same cube under seeded random rigid poses.
TEST_F(MeshLoadTest, CubeUnderVaryingPosesStaysWeldedAndClosed) {
  std::mt19937 rng(20240611);
  std::uniform_real_distribution<double> offset_mm(-500.0, 500.0);
  std::normal_distribution<double> gauss;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d axis = Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
    const Eigen::Matrix3d R_WC = Eigen::AngleAxisd(3.0 * gauss(rng), axis).toRotationMatrix();
    const Eigen::Vector3d p_WC(offset_mm(rng), offset_mm(rng), offset_mm(rng));
    Soup soup = cube(30.0);
    for (auto& v : soup.vertices) v = R_WC * v + p_WC;
    const auto loaded = loadMesh(write("posed.stl", asciiStl(facets(soup))));
    SCOPED_TRACE(k);
    EXPECT_EQ(loaded.mesh.vertices.size(), 8u);
    EXPECT_EQ(loaded.mesh.triangles.size(), 12u);
    EXPECT_TRUE(loaded.mesh.isClosed());
    EXPECT_NEAR(loaded.mesh.area(), 6 * 0.03 * 0.03, 1e-5 * 6 * 0.03 * 0.03);
  }
}

TEST_F(MeshLoadTest, TetrahedronInObjOffAndPly) {
  const Soup tet = tetrahedron();
  for (const auto& [name, text] : {std::pair{"tet.obj", obj(tet)}, std::pair{"tet.off", off(tet)},
                                   std::pair{"tet.ply", asciiPly(tet)}}) {
    SCOPED_TRACE(name);
    const auto loaded = loadMesh(write(name, text), inMetres());
    EXPECT_EQ(loaded.mesh.vertices.size(), 4u);
    EXPECT_EQ(loaded.mesh.triangles.size(), 4u);
    EXPECT_TRUE(loaded.mesh.isClosed());
    EXPECT_NEAR(loaded.mesh.area(), kTetrahedronArea, kFloatTol);
    EXPECT_TRUE(loaded.report.warnings.empty());
  }
}

TEST_F(MeshLoadTest, ObjQuadsAreTriangulated) {
  const std::string quads =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n"
      "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
  const auto loaded = loadMesh(write("cube_quads.obj", quads), inMetres());
  EXPECT_EQ(loaded.mesh.vertices.size(), 8u);
  EXPECT_EQ(loaded.mesh.triangles.size(), 12u);
  EXPECT_TRUE(loaded.mesh.isClosed());
  EXPECT_NEAR(loaded.mesh.area(), 6.0, kFloatTol);
}

// One polygon (corners in order, one face) as OBJ, PLY and OFF text, keyed by file name.
std::vector<std::pair<std::string, std::string>> polygonFiles(
    const std::string& stem, const std::vector<Eigen::Vector3d>& corners) {
  std::ostringstream v, obj_face, list;
  v.precision(9);
  for (std::size_t k = 0; k < corners.size(); ++k) {
    v << corners[k].x() << ' ' << corners[k].y() << ' ' << corners[k].z() << '\n';
    obj_face << ' ' << k + 1;
    list << ' ' << k;
  }
  const std::string n = std::to_string(corners.size());
  std::string obj;
  std::istringstream lines(v.str());
  for (std::string line; std::getline(lines, line);) obj += "v " + line + "\n";
  return {{stem + ".obj", obj + "f" + obj_face.str() + "\n"},
          {stem + ".ply", "ply\nformat ascii 1.0\nelement vertex " + n +
                              "\nproperty float x\nproperty float y\nproperty float z\nelement "
                              "face 1\nproperty list uchar int vertex_indices\nend_header\n" +
                              v.str() + n + list.str() + "\n"},
          {stem + ".off", "OFF\n" + n + " 1 0\n" + v.str() + n + list.str() + "\n"}};
}

// assimp's ear clipping cut a counter-clockwise L-shaped hexagon across its notch (area 4 for
// 3) and a star's points into overlapping triangles: a polygon of more than four corners that
// is not convex is refused naming the file, the face and its first corners. A convex hexagon
// (either winding) and a concave quad, which assimp cuts at its reflex corner, load with their
// true area.
TEST_F(MeshLoadTest, AConcavePolygonIsRefusedAndConvexOnesAreTriangulated) {
  const std::vector<Eigen::Vector3d> l_shape{{0, 0, 0}, {2, 0, 0}, {2, 1, 0},
                                             {1, 1, 0}, {1, 2, 0}, {0, 2, 0}};
  for (const auto& [name, text] : polygonFiles("l_shape", l_shape)) {
    SCOPED_TRACE(name);
    EXPECT_TRUE(containsAll(loadError(write(name, text), inMetres()),
                            {name, "face 1 is a polygon of 6 corners that is not convex",
                             "(0 0 0, 2 0 0, 2 1 0, …)", "expected triangles, quads or convex"}));
  }
  std::vector<Eigen::Vector3d> star, hexagon;
  for (int k = 0; k < 5; ++k) {
    const double a = std::numbers::pi / 2 + k * 4 * std::numbers::pi / 5;
    star.emplace_back(std::cos(a), std::sin(a), 0.0);
  }
  EXPECT_TRUE(containsAll(loadError(write("star.obj", polygonFiles("star", star)[0].second)),
                          {"star.obj", "face 1 is a polygon of 5 corners that is not convex"}));
  for (int k = 0; k < 6; ++k) {
    const double a = k * std::numbers::pi / 3;
    hexagon.emplace_back(std::cos(a), std::sin(a), 1.0);
  }
  const std::vector<Eigen::Vector3d> reversed(hexagon.rbegin(), hexagon.rend());
  const std::vector<Eigen::Vector3d> dart{{0, 0, 0}, {2, 0, 0}, {1, 0.5, 0}, {0, 2, 0}};
  for (const auto& [corners, area] :
       {std::pair{hexagon, 1.5 * std::sqrt(3.0)}, std::pair{reversed, 1.5 * std::sqrt(3.0)},
        std::pair{dart, 1.5}}) {
    for (const auto& [name, text] : polygonFiles("polygon", corners)) {
      SCOPED_TRACE(name);
      const auto loaded = loadMesh(write(name, text), inMetres());
      EXPECT_EQ(loaded.mesh.triangles.size(), corners.size() - 2);
      EXPECT_NEAR(loaded.mesh.area(), area, kFloatTol * area);
    }
  }
}

TEST_F(MeshLoadTest, ObjPointsAndLinesAreIgnoredWithAWarning) {
  const auto loaded =
      loadMesh(write("tet_extras.obj", obj(tetrahedron()) + "p 1\nl 1 2\n"), inMetres());
  EXPECT_EQ(loaded.mesh.triangles.size(), 4u);
  EXPECT_EQ(loaded.report.non_triangle_dropped, 2u);
  ASSERT_EQ(loaded.report.warnings.size(), 1u);
  EXPECT_TRUE(containsAll(loaded.report.warnings[0], {"tet_extras.obj", "2", "point/line"}));
}

TEST_F(MeshLoadTest, CubeWithoutTopFaceIsOpen) {
  Soup soup = cube(1.0);
  soup.triangles.erase(soup.triangles.begin() + 2, soup.triangles.begin() + 4);
  const auto loaded = loadMesh(write("open.stl", asciiStl(facets(soup))), inMetres());
  EXPECT_EQ(loaded.mesh.vertices.size(), 8u);
  EXPECT_EQ(loaded.mesh.triangles.size(), 10u);
  EXPECT_FALSE(loaded.mesh.isClosed());
  EXPECT_NEAR(loaded.mesh.area(), 5.0, kFloatTol);
}

// A facet with two equal corners welds to a repeated index; a collinear facet has zero area
// and references an edge midpoint nothing else uses, which must not stay as a dangling vertex.
TEST_F(MeshLoadTest, DegenerateTrianglesAreDroppedAndCounted) {
  auto list = facets(cube(1.0));
  const Eigen::Vector3d o(0, 0, 0), x(1, 0, 0);
  list.push_back({Eigen::Vector3d::UnitZ(), o, x, x});
  list.push_back({Eigen::Vector3d::UnitZ(), o, Eigen::Vector3d(0.5, 0, 0), x});
  const auto loaded = loadMesh(write("degenerate.stl", asciiStl(list)), inMetres());
  EXPECT_EQ(loaded.report.degenerate_dropped, 2u);
  EXPECT_EQ(loaded.mesh.vertices.size(), 8u);
  EXPECT_EQ(loaded.mesh.triangles.size(), 12u);
  EXPECT_TRUE(loaded.mesh.isClosed());
  ASSERT_EQ(loaded.report.warnings.size(), 1u);
  EXPECT_EQ(loaded.report.warnings[0], "degenerate.stl: dropped 2 degenerate triangles");
}

TEST_F(MeshLoadTest, StoredNormalAgainstTheWindingIsCountedAndWindingKept) {
  auto list = facets(cube(1.0));
  list[3].normal = -list[3].normal;
  list[7].normal = Eigen::Vector3d::Zero();  // STL allows zero normals: not a disagreement
  const auto loaded = loadMesh(write("flipped_normal.stl", asciiStl(list)), inMetres());
  EXPECT_EQ(loaded.report.normals_disagreeing, 1u);
  EXPECT_TRUE(loaded.mesh.isClosed());
  ASSERT_EQ(loaded.report.warnings.size(), 1u);
  EXPECT_TRUE(containsAll(loaded.report.warnings[0], {"flipped_normal.stl", "1", "normal"}));
}

TEST_F(MeshLoadTest, SameFileLoadsIdentically) {
  const auto path = write("cube.stl", asciiStl(facets(cube(7.0))));
  const auto first = loadMesh(path);
  const auto second = loadMesh(path);
  EXPECT_EQ(first.mesh.vertices, second.mesh.vertices);
  EXPECT_EQ(first.mesh.triangles, second.mesh.triangles);
}

TEST_F(MeshLoadTest, MissingFileAndDirectoryAreInputErrors) {
  EXPECT_TRUE(containsAll(loadError(dir_ / "nowhere.stl"), {"nowhere.stl", "does not exist"}));
  fs::create_directory(dir_ / "folder.stl");
  EXPECT_TRUE(containsAll(loadError(dir_ / "folder.stl"), {"folder.stl", "is a directory"}));
}

// An ASCII STL facet is a triangle: a facet of four corners (which assimp would cut to three)
// or of two is refused naming the file and the facet's line; the cube it sits in still loads.
TEST_F(MeshLoadTest, AnStlFacetOtherThanATriangleIsRefusedNamingItsLine) {
  const std::string cube_text = asciiStl(facets(cube(7.0)));
  EXPECT_EQ(loadMesh(write("cube.stl", cube_text)).mesh.triangles.size(), 12u);
  const auto withFacet = [&](const std::string& corners) {
    const std::string facet = "facet normal 0 0 1\nouter loop\n" + corners + "endloop\nendfacet\n";
    std::string text = cube_text;
    return text.insert(text.find("facet"), facet);
  };
  const std::string quad = withFacet("vertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\n");
  EXPECT_TRUE(containsAll(loadError(write("quad.stl", quad)),
                          {"quad.stl", "a facet with 4 vertices; expected 3"}));
  const std::string line = withFacet("vertex 0 0 0\nvertex 1 0 0\n");
  EXPECT_TRUE(containsAll(loadError(write("line.stl", line)),
                          {"line.stl", "line 7: a facet with 2 vertices; expected 3"}));
}

// STL words are read as assimp reads them: a solid named with a keyword is a name, and a last
// facet of four vertices whose `endfacet` is missing is refused naming the line it starts on.
TEST_F(MeshLoadTest, AnStlFacetIsCountedFromFacetToItsEndLikeAssimp) {
  const std::string body = asciiStl(facets(cube(7.0)));
  std::string named = body;
  named.replace(0, named.find('\n'), "solid vertex_part endfacet");
  EXPECT_EQ(loadMesh(write("named.stl", named)).mesh.triangles.size(), 12u);
  const std::string open =
      "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\n"
      "endloop\n";
  std::string text = body;
  const auto end = text.rfind("endsolid");
  const auto line = std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(end), '\n');
  text.insert(end, open);
  EXPECT_TRUE(containsAll(
      loadError(write("open.stl", text)),
      {"open.stl", "line " + std::to_string(line + 1) + ": a facet with 4 vertices; expected 3"}));
}

TEST_F(MeshLoadTest, EmptyFileIsAnInputError) {
  EXPECT_TRUE(containsAll(loadError(write("nothing.stl", "")), {"nothing.stl", "is empty"}));
}

TEST_F(MeshLoadTest, UnsupportedExtensionListsTheSupportedOnes) {
  EXPECT_TRUE(containsAll(loadError(write("part.step", "ISO-10303-21;\n")),
                          {"part.step", "unsupported extension", ".stl .obj .ply .off"}));
}

// Header says 12 facets, the file holds 4: assimp cannot tell binary from ASCII any more.
TEST_F(MeshLoadTest, TruncatedBinaryStlIsAnInputError) {
  auto list = facets(cube(1.0));
  list.resize(4);
  EXPECT_TRUE(containsAll(loadError(write("truncated.stl", binaryStl(list, 12))),
                          {"truncated.stl", "could not be read", "STL"}));
}

TEST_F(MeshLoadTest, GarbageAndFacelessFilesAreInputErrors) {
  struct Case {
    const char* name;
    const char* text;
    const char* says;
  };
  const Case cases[] = {
      {"garbage.stl", "this is not a mesh at all, just some words\n", "could not be read"},
      {"garbage_solid.stl", "solid x\n nonsense here\nendsolid x\n", "could not be read"},
      {"garbage.off", "garbage\n", "does not start with the OFF keyword"},
      {"garbage.ply", "garbage\n", "no complete PLY header"},
      {"points_only.obj", "v 0 0 0\nv 1 0 0\np 1\nl 1 2\n", "no triangles"}};
  for (const auto& c : cases) {
    EXPECT_TRUE(containsAll(loadError(write(c.name, c.text)), {c.name, c.says}));
  }
}

TEST_F(MeshLoadTest, NonFiniteCoordinatesAreInputErrors) {
  const auto nan_path = write("nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_TRUE(containsAll(loadError(nan_path), {"nan.obj", "non-finite"}));
  // 1e39 overflows the float32 assimp stores coordinates in.
  const auto inf_path = write("inf.obj", "v 1e39 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_TRUE(containsAll(loadError(inf_path), {"inf.obj", "non-finite"}));
}

TEST_F(MeshLoadTest, BadScaleIsAnInputError) {
  const auto path = write("cube.stl", asciiStl(facets(cube(1.0))));
  for (double scale : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(),
                       std::numeric_limits<double>::infinity()}) {
    SCOPED_TRACE(scale);
    EXPECT_TRUE(containsAll(loadError(path, {LengthUnit::kMillimetre, scale}),
                            {"cube.stl", "scale", "finite number > 0"}));
  }
}

// ---- Shared third-party data (skipped when ../shared/data is absent) ----

struct SharedMesh {
  const char* file;
  LengthUnit units;
  std::size_t triangles;
  bool closed;
  int genus;          // for closed meshes: V = 2 − 2g + F/2 checks the welding (Euler)
  double extent_x_m;  // 0 when SOURCES.md gives no size
};

void PrintTo(const SharedMesh& c, std::ostream* os) { *os << c.file; }

class SharedMeshTest : public ::testing::TestWithParam<SharedMesh> {};

// Counts and sizes from shared/data/SOURCES.md; no degenerate triangles in any of them.
TEST_P(SharedMeshTest, LoadsWithDocumentedTriangleCount) {
  const fs::path dir = kSharedData / "meshes";
  if (!fs::is_directory(dir)) GTEST_SKIP() << dir << " absent";
  const SharedMesh& c = GetParam();
  const auto loaded = loadMesh(dir / c.file, {c.units, 1.0});
  EXPECT_EQ(loaded.mesh.triangles.size(), c.triangles);
  EXPECT_EQ(loaded.report.degenerate_dropped, 0u);
  EXPECT_TRUE(loaded.report.warnings.empty());
  EXPECT_EQ(loaded.mesh.isClosed(), c.closed);
  if (c.closed) {
    EXPECT_EQ(static_cast<long>(loaded.mesh.vertices.size()),
              2 - 2 * c.genus + static_cast<long>(c.triangles / 2));
  }
  if (c.extent_x_m > 0) {
    EXPECT_NEAR(loaded.mesh.bounds().sizes().x(), c.extent_x_m, 1e-3 * c.extent_x_m);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Meshes,
    SharedMeshTest,
    ::testing::Values(
        SharedMesh{"stlmodels_bunny.bin.stl", LengthUnit::kMetre, 69451, false, 0, 0.1557},
        SharedMesh{"stlmodels_gearwheel.bin.stl", LengthUnit::kMillimetre, 2444, true, 1, 0.0417},
        SharedMesh{"cgal_fandisk.off", LengthUnit::kMetre, 12946, true, 0, 0},
        SharedMesh{"cgal_couplingdown.off", LengthUnit::kMetre, 3714, true, 9, 0},
        SharedMesh{"openscad_example006.stl", LengthUnit::kMillimetre, 11884, true, 0, 0.1},
        SharedMesh{"bunny_npm_3674.obj", LengthUnit::kMetre, 3674, true, 0, 0}),
    [](const ::testing::TestParamInfo<SharedMesh>& param) {
      std::string name = param.param.file;
      for (char& ch : name) {
        if (std::isalnum(static_cast<unsigned char>(ch)) == 0) ch = '_';
      }
      return name;
    });

TEST(SharedBrokenMeshes, EachThrowsOrWarnsAsAssimpAllows) {
  const fs::path dir = kSharedData / "meshes" / "broken";
  if (!fs::is_directory(dir)) GTEST_SKIP() << dir << " absent";

  EXPECT_TRUE(containsAll(loadError(dir / "empty.stl"), {"empty.stl", "is empty"}));
  // 66 facets stated, 4 held: the size fits neither layout, assimp refuses the file.
  EXPECT_TRUE(containsAll(loadError(dir / "incorrectFaceCounter.bin.stl"),
                          {"incorrectFaceCounter.bin.stl", "could not be read", "STL"}));
  // An STL facet is a triangle: one of two or four corners is refused naming its line (assimp
  // would keep three corners of the quad and drop the fourth).
  EXPECT_TRUE(containsAll(loadError(dir / "twoVertices.ascii.stl"),
                          {"twoVertices.ascii.stl", "a facet with 2 vertices; expected 3"}));
  EXPECT_TRUE(containsAll(loadError(dir / "quad.ascii.stl"),
                          {"quad.ascii.stl", "line 9: a facet with 4 vertices; expected 3"}));

  // Its normals are all zero, which STL permits; the winding is consistent, so it is a
  // correct closed tetrahedron with nothing to report.
  const auto wrong = loadMesh(dir / "wrongNormals.ascii.stl", inMetres());
  EXPECT_EQ(wrong.mesh.triangles.size(), 4u);
  EXPECT_EQ(wrong.report.normals_disagreeing, 0u);
  EXPECT_TRUE(wrong.report.warnings.empty());
  EXPECT_TRUE(wrong.mesh.isClosed());
}

// Viper s650 link meshes are ASCII STL in metres. Only link6 is a closed, consistently
// oriented surface: link2 is watertight but 3 facets are wound inwards (SOURCES.md calls it
// closed in the watertight sense), the others have holes or non-manifold edges.
TEST(SharedRobotMeshes, ViperLinksLoadInMetres) {
  const fs::path dir = kSharedData / "robots" / "viper_s650";
  if (!fs::is_directory(dir)) GTEST_SKIP() << dir << " absent";
  const std::size_t triangles[] = {2000, 1999, 2000, 2000, 2000, 1999, 580};
  for (int k = 0; k <= 6; ++k) {
    SCOPED_TRACE(k);
    const auto loaded = loadMesh(dir / ("link" + std::to_string(k) + ".stl"), inMetres());
    EXPECT_EQ(loaded.mesh.triangles.size(), triangles[k]);
    EXPECT_TRUE(loaded.report.warnings.empty());
    const double size = loaded.mesh.bounds().sizes().maxCoeff();
    EXPECT_GT(size, 0.05);  // a link of a 650 mm-reach arm, not millimetres read as metres
    EXPECT_LT(size, 0.5);
    EXPECT_EQ(loaded.mesh.isClosed(), k == 6);
    if (k == 2) {
      EXPECT_TRUE(everyEdgeUsedTwice(loaded.mesh));
    }
  }
}

}  // namespace
// Inputs that made the loader loop, allocate without end or wait forever: each is
// refused by the pre-check, quickly, naming the file.
TEST_F(MeshLoadTest, TruncatedHeadersHugeCountsAndPipesAreRefusedBeforeTheLoader) {
  const auto header_only = write("header.ply", "ply\nformat ascii 1.0\n");
  EXPECT_NE(loadError(header_only).find("no complete PLY header"), std::string::npos)
      << loadError(header_only);
  const auto billion = write("billion.ply",
                             "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\n"
                             "property float x\nproperty float y\nproperty float z\nend_header\n");
  EXPECT_NE(loadError(billion).find("claims 1000000000 PLY elements"), std::string::npos)
      << loadError(billion);
  const auto off = write("huge.off", "OFF\n# a comment\n2147483648 1 0\n0 0 0\n");
  EXPECT_NE(loadError(off).find("claims 2147483648 vertices"), std::string::npos) << loadError(off);
  const fs::path fifo = dir_ / "pipe.stl";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(loadError(fifo).find("is not a regular file"), std::string::npos) << loadError(fifo);
  for (const auto& p : {header_only, billion, off, fifo})
    EXPECT_NE(loadError(p).find(p.filename().string()), std::string::npos);
  // A well-formed small PLY still loads (the pre-check counts what the header claims).
  const auto good = write("tri.ply",
                          "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                          "property float y\nproperty float z\nelement face 1\n"
                          "property list uchar int vertex_indices\nend_header\n"
                          "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(loadError(good), "<no exception>");
}

// Found by fuzzing (tests/fuzz, mesh): a PLY face of length 0 passes assimp's validation and
// counts as a polygon, and assimp's triangulation then aborted the process (an assertion in
// TriangulateProcess). The loader refuses the face first.
TEST_F(MeshLoadTest, FaceWithNoVertexIndexIsAnInputErrorNotAnAbort) {
  const auto empty_face = write("empty_face.ply",
                                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                "property float y\nproperty float z\nelement face 2\n"
                                "property list uchar int vertex_indices\nend_header\n"
                                "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n0\n");
  EXPECT_TRUE(containsAll(loadError(empty_face),
                          {"empty_face.ply", "face 2 has no vertex index", "expected 3 or more"}));
}

// Found by fuzzing (tests/fuzz, mesh): with more than `end_header` on the header's last line,
// assimp's PLY reader never returned (it seeks at the end of the file for ever). Refused first;
// trailing blanks and CRLF stay fine.
TEST_F(MeshLoadTest, PlyEndHeaderWithMoreOnItsLineIsAnInputErrorNotAHang) {
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\n";
  const std::string body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  const auto glued = write("glued.ply", header + "end_header0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_TRUE(containsAll(loadError(glued), {"glued.ply", "more than 'end_header'"}));
  const auto words = write("words.ply", header + "end_header 0\n" + body);
  EXPECT_TRUE(containsAll(loadError(words), {"words.ply", "more than 'end_header'"}));
  EXPECT_EQ(loadError(write("blank.ply", header + "end_header \t\r\n" + body)), "<no exception>");
}

// Robustness catalogue: assimp's OFF reader clamps a face index past the last vertex
// to the last vertex (and reads a negative one as 0), without a word. The pre-check reads the
// faces itself and refuses them naming the face, the index and the vertex count.
TEST_F(MeshLoadTest, OffFaceIndicesOutOfRangeOrNotNumbersAreRefusedNamingTheFace) {
  const std::string head = "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  const auto error = [&](const std::string& name, const std::string& face) {
    return loadError(write(name, head + face));
  };
  EXPECT_TRUE(containsAll(error("past.off", "3 0 1 7\n"),
                          {"past.off",
                           "line 7 ('3 0 1 7'), OFF face 2 of 2, has vertex index 7 out "
                           "of range: the file has 3 vertices; expected indices from 0 "
                           "to 2"}));
  EXPECT_TRUE(containsAll(error("negative.off", "3 0 -1 2\n"),
                          {"negative.off", "line 7 ('3 0 -1 2'), OFF face 2 of 2",
                           "vertex index '-1'; expected an index from 0 to 2"}));
  EXPECT_TRUE(containsAll(error("short.off", "3 0 1\n"),
                          {"short.off", "OFF face 2 of 2, has 2 of its 3 vertex indices"}));
  // assimp drops a face of more than 9 corners without a word.
  EXPECT_TRUE(containsAll(error("ten.off", "10 0 1 2 0 1 2 0 1 2 0\n"),
                          {"ten.off", "line 7 ('10 0 1 2", "OFF face 2 of 2", "1 to 9"}));
  EXPECT_TRUE(containsAll(
      loadError(write("few.off", head)),
      {"few.off", "has 1 of the 2 faces its OFF header declares", "(a truncated file)"}));
  // assimp reads a comment line among the faces as a face of no corners and drops it.
  EXPECT_TRUE(
      containsAll(error("comment.off", "# a comment\n3 0 1 2\n"),
                  {"comment.off", "line 7 ('# a comment'), OFF face 2 of 2", "vertex count"}));
}

// Robustness catalogue: an ASCII PLY with fewer elements than its header gives, or
// an element cut short, was read with the rest made up (0) by assimp.
TEST_F(MeshLoadTest, AsciiPlyBodyMustHoldWhatItsHeaderGives) {
  const Soup soup = tetrahedron();
  const std::string whole = asciiPly(soup);
  const auto cut = [&](const std::string& name, std::size_t drop) {
    return loadError(write(name, whole.substr(0, whole.size() - drop)));
  };
  EXPECT_TRUE(containsAll(cut("lines.ply", 16), {"lines.ply",
                                                 "has 2 of the 4 'face' lines its PLY header "
                                                 "declares",
                                                 "a truncated file"}));
  EXPECT_TRUE(containsAll(cut("mid.ply", 20),
                          {"mid.ply", "line 15 ('3 0 '), 'face' 2 of 4",
                           "1 value left for property 'vertex_indices', which wants 3"}));
  std::string text = whole;
  text.replace(text.find("\n1 0 0\n") + 1, 1, "x");
  EXPECT_TRUE(containsAll(loadError(write("word.ply", text)),
                          {"word.ply", "line 11 ('x 0 0'), 'vertex' 2 of 4",
                           "'x' for property 'x' (float); expected a number"}));
  EXPECT_EQ(loadError(write("whole.ply", whole + "\n\n")), "<no exception>");
}

// Loader work is bounded by the triangles, counted before assimp reads the file (a PLY's from
// its faces' corner lists, ASCII or binary) and counted exactly again after reading, before its
// polygons are triangulated (for what the pre-check counts short: an OBJ face continued over
// lines).
TEST_F(MeshLoadTest, MeshesOverTheTriangleLimitAreRefusedBeforeTheExpensiveSteps) {
  std::string many =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 4000001\n"
      "property list uchar int vertex_indices\nend_header\n" +
      std::string(36, '\0');
  const std::string triangle("\x03\0\0\0\0\x01\0\0\0\x02\0\0\0", 13);  // 3 corners: 0 1 2
  many.reserve(many.size() + 4000001 * triangle.size());
  for (int f = 0; f < 4000001; ++f) many += triangle;
  EXPECT_TRUE(containsAll(loadError(write("many.ply", many)),
                          {"many.ply",
                           "has 4000001 triangles (counted before reading it); expected at most "
                           "4000000"}));

  // assimp takes at most 32 767 corners a face: 123 such faces make 4 030 095 triangles.
  const std::uint32_t corners = 32767, polygons = 123;
  std::string polygon =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face " +
      std::to_string(polygons) + "\nproperty list uint int vertex_indices\nend_header\n";
  const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  polygon.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
  for (std::uint32_t f = 0; f < polygons; ++f) {
    polygon.append(reinterpret_cast<const char*>(&corners), sizeof corners);
    for (std::uint32_t k = 0; k < corners; ++k) {
      const std::int32_t index = static_cast<std::int32_t>(k % 3);
      polygon.append(reinterpret_cast<const char*>(&index), sizeof index);
    }
  }
  EXPECT_TRUE(containsAll(loadError(write("polygon.ply", polygon)),
                          {"polygon.ply",
                           "has 4030095 triangles (counted before reading it); expected at most "
                           "4000000"}));

  // The same as OBJ faces continued over lines ('\\' at a line's end): the pre-check counts only
  // each face's first line; loadMesh counts the faces assimp read.
  std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  for (std::uint32_t f = 0; f < polygons; ++f) {
    obj += "f";
    for (std::uint32_t k = 0; k < corners; ++k) {
      obj += ' ' + std::to_string(k % 3 + 1) + (k % 1000 == 999 ? " \\\n" : "");
    }
    obj += '\n';
  }
  // (Its faces, repeating three corners, are not convex polygons either: that refusal, also
  // before triangulating, comes first.)
  const std::string error = loadError(write("polygon.obj", obj));
  EXPECT_TRUE(
      containsAll(error, {"polygon.obj", "has 4030095 triangles; expected at most 4000000"}) ||
      containsAll(error, {"polygon.obj", "is a polygon of 32767 corners that is not convex"}))
      << error;
}

// `value` as a binary PLY file stores it: little-endian (this host's order) or big-endian.
template <typename T>
std::string plyBinary(T value, bool big_endian = false) {
  std::string out(sizeof(T), '\0');
  std::memcpy(out.data(), &value, sizeof(T));
  if (big_endian) std::reverse(out.begin(), out.end());
  return out;
}

// Found by fuzzing (tests/fuzz, mesh; the heap corruption AddressSanitizer reported inside
// libassimp thousands of inputs later): assimp's PLY reader sizes the mesh's vertex and face
// arrays by the first 'vertex' and 'face' element and writes every later one's entries into them
// by index, so a second, longer element writes past their end (valgrind: invalid writes in
// libassimp). Refused from the header.
TEST_F(MeshLoadTest, PlyWithASecondVertexOrFaceElementIsAnInputErrorNotHeapCorruption) {
  const std::string lines9 = "0\n0\n0\n0\n0\n0\n0\n0\n0\n";
  const auto vertices = write("two_vertex.ply",
                              "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                              "element vertex 9\nproperty float x\nend_header\n0\n" +
                                  lines9);
  EXPECT_TRUE(containsAll(loadError(vertices),
                          {"two_vertex.ply", "line 5 of its PLY header ('element vertex 9')",
                           "second vertex element", "line 3", "expected one 'vertex' element"}));
  const std::string tet = asciiPly(tetrahedron());
  const std::string header = tet.substr(0, tet.find("end_header"));
  const std::string body = tet.substr(tet.find("end_header") + 11);
  const auto faces =
      write("two_face.ply", header + "element face 9\nproperty list uchar int vertex_indices\n" +
                                "end_header\n" + body + std::string(9, '\n'));
  EXPECT_TRUE(containsAll(loadError(faces), {"two_face.ply", "second face element"}));
  const auto strips =
      write("strips.ply", header + "element tristrips 1\nproperty list int int vertex_indices\n" +
                              "end_header\n" + body + "5 0 1 2 3 0\n");
  EXPECT_TRUE(containsAll(loadError(strips), {"strips.ply", "('element tristrips 1')",
                                              "second face element", "'face' on line 7"}));
}

// Found by fuzzing (tests/fuzz, mesh; an out-of-memory once the above was refused): assimp
// allocates a list's length before reading its values, so an ASCII length of 377777777777777
// (taken modulo 2³² by its 32-bit reader: 1044356209 values of 8 bytes) or a binary one of
// 2³²−1 asked for gigabytes. Each list length must be a whole number the line or file holds.
TEST_F(MeshLoadTest, PlyListLengthsTheDataDoesNotHoldAreInputErrorsNotHugeAllocations) {
  const std::string tet = asciiPly(tetrahedron());
  const std::string header = tet.substr(0, tet.find("end_header") + 11);
  const std::string vertices = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
  const auto huge = write(
      "huge.ply", header + vertices + "3 0 2 1\n377777777777777 0 1 3\n" + "3 0 3 2\n3 1 2 3\n");
  EXPECT_TRUE(containsAll(loadError(huge), {"huge.ply", "line 15 ('377777777777777 0 1 3')",
                                            "list length '377777777777777'", "up to 32767"}));
  const auto short_line =
      write("short.ply", header + vertices + "3 0 2 1\n3 0 1\n3 0 3 2\n3 1 2 3\n");
  EXPECT_TRUE(containsAll(loadError(short_line),
                          {"short.ply", "line 15 ('3 0 1')", "2 values left", "wants 3"}));
  const auto truncated = write("truncated.ply", header + vertices + "3 0 2 1\n3 0 1 3\n");
  EXPECT_TRUE(
      containsAll(loadError(truncated), {"truncated.ply", "2 of the 4 'face' lines", "truncated"}));

  const std::string binary_header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\n"
      "property list uint int vertex_indices\nend_header\r\n";
  std::string points;
  for (const float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) points += plyBinary(v);
  const std::string corners = plyBinary(0) + plyBinary(1) + plyBinary(2);
  const auto binary_huge =
      write("binary_huge.ply", binary_header + points + plyBinary(0xffffffffu) + corners);
  EXPECT_TRUE(containsAll(loadError(binary_huge),
                          {"binary_huge.ply", "list 'vertex_indices' of 4294967295 values",
                           "in 'face' 1 (byte 205)", "expected 0 to 32767"}));
  std::string signed_header = binary_header;
  signed_header.replace(signed_header.find("list uint"), 9, "list char");
  const auto negative =
      write("negative.ply", signed_header + points + plyBinary<std::int8_t>(-1) + corners);
  EXPECT_TRUE(containsAll(loadError(negative), {"negative.ply", "of -1 values"}));
  const auto binary_cut =
      write("binary_cut.ply", binary_header + points + plyBinary(3u) + corners.substr(0, 10));
  EXPECT_TRUE(containsAll(loadError(binary_cut), {"binary_cut.ply", "ends inside 'face' 1 of 1"}));
  EXPECT_EQ(loadError(write("good.ply", binary_header + points + plyBinary(3u) + corners)),
            "<no exception>");
}

// Six texture coordinates on a face make assimp read three corners from its corner list: with
// no list it read through a null pointer (a segmentation fault), with a shorter one past it.
TEST_F(MeshLoadTest, PlyFaceTextureCoordinatesWithoutCornersAreAnInputErrorNotACrash) {
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\n";
  const std::string vertices = "0 0 0\n1 0 0\n0 1 0\n";
  const auto alone = write("alone.ply", header + "property list uchar float texcoord\n" +
                                            "end_header\n" + vertices + "6 0 0 1 0 0 1\n");
  const std::string six =
      "line 13 ('6 0 0 1 0 0 1'), 'face' 1 of 1, has 6 texture coordinates and 0 corners";
  EXPECT_TRUE(containsAll(loadError(alone), {"alone.ply", six}));
  const std::string both =
      "property list uchar int vertex_indices\nproperty list uchar float texcoord\nend_header\n";
  const auto one = write("one.ply", header + both + vertices + "1 0 6 0 0 1 0 0 1\n");
  const std::string per_corner = "expected two coordinates per corner";
  EXPECT_TRUE(containsAll(loadError(one), {"one.ply", "and 1 corners", per_corner}));
  EXPECT_EQ(loadError(write("uv.ply", header + both + vertices + "3 0 1 2 6 0 0 1 0 0 1\n")),
            "<no exception>");
}

// Headers assimp reads its own way: it ends an element's properties at the first line that is
// not one (the rest are dropped and every later value lands in the wrong property), skips a
// property of a type it does not know, splits lines at control characters, and drops binary
// data's first byte when it is a line feed after a header ending in a bare line feed. Such files
// loaded wrong without a word (a comment before 'property float z': a tetrahedron flattened to
// z = 0) or failed on something else; now refused, naming the line.
TEST_F(MeshLoadTest, PlyHeadersAssimpWouldMisreadAreInputErrors) {
  const std::string tet = asciiPly(tetrahedron());
  const auto with = [&](const std::string& from, const std::string& to) {
    std::string text = tet;
    text.replace(text.find(from), from.size(), to);
    return text;
  };
  const struct {
    const char* name;
    std::string text;
    std::vector<std::string> says;
  } refused[] = {
      {"comment.ply",
       with("property float z", "comment z next\nproperty float z"),
       {"line 7 of its PLY header ('property float z')", "follows a comment line"}},
      {"bare_property.ply",
       with("property float z", "property"),
       {"line 6 of its PLY header ('property')", "not a property assimp reads"}},
      {"type.ply",
       with("property float z", "property float3 z"),
       {"line 6 of its PLY header ('property float3 z')", "not a property assimp reads"}},
      {"before.ply",
       with("element vertex", "property float w\nelement vertex"),
       {"line 3", "comes before any element"}},
      {"control.ply",
       with("property float y", "property float\fy"),
       {"line 5", "control character 0x0C"}},
      {"unknown.ply", with("element face", "elements face"), {"line 7", "not a PLY header line"}},
      {"float_index.ply", with("3 0 1 3", "3 0 1.0 3"), {"'1.0'", "(int); expected a whole"}},
      {"extra.ply", with("3 0 1 3", "3 0 1 3 0"), {"5 values where the PLY header declares 4"}},
      {"nothing.ply",
       with("element face 4\nproperty list uchar int vertex_indices\n", "element face 4\n"),
       {"PLY element 'face' on line 7 with no property"}}};
  for (const auto& c : refused) {
    SCOPED_TRACE(c.name);
    const std::string error = loadError(write(c.name, c.text));
    EXPECT_TRUE(containsAll(error, {c.name}));
    for (const auto& s : c.says) EXPECT_TRUE(containsAll(error, {s}));
  }

  // Binary data starting with 0x0A: refused after a bare \n, read right after \r\n.
  std::string header = with("ascii", "binary_little_endian");
  header.resize(header.find("end_header") + 10);
  std::string data;
  for (const float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f}) {
    data += plyBinary(v);
  }
  data.replace(0, 4, plyBinary(0x3f80000au));  // x of the first vertex ≈ 1.0000012
  for (const auto& t : tetrahedron().triangles) {
    data += '\x03' + plyBinary(t[0]) + plyBinary(t[1]) + plyBinary(t[2]);
  }
  EXPECT_TRUE(containsAll(loadError(write("lf.ply", header + "\n" + data)),
                          {"lf.ply", "starting with byte 0x0A right after 'end_header'"}));
  std::string crlf_header = header;
  for (std::size_t i = 0; (i = crlf_header.find('\n', i)) != std::string::npos; i += 2) {
    crlf_header.insert(i, "\r");
  }
  const auto crlf = loadMesh(write("crlf.ply", crlf_header + "\r\n" + data), inMetres());
  EXPECT_EQ(crlf.mesh.triangles.size(), 4u);
  EXPECT_NEAR(crlf.mesh.bounds().max().x(), 1.0000012, kFloatTol);

  // What the PLY format allows and assimp reads right still loads: comments and obj_info
  // between elements; floats with signs, exponents, a leading or trailing point.
  for (const auto& [name, text] :
       {std::pair{"between.ply", with("element face", "comment faces\nobj_info x\nelement face")},
        std::pair{"floats.ply", with("1 0 0\n", "+1.0E+0 -0. .0\n")}}) {
    SCOPED_TRACE(name);
    const auto loaded = loadMesh(write(name, text), inMetres());
    EXPECT_EQ(loaded.mesh.triangles.size(), 4u);
    EXPECT_TRUE(loaded.mesh.isClosed());
  }
}

// A big-endian binary PLY with per-vertex colours and normals and a face element with extra
// properties (as exporters write them) loads; the data walk reads each property's width.
TEST_F(MeshLoadTest, BinaryPlyWithColoursNormalsAndFaceExtrasLoads) {
  const Soup soup = cube(2.0);
  std::ostringstream head;
  head << "ply\nformat binary_big_endian 1.0\ncomment exported\nelement vertex "
       << soup.vertices.size()
       << "\nproperty double x\nproperty double y\nproperty double z\nproperty float nx\n"
          "property float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\n"
          "property uchar blue\nproperty ushort quality\nelement face "
       << soup.triangles.size()
       << "\nproperty uchar flags\nproperty list ushort uint vertex_indices\n"
          "property list uchar float texcoord\nproperty short group\nend_header\n";
  std::string data;
  for (const auto& v : soup.vertices) {
    for (int i = 0; i < 3; ++i) data += plyBinary(v[i], true);
    for (int i = 0; i < 3; ++i) data += plyBinary(0.5f, true);
    data += "\x10\x20\x30" + plyBinary<std::uint16_t>(7, true);
  }
  for (const auto& t : soup.triangles) {
    data += '\x01' + plyBinary<std::uint16_t>(3, true);
    for (int i = 0; i < 3; ++i) data += plyBinary(static_cast<std::uint32_t>(t[i]), true);
    data += '\x06';
    for (int i = 0; i < 6; ++i) data += plyBinary(0.25f, true);
    data += plyBinary<std::int16_t>(-2, true);
  }
  const auto loaded = loadMesh(write("cube_be.ply", head.str() + data), inMetres());
  EXPECT_EQ(loaded.mesh.vertices.size(), 8u);
  EXPECT_EQ(loaded.mesh.triangles.size(), 12u);
  EXPECT_TRUE(loaded.mesh.isClosed());
  EXPECT_TRUE(boxNear(loaded.mesh.bounds(), {Eigen::Vector3d::Zero(), Eigen::Vector3d(2, 2, 2)},
                      kFloatTol));
}

// Found by valgrind on the fuzzer's inputs: assimp's OFF reader skips a face line whose vertex
// count is 0 or over 9 by decrementing the face count, so more such lines than faces wrapped it
// to 4 billion and the faces were read past their array; a 10-corner face was dropped without
// a word (a hole), and a line of 4 kB or more wrote a byte past its stack buffer. Refused.
TEST_F(MeshLoadTest, OffLinesAssimpWouldDropOrOverrunAreInputErrors) {
  const std::string vertices = "0 0 0\n1 0 0\n0 1 0\n";
  const auto wrap = write("wrap.off", "OFF\n3 1 0\n" + vertices + "0\n0\n3 0 1 2\n");
  EXPECT_TRUE(containsAll(
      loadError(wrap),
      {"wrap.off", "line 6 ('0')", "does not start with a face's vertex count from 1 to 9"}));
  const auto ten =
      write("ten.off", "OFF\n3 2 0\n" + vertices + "10 0 1 2 0 1 2 0 1 2 0\n3 0 1 2\n");
  EXPECT_TRUE(containsAll(loadError(ten), {"ten.off", "line 6 ('10 0 1 2", "triangulate"}));
  const auto long_line =
      write("long.off", "OFF\n3 1 0\n0 0 0" + std::string(5000, ' ') + "\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_TRUE(containsAll(loadError(long_line),
                          {"long.off", "line 3", "5005 characters long", "expected at most 4000"}));
  const auto bare = write("bare.off", "3 1 0\n" + vertices + "3 0 1 2\n");
  EXPECT_TRUE(containsAll(loadError(bare), {"bare.off", "does not start with the OFF keyword"}));
  const auto no_edges = write("no_edges.off", "OFF\n3 1\n" + vertices + "3 0 1 2\n");
  EXPECT_TRUE(containsAll(loadError(no_edges), {"no_edges.off", "more after the edge count"}));
  const auto cut = write("cut.off", "OFF\n3 2 0\n" + vertices + "3 0 1 2\n");
  EXPECT_TRUE(containsAll(loadError(cut), {"cut.off", "has 1 of the 2 faces", "truncated"}));

  // Comments, blank lines, CRLF, the counts on the keyword's line and a colour variant load.
  for (const auto& [name, text] :
       {std::pair{"comments.off", "# c\n\nOFF # keyword\n# more\n3 1 0 # counts\n\n# c\n" +
                                      vertices + "\n3 0 1 2\n"},
        std::pair{"crlf.off",
                  std::string("OFF\r\n3 1 0\r\n0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 2\r\n")},
        std::pair{"one_line.off", "OFF 3 1 0\n" + vertices + "3 0 1 2\n"},
        std::pair{
            "colour.off",
            std::string("COFF\n3 1 0\n0 0 0 1 0 0 1\n1 0 0 0 1 0 1\n0 1 0 0 0 1 1\n3 0 1 2\n")}}) {
    SCOPED_TRACE(name);
    const auto loaded = loadMesh(write(name, text), inMetres());
    EXPECT_EQ(loaded.mesh.triangles.size(), 1u);
    EXPECT_NEAR(loaded.mesh.area(), 0.5, kFloatTol);
  }
}

}  // namespace scanplan::kinematics
