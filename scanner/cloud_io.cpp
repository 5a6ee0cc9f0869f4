#include "scanner/cloud_io.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "kinematics/error.h"
#include "kinematics/units.h"

namespace scanplan::scanner {
namespace {

// Little-endian bytes whatever the host's order.
class LittleEndianWriter {
 public:
  explicit LittleEndianWriter(std::ostream& out) : out_(out) {}
  void u8(std::uint8_t v) { out_.put(static_cast<char>(v)); }
  void u32(std::uint32_t v) {
    std::array<char, 4> b{};
    for (std::size_t i = 0; i < 4; ++i) b[i] = static_cast<char>((v >> (8 * i)) & 0xFFu);
    out_.write(b.data(), 4);
  }
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void f32(double v) { u32(std::bit_cast<std::uint32_t>(static_cast<float>(v))); }

 private:
  std::ostream& out_;
};

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

void writeCloudPly(std::ostream& out, const std::vector<CloudPoint>& points) {
  out << "ply\n"
      << "format binary_little_endian 1.0\n"
      << "comment scanplan simulated cloud: part frame, mm; time s; range mm; incidence deg\n"
      << "element vertex " << points.size() << "\n"
      << "property float x\n"
      << "property float y\n"
      << "property float z\n"
      << "property float time\n"
      << "property uint profile\n"
      << "property float range_mm\n"
      << "property float incidence_deg\n"
      << "end_header\n";
  LittleEndianWriter w(out);
  for (const CloudPoint& p : points) {
    w.f32(toMm(p.p_P.x()));
    w.f32(toMm(p.p_P.y()));
    w.f32(toMm(p.p_P.z()));
    w.f32(p.t);
    w.u32(p.profile);
    w.f32(toMm(p.range));
    w.f32(toDeg(p.incidence));
  }
}

void writeCoveragePly(std::ostream& out,
                      const kinematics::TriangleMesh& part,
                      const PartCoverage& coverage,
                      const CoverageSettings& settings,
                      double max_per_mm2) {
  const std::size_t n = part.triangles.size();
  const double top = max_per_mm2 > 0.0 ? max_per_mm2 : coverage.density_p95_per_mm2;
  out << "ply\n"
      << "format binary_little_endian 1.0\n"
      << "comment scanplan coverage: part frame, mm; colour = points/mm2, viridis 0 .. " << top
      << ", grey = not covered\n"
      << "element vertex " << 3 * n << "\n"
      << "property float x\n"
      << "property float y\n"
      << "property float z\n"
      << "property uchar red\n"
      << "property uchar green\n"
      << "property uchar blue\n"
      << "property float density_per_mm2\n"
      << "property uint points\n"
      << "element face " << n << "\n"
      << "property list uchar int vertex_indices\n"
      << "end_header\n";
  LittleEndianWriter w(out);
  const std::uint32_t min_points = std::max<std::uint32_t>(settings.min_points, 1);
  std::vector<std::array<std::uint8_t, 3>> colours(n);
  std::vector<double> densities(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t hits = i < coverage.hits.size() ? coverage.hits[i] : 0;
    densities[i] = i < coverage.hits.size() ? triangleDensityPerMm2(part, coverage, i) : 0.0;
    colours[i] = densityColour(densities[i], top, hits >= min_points);
  }
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& v = part.vertices[static_cast<std::size_t>(part.triangles[i](k))];
      w.f32(toMm(v.x()));
      w.f32(toMm(v.y()));
      w.f32(toMm(v.z()));
      for (const std::uint8_t c : colours[i]) w.u8(c);
      w.f32(densities[i]);
      w.u32(i < coverage.hits.size() ? coverage.hits[i] : 0);
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    w.u8(3);
    for (std::size_t k = 0; k < 3; ++k) w.i32(static_cast<std::int32_t>(3 * i + k));
  }
}

const std::vector<double>& PlyVertices::column(const std::string& name) const {
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) throw std::out_of_range("PLY vertex property '" + name + "' absent");
  return columns[static_cast<std::size_t>(it - names.begin())];
}

namespace {

InputError plyError(const std::string& source, const std::string& what) {
  return InputError("PLY file '" + source + "': " + what);
}

// One `property` line of the header into the last element.
void addProperty(std::istringstream& words,
                 const std::string& line,
                 const std::string& source,
                 std::vector<Element>& elements) {
  if (elements.empty()) throw plyError(source, "property before any element: '" + line + "'");
  Property p;
  std::string type;
  words >> type;
  if (type == "list") {
    std::string count_type, item_type;
    words >> count_type >> item_type >> p.name;
    p.is_list = true;
    if (!parseScalar(count_type, p.count_type) || !parseScalar(item_type, p.type)) {
      throw plyError(source, "bad list property '" + line + "'");
    }
  } else {
    words >> p.name;
    if (!parseScalar(type, p.type)) {
      throw plyError(source, "unknown property type in '" + line + "'");
    }
  }
  if (p.name.empty()) throw plyError(source, "property without a name: '" + line + "'");
  elements.back().properties.push_back(p);
}

// The header up to end_header: the format (into `format`) and the elements.
std::vector<Element> readPlyHeader(std::istream& in,
                                   const std::string& source,
                                   std::string& format) {
  std::string line;
  const auto next = [&]() -> bool {
    if (!std::getline(in, line)) return false;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  };
  if (!next() || line != "ply") throw plyError(source, "does not start with 'ply'");
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
      words >> format >> version;
      if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian") {
        throw plyError(source, "unknown format '" + format + "'");
      }
    } else if (keyword == "element") {
      Element e;
      long long count = -1;
      if (!(words >> e.name >> count) || count < 0) {
        throw plyError(source, "bad element line '" + line + "'");
      }
      e.count = static_cast<std::size_t>(count);
      elements.push_back(std::move(e));
    } else if (keyword == "property") {
      addProperty(words, line, source, elements);
    } else {
      throw plyError(source, "unknown header line '" + line + "'");
    }
  }
  if (!ended) throw plyError(source, "no end_header");
  if (format.empty()) throw plyError(source, "no format line");
  return elements;
}

}  // namespace

PlyVertices readPlyVertices(std::istream& in, const std::string& source) {
  PlyVertices result;
  const std::vector<Element> elements = readPlyHeader(in, source, result.format);
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
  throw plyError(source, "has no vertex element");
}

}  // namespace scanplan::scanner
