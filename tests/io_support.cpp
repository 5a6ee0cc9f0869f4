// Test-only readers (see io_support.h).
#include "tests/io_support.h"

#include <array>
#include <bit>
#include <cctype>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>
#include <png.h>

#include <scanplan/kinematics/error.h>

namespace scanplan::test {
namespace {

enum class Scalar { kI8, kU8, kI16, kU16, kI32, kU32, kF32, kF64 };

bool parseScalar(const std::string& name, Scalar& type) {
  static const std::pair<const char*, Scalar> kNames[] = {
      {"char", Scalar::kI8},     {"int8", Scalar::kI8},     {"uchar", Scalar::kU8},
      {"uint8", Scalar::kU8},    {"short", Scalar::kI16},   {"int16", Scalar::kI16},
      {"ushort", Scalar::kU16},  {"uint16", Scalar::kU16},  {"int", Scalar::kI32},
      {"int32", Scalar::kI32},   {"uint", Scalar::kU32},    {"uint32", Scalar::kU32},
      {"float", Scalar::kF32},   {"float32", Scalar::kF32}, {"double", Scalar::kF64},
      {"float64", Scalar::kF64},
  };
  for (const auto& [n, t] : kNames) {
    if (name == n) {
      type = t;
      return true;
    }
  }
  return false;
}

std::size_t scalarSize(Scalar type) {
  switch (type) {
    case Scalar::kI8:
    case Scalar::kU8:
      return 1;
    case Scalar::kI16:
    case Scalar::kU16:
      return 2;
    case Scalar::kI32:
    case Scalar::kU32:
    case Scalar::kF32:
      return 4;
    case Scalar::kF64:
      return 8;
  }
  return 0;
}

struct Property {
  std::string name;
  Scalar type = Scalar::kF32;
  bool is_list = false;
  Scalar count_type = Scalar::kU8;
};

struct Element {
  std::string name;
  std::size_t count = 0;
  std::vector<Property> properties;
};

class PlyDataReader {
 public:
  PlyDataReader(std::istream& in, std::string format, const std::string& source)
      : in_(in), format_(std::move(format)), source_(source) {}

  double read(Scalar type) {
    if (format_ == "ascii") {
      double v = 0.0;
      if (!(in_ >> v)) fail();
      return v;
    }
    const std::size_t size = scalarSize(type);
    std::array<unsigned char, 8> b{};
    if (!in_.read(reinterpret_cast<char*>(b.data()), static_cast<std::streamsize>(size))) fail();
    std::uint64_t bits = 0;
    for (std::size_t i = 0; i < size; ++i) {
      const std::size_t shift = format_ == "binary_little_endian" ? i : size - 1 - i;
      bits |= static_cast<std::uint64_t>(b[i]) << (8 * shift);
    }
    switch (type) {
      case Scalar::kI8:
        return static_cast<std::int8_t>(bits);
      case Scalar::kU8:
        return static_cast<std::uint8_t>(bits);
      case Scalar::kI16:
        return static_cast<std::int16_t>(bits);
      case Scalar::kU16:
        return static_cast<std::uint16_t>(bits);
      case Scalar::kI32:
        return static_cast<std::int32_t>(bits);
      case Scalar::kU32:
        return static_cast<std::uint32_t>(bits);
      case Scalar::kF32:
        return std::bit_cast<float>(static_cast<std::uint32_t>(bits));
      case Scalar::kF64:
        return std::bit_cast<double>(bits);
    }
    return 0.0;
  }

  [[noreturn]] void fail() const {
    throw InputError("PLY file '" + source_ + "' is truncated or malformed in its data");
  }

 private:
  std::istream& in_;
  std::string format_;
  const std::string& source_;
};

}  // namespace

const std::vector<double>& PlyVertices::column(const std::string& name) const {
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) throw std::out_of_range("PLY vertex property '" + name + "' absent");
  return columns[static_cast<std::size_t>(it - names.begin())];
}

PlyVertices readPlyVertices(std::istream& in, const std::string& source) {
  const auto bad = [&](const std::string& what) {
    return InputError("PLY file '" + source + "': " + what);
  };
  std::string line;
  const auto next = [&]() -> bool {
    if (!std::getline(in, line)) return false;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  };
  if (!next() || line != "ply") throw bad("does not start with 'ply'");
  PlyVertices result;
  std::vector<Element> elements;
  bool ended = false;
  while (next()) {
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword == "end_header") {
      ended = true;
      break;
    }
    if (keyword == "comment" || keyword == "obj_info" || keyword.empty()) continue;
    if (keyword == "format") {
      std::string version;
      words >> result.format >> version;
      if (result.format != "ascii" && result.format != "binary_little_endian" &&
          result.format != "binary_big_endian") {
        throw bad("unknown format '" + result.format + "'");
      }
    } else if (keyword == "element") {
      Element e;
      long long count = -1;
      if (!(words >> e.name >> count) || count < 0) throw bad("bad element line '" + line + "'");
      e.count = static_cast<std::size_t>(count);
      elements.push_back(std::move(e));
    } else if (keyword == "property") {
      if (elements.empty()) throw bad("property before any element: '" + line + "'");
      Property p;
      std::string type;
      words >> type;
      if (type == "list") {
        std::string count_type, item_type;
        words >> count_type >> item_type >> p.name;
        p.is_list = true;
        if (!parseScalar(count_type, p.count_type) || !parseScalar(item_type, p.type)) {
          throw bad("bad list property '" + line + "'");
        }
      } else {
        words >> p.name;
        if (!parseScalar(type, p.type)) throw bad("unknown property type in '" + line + "'");
      }
      if (p.name.empty()) throw bad("property without a name: '" + line + "'");
      elements.back().properties.push_back(p);
    } else {
      throw bad("unknown header line '" + line + "'");
    }
  }
  if (!ended) throw bad("no end_header");
  if (result.format.empty()) throw bad("no format line");
  PlyDataReader reader(in, result.format, source);
  for (const Element& e : elements) {
    const bool is_vertex = e.name == "vertex";
    if (is_vertex) {
      result.count = e.count;
      for (const Property& p : e.properties) {
        if (p.is_list) continue;
        result.names.push_back(p.name);
        result.columns.emplace_back();
        result.columns.back().reserve(e.count);
      }
    }
    for (std::size_t i = 0; i < e.count; ++i) {
      std::size_t column = 0;
      for (const Property& p : e.properties) {
        if (p.is_list) {
          const double items = reader.read(p.count_type);
          if (items < 0.0) reader.fail();
          for (std::size_t k = 0; k < static_cast<std::size_t>(items); ++k) reader.read(p.type);
          continue;
        }
        const double v = reader.read(p.type);
        if (is_vertex) result.columns[column++].push_back(v);
      }
    }
    if (is_vertex) return result;
  }
  throw bad("has no vertex element");
}

cli::RgbImage decodePng(const std::string& bytes) {
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  const auto fail = [&png] {
    png_image_free(&png);
    return InputError(fmt::format("PNG data: {}", png.message));
  };
  if (png_image_begin_read_from_memory(&png, bytes.data(), bytes.size()) == 0) throw fail();
  png.format = PNG_FORMAT_RGB;
  cli::RgbImage image;
  image.width = static_cast<int>(png.width);
  image.height = static_cast<int>(png.height);
  image.rgb.resize(3 * static_cast<std::size_t>(image.width) *
                   static_cast<std::size_t>(image.height));
  if (png_image_finish_read(&png, nullptr, image.rgb.data(), 0, nullptr) == 0) throw fail();
  return image;
}

NpyArray readNpy(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  const auto fail = [&](const std::string& what) {
    return InputError(fmt::format("{}: {}: expected a C-order .npy file", file.string(), what));
  };
  if (!in) throw fail("cannot read the file");
  if (bytes.size() < 10 || bytes.compare(0, 6, "\x93NUMPY") != 0) throw fail("no .npy magic");
  const auto byteAt = [&](std::size_t i) {
    return static_cast<std::size_t>(static_cast<unsigned char>(bytes[i]));
  };
  if (byteAt(6) != 1) throw fail(fmt::format("format version {}", byteAt(6)));
  const std::size_t start = 10, length = byteAt(8) | byteAt(9) << 8;
  if (bytes.size() < start + length) throw fail("truncated header");
  const std::string header = bytes.substr(start, length);
  const auto valueAfter = [&](const std::string& key) {
    const std::size_t at = header.find("'" + key + "':");
    if (at == std::string::npos) throw fail("no '" + key + "' in the header");
    return header.find_first_not_of(' ', at + key.size() + 3);
  };
  NpyArray array;
  const std::size_t descr_at = valueAfter("descr") + 1;
  array.descr = header.substr(descr_at, header.find('\'', descr_at) - descr_at);
  if (header.compare(valueAfter("fortran_order"), 5, "False") != 0) throw fail("Fortran order");
  const std::size_t shape_at = valueAfter("shape");
  const std::size_t shape_end = header.find(')', shape_at);
  if (header[shape_at] != '(' || shape_end == std::string::npos) throw fail("bad shape");
  std::size_t count = 1;
  for (std::size_t i = shape_at + 1; i < shape_end; ++i) {
    if (std::isdigit(static_cast<unsigned char>(header[i])) == 0) continue;
    std::size_t n = 0;
    for (; std::isdigit(static_cast<unsigned char>(header[i])) != 0; ++i) {
      n = 10 * n + static_cast<std::size_t>(header[i] - '0');
    }
    array.shape.push_back(n);
    count *= n;
  }
  if (array.descr.size() < 3) throw fail("descr '" + array.descr + "'");
  const std::size_t item_size = std::stoul(array.descr.substr(2));
  array.raw = bytes.substr(start + length);
  if (array.raw.size() != count * item_size) {
    throw fail(
        fmt::format("{} data bytes for {} items of {} bytes", array.raw.size(), count, item_size));
  }
  return array;
}

}  // namespace scanplan::test
