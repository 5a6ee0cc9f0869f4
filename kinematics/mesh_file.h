#pragma once
// What a mesh file must pass before assimp reads it (kinematics/mesh.cpp's loader): assimp
// loops, allocates without end or silently repairs on some malformed files, so the file's kind,
// size and structure are checked first, and its triangles estimated.

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
/// OFF lines are read into a 4 096-byte buffer by assimp, which misreads longer ones.
inline constexpr std::size_t kMaxOffLine = 4000;

/// Throws the loader's InputError, "mesh file '<path>' <what>".
[[noreturn]] void failMesh(const std::filesystem::path& path, const std::string& what);

/// Refuses (InputError naming the file) a mesh file assimp would misread, loop on or take
/// without bound: missing, not a regular file, empty or over kMaxMeshBytes, an unsupported
/// extension; a PLY or OFF whose header does not fit its size or whose body does not match its
/// header (truncated, too few numbers in an ASCII element, an OFF face index out of range or
/// not a number); and a mesh whose triangles, counted or estimated before reading (binary STL
/// and PLY: the header's count; the text formats: their faces), exceed kMaxMeshTriangles.
/// Reads the file at most once, in blocks.
void checkMeshFile(const std::filesystem::path& path);

}  // namespace scanplan::kinematics::detail
