#include <scanplan/scanner/cloud_io.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>
#include <vector>

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/units.h>

namespace scanplan::scanner {
namespace {

// Little-endian records formatted into a buffer and handed to the stream 256 KiB at a time: one
// stream call per chunk rather than one per value (which cost 10× the formatting itself), large
// enough that writeFileAtomically passes it to the file without copying it into its buffer.
class LittleEndianWriter {
 public:
  explicit LittleEndianWriter(std::ostream& out) : out_(out), buffer_(kChunk + kRecordMax) {}
  LittleEndianWriter(const LittleEndianWriter&) = delete;
  LittleEndianWriter& operator=(const LittleEndianWriter&) = delete;
  ~LittleEndianWriter() { flush(); }

  void u8(std::uint8_t v) { buffer_[size_++] = static_cast<char>(v); }
  void u32(std::uint32_t v) {
    // Shifts, not the host's layout: the compiler makes one store of them on a little-endian
    // machine.
    const std::array<char, 4> b{static_cast<char>(v & 0xFFu), static_cast<char>((v >> 8) & 0xFFu),
                                static_cast<char>((v >> 16) & 0xFFu),
                                static_cast<char>((v >> 24) & 0xFFu)};
    std::memcpy(buffer_.data() + size_, b.data(), b.size());
    size_ += b.size();
  }
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void f32(double v) { u32(std::bit_cast<std::uint32_t>(static_cast<float>(v))); }
  /// Call after each record (at most kRecordMax bytes): passes the buffer on once it holds a
  /// chunk.
  void endRecord() {
    if (size_ >= kChunk) flush();
  }
  void flush() {
    out_.write(buffer_.data(), static_cast<std::streamsize>(size_));
    size_ = 0;
  }

 private:
  static constexpr std::size_t kChunk = 256 * 1024, kRecordMax = 256;
  std::ostream& out_;
  std::vector<char> buffer_;
  std::size_t size_ = 0;
};

// Writes a PLY header given with '\n' line ends with "\r\n" ones. assimp 5.2 (what loadMesh
// reads with) takes a 0x0A right after the bare '\n' ending 'end_header' for part of the line
// end and reads every value one byte off; about 1 file in 256 starts its data with that byte.
// After "\r\n" it reads the data where it starts, whatever its first byte, and so do rply
// (Open3D, CloudCompare: it takes the line end of the 'ply' line for all) and line readers.
void writeHeader(std::ostream& out, const std::string& header) {
  std::string text;
  for (const char c : header) {
    if (c == '\n') text += '\r';
    text += c;
  }
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
}

}  // namespace

void writeCloudPly(std::ostream& out, const std::vector<CloudPoint>& points) {
  std::ostringstream header;
  header << "ply\n"
         << "format binary_little_endian 1.0\n"
         << "comment scanplan simulated cloud: part frame, mm; normals unit, towards the laser; "
            "time s; range mm; incidence deg; part_triangle -1 = on another body; quality = "
            "incidence deg (for MeshLab)\n"
         << "element vertex " << points.size() << "\n"
         << "property float x\n"
         << "property float y\n"
         << "property float z\n"
         << "property float nx\n"
         << "property float ny\n"
         << "property float nz\n"
         << "property float scalar_time\n"
         << "property int scalar_profile\n"
         << "property int scalar_ray\n"
         << "property float scalar_range_mm\n"
         << "property float scalar_incidence_deg\n"
         << "property int scalar_part_triangle\n"
         << "property float quality\n"
         << "end_header\n";
  writeHeader(out, header.str());
  LittleEndianWriter w(out);
  const auto index = [](std::uint32_t v) {  // int: what every viewer keeps (Open3D drops uint)
    return static_cast<std::int32_t>(std::min<std::uint32_t>(v, 0x7FFFFFFFu));
  };
  for (const CloudPoint& p : points) {
    w.f32(toMm(p.p_P.x()));
    w.f32(toMm(p.p_P.y()));
    w.f32(toMm(p.p_P.z()));
    w.f32(p.n_P.x());
    w.f32(p.n_P.y());
    w.f32(p.n_P.z());
    w.f32(p.t);
    w.i32(index(p.profile));
    w.i32(index(p.ray));
    w.f32(toMm(p.range));
    w.f32(toDeg(p.incidence));
    w.i32(p.part_triangle);
    w.f32(toDeg(p.incidence));  // quality
    w.endRecord();
  }
}

void writeCoveragePly(std::ostream& out,
                      const kinematics::TriangleMesh& part,
                      const PartCoverage& coverage,
                      const CoverageSettings& settings,
                      double max_per_mm2) {
  const std::size_t n = part.triangles.size();
  const double top = max_per_mm2 > 0.0 ? max_per_mm2 : coverage.density_p95_per_mm2;
  std::ostringstream header;
  header << "ply\n"
         << "format binary_little_endian 1.0\n"
         << "comment scanplan coverage: part frame, mm; colour = points/mm2, viridis 0 .. " << top
         << ", red-orange (220, 70, 40) = not covered; quality = points/mm2 (for MeshLab)\n"
         << "element vertex " << 3 * n << "\n"
         << "property float x\n"
         << "property float y\n"
         << "property float z\n"
         << "property uchar red\n"
         << "property uchar green\n"
         << "property uchar blue\n"
         << "property float scalar_density_per_mm2\n"
         << "property int scalar_points\n"  // int, not uint: Open3D's tensor reader refuses uint
         << "property float quality\n"
         << "element face " << n << "\n"
         << "property list uchar int vertex_indices\n"
         << "end_header\n";
  writeHeader(out, header.str());
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
      const std::uint32_t hits = i < coverage.hits.size() ? coverage.hits[i] : 0;
      w.i32(static_cast<std::int32_t>(
          std::min<std::uint32_t>(hits, std::numeric_limits<std::int32_t>::max())));
      w.f32(densities[i]);  // quality
    }
    w.endRecord();
  }
  for (std::size_t i = 0; i < n; ++i) {
    w.u8(3);
    for (std::size_t k = 0; k < 3; ++k) w.i32(static_cast<std::int32_t>(3 * i + k));
    w.endRecord();
  }
}

void writeLabelledSamplesPly(std::ostream& out,
                             const std::vector<Eigen::Vector3d>& points,
                             const std::vector<Eigen::Vector3d>& normals,
                             const std::vector<std::uint8_t>& labels,
                             const std::vector<std::string>& reasons) {
  std::ostringstream header;
  header << "ply\n"
         << "format binary_little_endian 1.0\n"
         << "comment scanplan surface samples: part frame, mm; unit normals; quality = reason "
            "(for MeshLab); reason:";
  for (std::size_t i = 0; i < reasons.size(); ++i) header << ' ' << i << " = " << reasons[i];
  header << "\nelement vertex " << points.size() << "\n"
         << "property float x\nproperty float y\nproperty float z\n"
         << "property float nx\nproperty float ny\nproperty float nz\n"
         << "property uchar scalar_reason\n"
         << "property float quality\n"
         << "end_header\n";
  writeHeader(out, header.str());
  LittleEndianWriter w(out);
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (int k = 0; k < 3; ++k) w.f32(toMm(points[i][k]));
    for (int k = 0; k < 3; ++k) w.f32(normals[i][k]);
    w.u8(labels[i]);
    w.f32(labels[i]);  // quality
    w.endRecord();
  }
}

}  // namespace scanplan::scanner
