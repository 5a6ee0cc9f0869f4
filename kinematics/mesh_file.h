#pragma once
// What a mesh file must pass before assimp reads it (kinematics/mesh.cpp's loader): assimp
// loops, allocates without end, corrupts its heap or silently repairs on some malformed files, so
// the file's kind, size and structure are checked first, and its triangles counted. The parts:
// mesh_file.cpp (kind, size, STL, OBJ), mesh_file_ply.cpp, mesh_file_off.cpp.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

namespace scanplan::kinematics::detail {

/// Mesh files larger than this are refused unread.
inline constexpr std::uintmax_t kMaxMeshBytes = std::uintmax_t{1} << 30;  // 1 GB
/// The most triangles a mesh may have. This bounds the loader's time and memory: a 4 M-triangle
/// binary STL loads in about 5 s and 2.3 GB (assimp's welding dominates, ~600 B a triangle).
inline constexpr std::size_t kMaxMeshTriangles = 4'000'000;
/// OFF lines are read into a 4 096-byte buffer by assimp, which overruns it on longer ones and
/// reads their rest as another line.
inline constexpr std::size_t kMaxOffLine = 4000;

/// Throws the loader's InputError, "mesh file '<path>' <what>".
[[noreturn]] void failMesh(const std::filesystem::path& path, const std::string& what);

/// Refuses (InputError naming the file, the line or element, and what was expected) a mesh file
/// assimp would misread, crash on, loop on or take without bound: missing, not a regular file,
/// empty or over kMaxMeshBytes, an unsupported extension; a PLY whose header is not the format's
/// (one vertex and one face element, known types, 'end_header' alone on its line, within 64 kB)
/// or whose data (ASCII or binary) does not hold exactly what the header declares, with list
/// lengths up to 32 767; an OFF without its keyword, with a line over kMaxOffLine, a vertex or
/// face line missing, or a face that is not 1 to 9 indices of its vertices; any line of a PLY
/// header or ASCII body, or of an OFF, with a control character; and a mesh whose triangles,
/// counted before reading (binary STL: its count; ASCII STL: its `vertex` keywords; OBJ: its
/// `f` lines; PLY and OFF: their faces' corners), exceed kMaxMeshTriangles. Reads the file once
/// or twice, in blocks, keeping nothing of it.
void checkMeshFile(const std::filesystem::path& path);

}  // namespace scanplan::kinematics::detail
