#include "kinematics/mesh_file.h"

#include "kinematics/error.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>
#include <system_error>
#include <vector>

namespace scanplan::kinematics::detail {
namespace {

constexpr const char* kSupported = ".stl .obj .ply .off";
constexpr std::size_t kMaxHeader = 64 << 10;  // PLY and OFF header bytes
constexpr std::size_t kMaxLine = 1 << 20;     // an ASCII PLY line

// The first `n` bytes of a file.
std::string head(const std::filesystem::path& path, std::size_t n) {
  std::ifstream in(path, std::ios::binary);
  std::string text(n, '\0');
  in.read(text.data(), static_cast<std::streamsize>(n));
  text.resize(static_cast<std::size_t>(in.gcount()));
  return text;
}

// A file's bytes from an offset, read in blocks; a NUL byte ends the text, as it ends assimp's
// (its readers take the file as a C string).
class ByteReader {
 public:
  ByteReader(const std::filesystem::path& path, std::uintmax_t offset)
      : in_(path, std::ios::binary), buffer_(1 << 16) {
    in_.seekg(static_cast<std::streamoff>(offset));
  }
  // The next byte without taking it; false at the end.
  bool peek(char& c) {
    if (pos_ == size_ && !fill()) return false;
    c = buffer_[pos_];
    return c != '\0';
  }
  void take() { ++pos_; }

 private:
  bool fill() {
    if (!in_) return false;
    in_.read(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
    size_ = static_cast<std::size_t>(in_.gcount());
    pos_ = 0;
    return size_ > 0;
  }

  std::ifstream in_;
  std::vector<char> buffer_;
  std::size_t size_ = 0, pos_ = 0;
};

bool isLineEnd(char c) { return c == '\n' || c == '\r' || c == '\f'; }
bool isBlank(char c) { return c == ' ' || c == '\t'; }

// The lines of a file from an offset, split as assimp's OFF and PLY readers split them: a run of
// '\n', '\r' and '\f' is one break (blank lines vanish); a line of spaces is a line.
class LineReader {
 public:
  LineReader(const std::filesystem::path& path,
             std::uintmax_t offset,
             std::size_t first_line,
             std::size_t max_line)
      : path_(path), bytes_(path, offset), newlines_(first_line - 1), max_line_(max_line) {}

  // The next line into `line`; false at the end of the text.
  bool next(std::string& line) {
    line.clear();
    char c = 0;
    for (; bytes_.peek(c) && isLineEnd(c); bytes_.take()) newlines_ += c == '\n' ? 1 : 0;
    if (!bytes_.peek(c)) return false;
    number_ = newlines_ + 1;
    for (; bytes_.peek(c) && !isLineEnd(c); bytes_.take()) {
      if (line.size() == max_line_) {
        failMesh(path_, "has a line (line " + std::to_string(number_) + ") longer than " +
                            std::to_string(max_line_) + " characters; expected shorter lines");
      }
      line.push_back(c);
    }
    return true;
  }
  // The line number of the line `next` returned last.
  std::size_t number() const { return number_; }

 private:
  const std::filesystem::path& path_;
  ByteReader bytes_;
  std::size_t newlines_, max_line_, number_ = 0;
};

// The words of a line (separated by blanks), one at a time.
class Words {
 public:
  explicit Words(std::string_view line) : line_(line) {}
  bool next(std::string_view& word) {
    while (at_ < line_.size() && isBlank(line_[at_])) ++at_;
    const std::size_t begin = at_;
    while (at_ < line_.size() && !isBlank(line_[at_])) ++at_;
    word = line_.substr(begin, at_ - begin);
    return !word.empty();
  }

 private:
  std::string_view line_;
  std::size_t at_ = 0;
};

// A whole word of decimal digits as a number (saturating); nullopt for anything else.
std::optional<std::uint64_t> wholeNumber(std::string_view word) {
  if (word.empty() || !std::all_of(word.begin(), word.end(), [](char c) {
        return std::isdigit(static_cast<unsigned char>(c));
      })) {
    return std::nullopt;
  }
  std::uint64_t value = 0;
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), value);
  return ec == std::errc() ? value : std::numeric_limits<std::uint64_t>::max();
}

bool isNumber(std::string_view word) {
  if (!word.empty() && word.front() == '+') word.remove_prefix(1);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), value);
  return !word.empty() && end == word.data() + word.size() &&
         (ec == std::errc() || ec == std::errc::result_out_of_range);
}

std::size_t linesIn(std::string_view text) {
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

// --- OFF --------------------------------------------------------------------------------------

struct OffHeader {
  std::uint64_t vertices = 0, faces = 0;
  std::size_t body = 0;  // byte offset of the first vertex
};

// The header as assimp 5.2's OFF reader takes it, token by token (OFFImporter::InternReadFile):
// optional ST, C, N, 4, n prefixes and OFF, a dimension after n, the vertex, face and edge
// counts, comment lines between tokens. Nullopt where assimp refuses the header itself.
std::optional<OffHeader> parseOffHeader(const std::string& h) {
  std::size_t i = 0;
  const auto at = [&h](std::size_t k) { return k < h.size() ? h[k] : '\0'; };
  const auto skipBlanks = [&] {
    while (isBlank(at(i)) || at(i) == '\r' || at(i) == '\n') ++i;
  };
  const auto nextToken = [&] {
    skipBlanks();
    while (at(i) == '#' || at(i) == '\r' || at(i) == '\n') {
      while (at(i) != '\r' && at(i) != '\n' && at(i) != '\0') ++i;
      skipBlanks();
    }
  };
  const auto number = [&] {
    std::uint64_t v = 0;
    for (; std::isdigit(static_cast<unsigned char>(at(i))); ++i) {
      v = std::min<std::uint64_t>(v * 10 + static_cast<std::uint64_t>(at(i) - '0'), 1ull << 40);
    }
    return v;
  };
  nextToken();
  if (at(i) == 'S' && at(i + 1) == 'T') i += 2;
  if (at(i) == 'C') ++i;
  if (at(i) == 'N') ++i;
  if (at(i) == '4') ++i;
  const bool dimension = at(i) == 'n';
  if (dimension) ++i;
  if (at(i) == 'O' && at(i + 1) == 'F' && at(i + 2) == 'F') {
    i += 3;
    nextToken();
  } else {
    nextToken();
    if (!std::isdigit(static_cast<unsigned char>(at(i)))) return std::nullopt;
  }
  if (dimension) {
    if (number() > 3) return std::nullopt;
    nextToken();
  }
  nextToken();
  OffHeader header;
  header.vertices = number();
  nextToken();
  header.faces = number();
  nextToken();
  number();  // edges, unused
  nextToken();
  header.body = i;
  return header;
}

// One face line: its vertex count (1 to 9: assimp drops other faces without a word) and that
// many indices, each a plain number below the vertex count (assimp clamps a larger one to the
// last vertex, and reads a negative one as 0). Returns its triangles.
std::size_t checkOffFace(const std::filesystem::path& path,
                         const std::string& line,
                         std::uint64_t face,
                         std::size_t line_number,
                         std::uint64_t vertices) {
  const std::string where =
      "face " + std::to_string(face + 1) + " (line " + std::to_string(line_number) + ")";
  const std::string range = "from 0 to " + std::to_string(vertices - 1);
  Words words(line);
  std::string_view word;
  const auto n = words.next(word) ? wholeNumber(word) : std::nullopt;
  if (!n || *n < 1 || *n > 9) {
    failMesh(path, "has OFF " + where + " '" + clipForMessage(line) +
                       "': expected its vertex count (1 to 9, as the reader takes), then as many "
                       "vertex indices");
  }
  for (std::uint64_t k = 0; k < *n; ++k) {
    if (!words.next(word)) {
      failMesh(path, "has OFF " + where + " with " + std::to_string(k) + " of its " +
                         std::to_string(*n) + " vertex indices; expected " + std::to_string(*n) +
                         " indices " + range);
    }
    const auto index = wholeNumber(word);
    if (!index) {
      failMesh(path, "has OFF " + where + " vertex index '" + clipForMessage(std::string(word)) +
                         "'; expected an index " + range);
    }
    if (*index >= vertices) {
      failMesh(path, "has OFF " + where + " vertex index " + std::to_string(*index) +
                         " out of range: the file has " + std::to_string(vertices) +
                         " vertices (indices " + range + ")");
    }
  }
  return *n >= 3 ? static_cast<std::size_t>(*n - 2) : 0;
}

// The header's counts must fit the file (each vertex and face takes a few bytes at least), and
// the body must hold them, every face well-formed. Returns the triangles.
std::size_t checkOff(const std::filesystem::path& path, std::uintmax_t size) {
  const std::string text = head(path, kMaxHeader);
  const auto header = parseOffHeader(text);
  if (!header) return 0;  // assimp says why
  const auto v = header->vertices, f = header->faces;
  if (v == 0 || f == 0) {
    failMesh(path,
             "has no vertex and face counts above 0 in its OFF header; expected 'OFF', then the "
             "numbers of vertices, faces and edges");
  }
  if (static_cast<double>(v) * 6.0 + static_cast<double>(f) * 8.0 > static_cast<double>(size)) {
    failMesh(path, "claims " + std::to_string(v) + " vertices and " + std::to_string(f) +
                       " faces in " + std::to_string(size) +
                       " bytes: a truncated or corrupt OFF file");
  }
  if (header->body >= text.size() && size > text.size()) {
    failMesh(path, "has no complete OFF header in its first 64 kB; expected 'OFF' and the counts");
  }
  LineReader lines(path, header->body, linesIn(std::string_view(text).substr(0, header->body)) + 1,
                   kMaxOffLine);
  std::string line;
  const std::string counts = std::to_string(v) + " vertices and " + std::to_string(f) + " faces";
  for (std::uint64_t k = 0; k < v; ++k) {
    if (!lines.next(line)) {
      failMesh(path, "ends after " + std::to_string(k) + " vertices; its OFF header gives " +
                         counts + ": a truncated file");
    }
  }
  std::size_t triangles = 0;
  for (std::uint64_t k = 0; k < f; ++k) {
    if (!lines.next(line)) {
      failMesh(path, "ends after " + std::to_string(k) + " faces; its OFF header gives " + counts +
                         ": a truncated file");
    }
    triangles += checkOffFace(path, line, k, lines.number(), v);
  }
  return triangles;
}

// --- PLY --------------------------------------------------------------------------------------

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<bool> lists;  // per property: a list (a length, then that many values)
};

struct PlyHeader {
  bool ascii = false;
  std::vector<PlyElement> elements;
  std::size_t body = 0;       // byte offset after the end_header line
  std::size_t body_line = 0;  // its line number
};

// The header must end within 64 kB and its element counts fit the file: a header alone, or one
// claiming a billion vertices, is refused before the loader sees it (which loops or allocates
// without end on them). Its last line must be `end_header` alone: with more on that line
// (`end_header0 0 0`) assimp's PLY reader seeks at the end of the file for ever.
PlyHeader parsePlyHeader(const std::filesystem::path& path, std::uintmax_t size) {
  const std::string text = head(path, kMaxHeader);
  std::istringstream lines(text);
  PlyHeader header;
  std::uintmax_t needed = 0;  // at least a byte per element (binary), two per number (ASCII)
  bool ended = false;
  for (std::string line; !ended && std::getline(lines, line);) {
    header.body += line.size() + 1;
    ++header.body_line;
    std::istringstream words(line);
    std::string word, name, type;
    double count = 0.0;
    if ((words >> word) && word.rfind("end_header", 0) == 0) {
      if (word != "end_header" || words >> name) {
        failMesh(path,
                 "has more than 'end_header' on the PLY header's last line; expected it alone");
      }
      ended = true;
    } else if (word == "format" && words >> type) {
      header.ascii = type == "ascii";
    } else if (word == "element" && words >> name >> count) {
      if (!(count >= 0.0) || count > 1e10) failMesh(path, "has a PLY element count of " + line);
      header.elements.push_back({name, static_cast<std::uint64_t>(count), {}});
      needed += static_cast<std::uintmax_t>(count);
    } else if (word == "property" && words >> type && !header.elements.empty()) {
      header.elements.back().lists.push_back(type == "list");
    }
  }
  if (text.rfind("ply", 0) != 0 || !ended) {
    failMesh(path,
             "has no complete PLY header ('ply' … 'end_header' in the first 64 kB); expected a "
             "PLY mesh");
  }
  if (needed > size) {
    failMesh(path, "claims " + std::to_string(needed) + " PLY elements in " + std::to_string(size) +
                       " bytes: a truncated or corrupt file");
  }
  ++header.body_line;
  return header;
}

// One ASCII element: a number for each scalar property, a length and that many numbers for
// each list (assimp reads a missing or unreadable one as 0 without a word). Returns the
// triangles of a face.
std::size_t checkPlyElement(const std::filesystem::path& path,
                            const PlyElement& element,
                            std::uint64_t index,
                            const std::string& line,
                            std::size_t line_number) {
  const std::string where = "'" + element.name + "' " + std::to_string(index + 1) + " of " +
                            std::to_string(element.count) + " (line " +
                            std::to_string(line_number) + ")";
  Words words(line);
  std::string_view word;
  // Numbers: each property has one at least; a list's length adds its values once read.
  std::uint64_t found = 0, expected = element.lists.size();
  const auto take = [&] {
    if (!words.next(word)) {
      failMesh(path, "has PLY " + where + " with " + std::to_string(found) +
                         " numbers where its header declares at least " + std::to_string(expected) +
                         ": a truncated or corrupt file");
    }
    if (!isNumber(word)) {
      failMesh(path, "has PLY " + where + " value '" + clipForMessage(std::string(word)) +
                         "'; expected a number");
    }
    ++found;
  };
  std::size_t triangles = 0;
  for (const bool list : element.lists) {
    take();
    if (!list) continue;
    const auto length = wholeNumber(word);
    if (!length) {
      failMesh(path, "has PLY " + where + " list length '" + clipForMessage(std::string(word)) +
                         "'; expected a whole number");
    }
    expected += *length;
    for (std::uint64_t k = 0; k < *length; ++k) take();
    if (element.name == "face" && *length >= 3) triangles += static_cast<std::size_t>(*length - 2);
  }
  return triangles;
}

// An ASCII PLY's body must hold every element its header gives, one per line. Returns the
// triangles (for a binary PLY, the header's face count).
std::size_t checkPly(const std::filesystem::path& path, std::uintmax_t size) {
  const PlyHeader header = parsePlyHeader(path, size);
  std::size_t triangles = 0;
  if (!header.ascii) {
    for (const PlyElement& e : header.elements) {
      if (e.name == "face") triangles += static_cast<std::size_t>(e.count);
    }
    return triangles;
  }
  LineReader lines(path, header.body, header.body_line, kMaxLine);
  std::string line;
  for (const PlyElement& e : header.elements) {
    for (std::uint64_t k = 0; k < e.count; ++k) {
      do {
        if (!lines.next(line)) {
          failMesh(path, "has " + std::to_string(k) + " '" + e.name + "' elements where its PLY " +
                             "header gives " + std::to_string(e.count) + ": a truncated file");
        }
      } while (line.find_first_not_of(" \t") == std::string::npos);
      triangles += checkPlyElement(path, e, k, line, lines.number());
    }
  }
  return triangles;
}

// --- STL and OBJ ------------------------------------------------------------------------------

// A binary STL is the size its count says (assimp's test); an ASCII one makes a triangle of
// every three `vertex` keywords.
std::size_t stlTriangles(const std::filesystem::path& path, std::uintmax_t size) {
  const std::string start = head(path, 84);
  if (start.size() == 84) {
    std::uint32_t count = 0;
    std::memcpy(&count, start.data() + 80, sizeof count);
    if (std::uintmax_t{count} * 50 + 84 == size) return count;
  }
  ByteReader bytes(path, 0);
  constexpr std::string_view kVertex = "vertex";
  std::size_t matched = 0, vertices = 0;
  for (char c = 0; bytes.peek(c); bytes.take()) {
    matched = c == kVertex[matched] ? matched + 1 : (c == kVertex[0] ? 1 : 0);
    if (matched == kVertex.size()) {
      ++vertices;
      matched = 0;
    }
  }
  return vertices / 3;
}

// An OBJ face line (`f` and n vertices) makes n − 2 triangles.
std::size_t objTriangles(const std::filesystem::path& path) {
  ByteReader bytes(path, 0);
  std::size_t triangles = 0, words = 0, first_length = 0;
  char first = 0;
  bool in_word = false;
  const auto endLine = [&] {
    if (first == 'f' && first_length == 1 && words >= 4) triangles += words - 3;
    words = first_length = 0;
    first = 0;
    in_word = false;
  };
  for (char c = 0; bytes.peek(c); bytes.take()) {
    if (isLineEnd(c)) {
      endLine();
    } else if (isBlank(c)) {
      in_word = false;
    } else {
      if (!in_word && ++words == 1) first = c;
      in_word = true;
      if (words == 1) ++first_length;
    }
  }
  endLine();
  return triangles;
}

// --- the file ---------------------------------------------------------------------------------

std::string lowerExtension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// A regular file of a supported kind, not empty, not over the size limit: its size.
std::uintmax_t checkKindAndSize(const std::filesystem::path& path, const std::string& ext) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) {
    failMesh(path, "does not exist; expected an existing " + std::string(kSupported) + " file");
  }
  if (std::filesystem::is_directory(status)) {
    failMesh(path, "is a directory; expected a " + std::string(kSupported) + " file");
  }
  if (ext != ".stl" && ext != ".obj" && ext != ".ply" && ext != ".off") {
    failMesh(path, "has unsupported extension '" + ext + "'; supported: " + kSupported);
  }
  if (!std::filesystem::is_regular_file(status)) {
    failMesh(path, "is not a regular file (a pipe, socket or device); expected a mesh file");
  }
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) failMesh(path, "cannot be read: " + ec.message());
  if (size == 0) failMesh(path, "is empty (0 bytes); expected a triangle mesh");
  if (size > kMaxMeshBytes) {
    failMesh(path, "is " + std::to_string(size >> 20) + " MB; expected at most " +
                       std::to_string(kMaxMeshBytes >> 20) + " MB");
  }
  return size;
}

}  // namespace

void failMesh(const std::filesystem::path& path, const std::string& what) {
  throw InputError("mesh file '" + path.string() + "' " + what);
}

void checkMeshFile(const std::filesystem::path& path) {
  const std::string ext = lowerExtension(path);
  const std::uintmax_t size = checkKindAndSize(path, ext);
  const std::size_t triangles = ext == ".off"   ? checkOff(path, size)
                                : ext == ".ply" ? checkPly(path, size)
                                : ext == ".stl" ? stlTriangles(path, size)
                                                : objTriangles(path);
  if (triangles > kMaxMeshTriangles) {
    failMesh(path, "has " + std::to_string(triangles) + " triangles (counted before reading it); " +
                       "expected at most " + std::to_string(kMaxMeshTriangles) +
                       " (simplify the mesh)");
  }
}

}  // namespace scanplan::kinematics::detail
