#pragma once
// Readers that only the tests need: the PLY vertices `simulate` writes, the .npy layers of
// `map`, and PNG figures. The product writes these formats; it never reads them.

#include <cstddef>
#include <filesystem>
#include <istream>
#include <string>
#include <vector>

#include "cli/plot/image_io.h"

namespace scanplan::test {

/// The scalar properties of a PLY file's `vertex` element, as columns of doubles.
struct PlyVertices {
  std::string format;              ///< "ascii", "binary_little_endian" or "binary_big_endian"
  std::vector<std::string> names;  ///< property names, in file order
  std::vector<std::vector<double>> columns;
  std::size_t count = 0;

  /// The column of a property; throws std::out_of_range when there is none.
  const std::vector<double>& column(const std::string& name) const;
};

/// Reads the `vertex` element of a PLY file (any of the three formats; scalar properties of
/// the standard types; list properties and other elements are skipped). Throws InputError
/// naming `source` for anything malformed or truncated.
PlyVertices readPlyVertices(std::istream& in, const std::string& source);

/// Decodes any PNG libpng reads, converted to 8-bit RGB; throws InputError on bad data.
cli::RgbImage decodePng(const std::string& bytes);

/// A .npy file as stored: dtype descriptor (e.g. "<f4"), shape and the raw data bytes.
struct NpyArray {
  std::string descr;
  std::vector<std::size_t> shape;
  std::string raw;
};
/// Reads a C-order .npy file, format 1.0; throws InputError naming the file.
NpyArray readNpy(const std::filesystem::path& file);

}  // namespace scanplan::test
