#include <scanplan/kinematics/mesh.h>

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/mesh_file.h>
#include <scanplan/kinematics/units.h>

#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <numbers>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace scanplan::kinematics {
namespace {

// Relative to the bounding-box diagonal squared so a file is judged alike in mm and in m. A
// triangle of area 1e-12·diag² (sides ~1e-6·diag) is at the resolution of the float32
// coordinates assimp stores (~1e-7 relative), so it carries no surface worth keeping.
constexpr double kDegenerateAreaRatio = 1e-12;

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& what) {
  detail::failMesh(path, what);
}

Eigen::Vector3d toEigen(const aiVector3D& v) { return {v.x, v.y, v.z}; }

// Stored normals are inspected before they are dropped for welding: a facet whose stored
// normal points against its winding is reported, and the winding wins (it is what every
// later inside/outside decision uses). Zero normals, which STL allows, are not counted.
void inspectFaces(const aiScene& scene, MeshLoadReport& report) {
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[m];
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) {
        ++report.non_triangle_dropped;
        continue;
      }
      if (mesh.mNormals == nullptr) continue;
      const unsigned* idx = face.mIndices;
      const Eigen::Vector3d a = toEigen(mesh.mVertices[idx[0]]);
      const Eigen::Vector3d winding =
          (toEigen(mesh.mVertices[idx[1]]) - a).cross(toEigen(mesh.mVertices[idx[2]]) - a);
      const Eigen::Vector3d stored = toEigen(mesh.mNormals[idx[0]]) +
                                     toEigen(mesh.mNormals[idx[1]]) +
                                     toEigen(mesh.mNormals[idx[2]]);
      if (winding.dot(stored) < 0.0) ++report.normals_disagreeing;
    }
  }
}

// assimp cuts a polygon of more than four corners into triangles by ear clipping, which can cut
// across a concave one (an L-shaped hexagon wound counter-clockwise came out with a third more
// area, over its notch); quads, concave or not, and convex polygons come out right. A larger
// polygon must be convex in the plane of its Newell normal, turning once around (not a star).
void checkConvexPolygon(const std::filesystem::path& path, const aiMesh& mesh, unsigned f) {
  constexpr double kTurnTol = 1e-3;  // rad: float corners on a straight edge turn by less
  const aiFace& face = mesh.mFaces[f];
  const unsigned n = face.mNumIndices;
  const auto corner = [&](unsigned k) { return toEigen(mesh.mVertices[face.mIndices[k % n]]); };
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // Newell's: 0 for a line or a figure 8
  for (unsigned k = 0; k < n; ++k) normal += corner(k).cross(corner(k + 1));
  bool convex = normal.norm() > 0.0;
  normal = normal.normalized();
  double turned = 0.0;
  for (unsigned k = 0; k < n && convex; ++k) {
    const Eigen::Vector3d in = corner(k + 1) - corner(k), out = corner(k + 2) - corner(k + 1);
    const double sine = in.cross(out).dot(normal), cosine = in.dot(out);
    convex = sine >= -kTurnTol * in.norm() * out.norm();
    turned += std::atan2(sine, cosine);
  }
  // A closed polygon turns by a multiple of 2π: once around is convex, twice a star.
  if (convex && std::abs(turned - 2.0 * std::numbers::pi) < std::numbers::pi) return;
  std::ostringstream what;
  what << "face " << f + 1 << " is a polygon of " << n << " corners that is not convex (";
  for (unsigned k = 0; k < 3; ++k) {
    const Eigen::Vector3d c = corner(k);
    what << (k ? ", " : "") << c.x() << " " << c.y() << " " << c.z();
  }
  what << ", …): assimp's triangulation can cut across it; expected triangles, quads or convex "
          "polygons (triangulate the mesh in the tool that wrote it)";
  fail(path, what.str());
}

// assimp's triangulation aborts the process (an always-on assertion) when a mesh claims polygons
// it does not have: a face with no vertex index (a PLY face list of length 0 passes assimp's
// own validation) counts as a polygon. Such files are refused before triangulating, and so are
// a polygon checkConvexPolygon refuses and a mesh whose polygons make more triangles than the
// limit (the pre-check counts an OBJ face continued over lines short): triangulating and
// welding take the time and memory.
void checkTriangulable(const std::filesystem::path& path, const aiScene& scene) {
  std::size_t triangles = 0;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[m];
    bool polygon = false;
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const unsigned corners = mesh.mFaces[f].mNumIndices;
      if (corners == 0) {
        fail(path,
             "face " + std::to_string(f + 1) +
                 " has no vertex index; expected 3 or more per face (1 or 2: a point or line)");
      }
      if (corners > 4) checkConvexPolygon(path, mesh, f);
      polygon = polygon || corners > 3;
      triangles += corners >= 3 ? corners - 2 : 0;
    }
    if ((mesh.mPrimitiveTypes & aiPrimitiveType_POLYGON) != 0 && !polygon) {
      fail(path, "declares polygons but has none; expected a consistent face list");
    }
  }
  if (triangles > detail::kMaxMeshTriangles) {
    fail(path, "has " + std::to_string(triangles) + " triangles; expected at most " +
                   std::to_string(detail::kMaxMeshTriangles) + " (simplify the mesh)");
  }
}

// Importers may hang meshes below nodes with transforms (OBJ puts each group in a node), so
// the tree is walked with accumulated transforms; a mesh used by two nodes is copied twice.
void collect(const aiScene& scene,
             const aiNode& node,
             const aiMatrix4x4& X_parent,
             TriangleMesh& out) {
  const aiMatrix4x4 X = X_parent * node.mTransformation;
  // A mirroring transform reverses the winding; swap two corners to keep outward CCW.
  const bool mirrored = X.Determinant() < 0.0f;
  for (unsigned k = 0; k < node.mNumMeshes; ++k) {
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[k]];
    const int base = static_cast<int>(out.vertices.size());
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      out.vertices.push_back(toEigen(X * mesh.mVertices[v]));
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;
      Eigen::Vector3i t(base + static_cast<int>(face.mIndices[0]),
                        base + static_cast<int>(face.mIndices[1]),
                        base + static_cast<int>(face.mIndices[2]));
      if (mirrored) std::swap(t[1], t[2]);
      out.triangles.push_back(t);
    }
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c) collect(scene, *node.mChildren[c], X, out);
}

// Drops repeated-index and zero-area triangles, then renumbers the vertices still in use,
// keeping their file order so the result is deterministic.
std::size_t dropDegenerates(TriangleMesh& mesh) {
  Eigen::AlignedBox3d box;
  for (const auto& t : mesh.triangles) {
    for (int i = 0; i < 3; ++i) box.extend(mesh.vertices[static_cast<std::size_t>(t[i])]);
  }
  const double min_area = kDegenerateAreaRatio * box.diagonal().squaredNorm();
  const auto before = mesh.triangles.size();
  std::erase_if(mesh.triangles, [&](const Eigen::Vector3i& t) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
    const auto& a = mesh.vertices[static_cast<std::size_t>(t[0])];
    const auto& b = mesh.vertices[static_cast<std::size_t>(t[1])];
    const auto& c = mesh.vertices[static_cast<std::size_t>(t[2])];
    return 0.5 * (b - a).cross(c - a).norm() <= min_area;
  });

  std::vector<int> remap(mesh.vertices.size(), -1);
  for (const auto& t : mesh.triangles) {
    for (int i = 0; i < 3; ++i) remap[static_cast<std::size_t>(t[i])] = 0;
  }
  std::vector<Eigen::Vector3d> kept;
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (remap[v] < 0) continue;
    remap[v] = static_cast<int>(kept.size());
    kept.push_back(mesh.vertices[v]);
  }
  for (auto& t : mesh.triangles) {
    for (int i = 0; i < 3; ++i) t[i] = remap[static_cast<std::size_t>(t[i])];
  }
  mesh.vertices = std::move(kept);
  return before - mesh.triangles.size();
}

void warn(MeshLoadReport& report,
          const std::filesystem::path& path,
          const char* verb,
          std::size_t count,
          const char* what) {
  if (count == 0) return;
  std::ostringstream line;
  line << path.filename().string() << ": " << verb << " " << count << " " << what;
  report.warnings.push_back(line.str());
}

}  // namespace

Eigen::AlignedBox3d TriangleMesh::bounds() const {
  Eigen::AlignedBox3d box;
  for (const auto& v : vertices) box.extend(v);
  return box;
}

bool TriangleMesh::isClosed() const {
  // An empty mesh encloses nothing, so callers relying on inside/outside must not accept it.
  if (triangles.empty()) return false;
  // Directed edges as 64-bit keys: closed iff no directed edge repeats and each one's
  // reverse is present, i.e. every undirected edge is used exactly twice, oppositely.
  std::vector<std::uint64_t> edges;
  edges.reserve(3 * triangles.size());
  const auto key = [](int a, int b) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
           static_cast<std::uint32_t>(b);
  };
  for (const auto& t : triangles) {
    for (int i = 0; i < 3; ++i) {
      const int a = t[i];
      const int b = t[(i + 1) % 3];
      if (a == b) return false;
      edges.push_back(key(a, b));
    }
  }
  std::sort(edges.begin(), edges.end());
  if (std::adjacent_find(edges.begin(), edges.end()) != edges.end()) return false;
  return std::all_of(edges.begin(), edges.end(), [&](std::uint64_t e) {
    const auto a = static_cast<int>(e >> 32);
    const auto b = static_cast<int>(e & 0xffffffffu);
    return std::binary_search(edges.begin(), edges.end(), key(b, a));
  });
}

double TriangleMesh::area() const {
  double sum = 0.0;
  for (const auto& t : triangles) {
    const auto& a = vertices[static_cast<std::size_t>(t[0])];
    const auto& b = vertices[static_cast<std::size_t>(t[1])];
    const auto& c = vertices[static_cast<std::size_t>(t[2])];
    sum += 0.5 * (b - a).cross(c - a).norm();
  }
  return sum;
}

double TriangleMesh::signedVolume() const {
  double sum = 0.0;  // divergence theorem: tetrahedra from the origin to each triangle
  for (const auto& t : triangles) {
    sum += vertices[static_cast<std::size_t>(t[0])].dot(
        vertices[static_cast<std::size_t>(t[1])].cross(vertices[static_cast<std::size_t>(t[2])]));
  }
  return sum / 6.0;
}

LoadedMesh loadMesh(const std::filesystem::path& path, const MeshLoadOptions& options) {
  if (!std::isfinite(options.scale) || options.scale <= 0.0) {
    std::ostringstream what;
    what << "cannot be loaded with scale " << options.scale << "; expected a finite number > 0";
    fail(path, what.str());
  }
  detail::checkMeshFile(path);

  LoadedMesh result;
  Assimp::Importer importer;
  // Texture coordinates and colours would keep seam vertices apart when welding.
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, aiComponent_TEXCOORDS | aiComponent_COLORS |
                                                          aiComponent_TANGENTS_AND_BITANGENTS);
  const aiScene* scene = nullptr;
  try {
    scene = importer.ReadFile(path.string(),
                              aiProcess_RemoveComponent | aiProcess_ValidateDataStructure);
    if (scene != nullptr) {
      checkTriangulable(path, *scene);
      scene = importer.ApplyPostProcessing(aiProcess_Triangulate);
    }
    if (scene != nullptr) {
      inspectFaces(*scene, result.report);
      // Normals must go first: assimp keeps STL corners apart because each carries its
      // facet's normal, and welding only merges vertices identical in every attribute.
      scene = importer.ApplyPostProcessing(aiProcess_DropNormals | aiProcess_JoinIdenticalVertices);
    }
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    fail(path, std::string("could not be read: ") + e.what());
  }
  if (scene == nullptr || scene->mRootNode == nullptr) {
    fail(path, std::string("could not be read: ") + importer.GetErrorString() +
                   "; expected a well-formed .stl .obj .ply .off mesh");
  }

  // Checked in file units, before any transform smears a NaN over all three coordinates.
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh& raw = *scene->mMeshes[m];
    for (unsigned v = 0; v < raw.mNumVertices; ++v) {
      const aiVector3D& p = raw.mVertices[v];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
        std::ostringstream what;
        what << "has a vertex with a non-finite coordinate (" << p.x << " " << p.y << " " << p.z
             << "); expected finite numbers";
        fail(path, what.str());
      }
    }
  }

  TriangleMesh& mesh = result.mesh;
  collect(*scene, *scene->mRootNode, aiMatrix4x4(), mesh);
  if (mesh.triangles.empty()) {
    fail(path, "holds no triangles (" + std::to_string(result.report.non_triangle_dropped) +
                   " point/line primitives); expected a triangle surface mesh");
  }
  const double factor = (options.units == LengthUnit::kMillimetre ? kMmToM : 1.0) * options.scale;
  const bool rotate = !options.rotation.isIdentity(0.0);
  for (auto& v : mesh.vertices) {
    v *= factor;
    if (rotate) v = options.rotation * v;
    if (!v.allFinite()) {
      std::ostringstream what;
      what << "overflows when scaled by " << factor << " to metres; expected a smaller scale";
      fail(path, what.str());
    }
  }

  MeshLoadReport& report = result.report;
  report.degenerate_dropped = dropDegenerates(mesh);
  if (mesh.triangles.empty()) {
    fail(path, "holds only degenerate (zero-area) triangles; expected a triangle surface mesh");
  }
  warn(report, path, "dropped", report.degenerate_dropped, "degenerate triangles");
  warn(report, path, "ignored", report.non_triangle_dropped, "point/line primitives");
  warn(report, path, "found", report.normals_disagreeing,
       "facet normals opposite to the winding; used the winding");
  return result;
}

}  // namespace scanplan::kinematics
