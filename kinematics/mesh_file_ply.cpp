// PLY. Debian's assimp 5.2 trusts a PLY file's structure:
// - it sizes the mesh's vertex and face arrays by the first 'vertex' and the first 'face' (or
//   'tristrips') element and writes every later such element's entries into them by index, so a
//   second, longer one writes past their end: heap corruption (found by fuzzing);
// - it allocates a list's length before reading its values (an ASCII count of 377777777777777,
//   a binary one of 2³²−1: gigabytes), and reads a face's corners through its texture
//   coordinates (six coordinates and no corner list: a null pointer read, a crash);
// - it reads a header it does not expect its own way: a property after a comment is dropped (and
//   every value after it read into the wrong property), as is one of an unknown type, and binary
//   data starting with a line feed after a header ending in a bare line feed loses that byte;
// - it reads a missing or unreadable ASCII value as 0 without a word (a truncated file loads);
// - it loops or allocates without end on a header that never ends or claims a billion vertices,
//   and seeks at the end of the file for ever when 'end_header' has more on its line
//   ('end_header0 0 0').
// So a PLY file is checked whole before assimp sees it: its header (within 64 kB) line by line
// as the PLY format writes it, its counts against the file's size, then its data element by
// element, without keeping anything, counting the faces' triangles on the way.

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/mesh_file.h>
#include <scanplan/kinematics/mesh_file_formats.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <optional>
#include <string>

namespace scanplan::kinematics::detail {
namespace {

constexpr std::size_t kMaxHeader = 64 << 10;  // header bytes
constexpr std::size_t kMaxLine = 1 << 20;     // an ASCII line
// assimp's own limit on a face's corners (AI_MAX_FACE_INDICES); it keeps every list value in 8
// bytes, so longer lists of anything are refused as well.
constexpr std::uintmax_t kMaxPlyList = 0x7fff;
constexpr std::uintmax_t kMaxPlyCount = 10'000'000'000;

struct PlyType {
  std::string_view name;
  unsigned bytes;
  bool integer;
  bool is_signed;
};

// assimp's type names (PLY::Property::ParseDataType).
constexpr std::array<PlyType, 17> kPlyTypes = {{{"char", 1, true, true},
                                                {"int8", 1, true, true},
                                                {"uchar", 1, true, false},
                                                {"uint8", 1, true, false},
                                                {"short", 2, true, true},
                                                {"int16", 2, true, true},
                                                {"ushort", 2, true, false},
                                                {"uint16", 2, true, false},
                                                {"int", 4, true, true},
                                                {"int32", 4, true, true},
                                                {"uint", 4, true, false},
                                                {"uint32", 4, true, false},
                                                {"float", 4, false, true},
                                                {"float32", 4, false, true},
                                                {"double", 8, false, true},
                                                {"float64", 8, false, true},
                                                {"double64", 8, false, true}}};

const PlyType* plyType(std::string_view name) {
  for (const auto& type : kPlyTypes) {
    if (type.name == name) return &type;
  }
  return nullptr;
}

struct PlyProperty {
  std::string name;
  const PlyType* length = nullptr;  // a list's length type; nullptr for a single value
  const PlyType* type = nullptr;
};

struct PlyElement {
  std::string name;
  std::uintmax_t count = 0;
  std::size_t line = 0;  // of its 'element' line, from 1
  std::vector<PlyProperty> properties;
  // A face's corner list and per-corner texture coordinates (the last of each, as assimp takes
  // them); -1 when absent.
  int corners = -1;
  int texcoords = -1;

  bool hasLists() const {
    return std::any_of(properties.begin(), properties.end(),
                       [](const PlyProperty& p) { return p.length != nullptr; });
  }
};

enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  std::optional<std::size_t> vertex, face;  // indices into elements; a face may be tristrips
  std::string previous;                     // the keyword of the line before
};

// --- the header -------------------------------------------------------------------------------

[[noreturn]] void failIncomplete(const std::filesystem::path& path) {
  failMesh(path,
           "has no complete PLY header ('ply' … 'end_header' in the first 64 kB); expected a PLY "
           "mesh");
}

PlyFormat readFormat(const TextLines& lines, const std::vector<std::string_view>& word) {
  if (word.size() != 3 || word[0] != "format" ||
      (word[1] != "ascii" && word[1] != "binary_little_endian" && word[1] != "binary_big_endian")) {
    lines.fail("is not a PLY format line",
               "'format ascii 1.0', 'format binary_little_endian 1.0' or "
               "'format binary_big_endian 1.0'");
  }
  return word[1] == "ascii"                  ? PlyFormat::kAscii
         : word[1] == "binary_little_endian" ? PlyFormat::kBinaryLittleEndian
                                             : PlyFormat::kBinaryBigEndian;
}

// assimp fills one vertex array and one face array: a second such element writes past them.
void refuseSecond(const TextLines& lines, const PlyHeader& header, const std::string& name) {
  const bool is_vertex = name == "vertex";
  const bool is_face = name == "face" || name == "tristrips";
  const auto first = is_vertex ? header.vertex : is_face ? header.face : std::nullopt;
  if (!first) return;
  const PlyElement& other = header.elements[*first];
  lines.fail("declares a second " + std::string(is_vertex ? "vertex" : "face") +
                 " element (the first: '" + other.name + "' on line " + std::to_string(other.line) +
                 ")",
             "one 'vertex' element and one 'face' (or 'tristrips') element");
}

void addElement(const TextLines& lines,
                const std::vector<std::string_view>& word,
                PlyHeader& header) {
  if (word.size() != 3 || !isDigits(word[2]) || word[2].size() > 11) {
    lines.fail("is not an element line", "'element <name> <count>' with a whole number up to 1e10");
  }
  PlyElement element;
  element.name = word[1];
  element.count = std::stoull(std::string(word[2]));
  element.line = lines.number();
  if (element.count > kMaxPlyCount) {
    lines.fail("has an element count over 1e10",
               "'element <name> <count>' with a count up to 1e10");
  }
  if (element.name == "TextureFile") {
    lines.fail("names an element 'TextureFile', which assimp takes for a texture file name",
               "another element name");
  }
  refuseSecond(lines, header, element.name);
  if (element.name == "vertex") header.vertex = header.elements.size();
  if (element.name == "face" || element.name == "tristrips") header.face = header.elements.size();
  header.elements.push_back(std::move(element));
}

void addProperty(const TextLines& lines,
                 const std::vector<std::string_view>& word,
                 PlyHeader& header) {
  if (header.previous != "element" && header.previous != "property") {
    lines.fail(header.previous.empty()
                   ? "comes before any element"
                   : "follows a " + header.previous +
                         " line, which ends the element's properties for assimp",
               "an element's properties right after its 'element' line, comments elsewhere");
  }
  const bool list = word.size() == 5 && word[1] == "list";
  const PlyType* length = list ? plyType(word[2]) : nullptr;
  const PlyType* type = list || word.size() == 3 ? plyType(word[list ? 3 : 1]) : nullptr;
  if (type == nullptr || (list && length == nullptr)) {
    lines.fail("is not a property assimp reads",
               "'property <type> <name>' or 'property list <type> <type> <name>', a type being "
               "char, uchar, short, ushort, int, uint, float, double, int8 … uint32, float32 or "
               "float64");
  }
  if (list && !length->integer) lines.fail("has a list length type that is not an integer", "one");
  PlyElement& element = header.elements.back();
  const int index = static_cast<int>(element.properties.size());
  const std::string name(word.back());
  const bool face = element.name == "face" || element.name == "tristrips";
  if (face && list && (name == "vertex_indices" || name == "vertex_index")) element.corners = index;
  if (element.name == "face" && list && name == "texcoord") element.texcoords = index;
  element.properties.push_back({name, length, type});
}

// A header line after the format line, but 'end_header'.
void readHeaderLine(const TextLines& lines,
                    const std::vector<std::string_view>& word,
                    PlyHeader& header) {
  const std::string keyword(word.empty() ? std::string_view() : word[0]);
  if (keyword == "element") {
    addElement(lines, word, header);
  } else if (keyword == "property") {
    addProperty(lines, word, header);
  } else if (keyword != "comment" && keyword != "obj_info") {
    lines.fail("is not a PLY header line",
               "'comment', 'obj_info', 'element', 'property' or 'end_header' lines");
  }
  header.previous = keyword;
}

// Every element has a property, and each takes a byte at least (binary; two, ASCII): a header
// claiming a billion vertices in a small file is refused before the loader allocates them.
void checkCounts(const std::filesystem::path& path, const PlyHeader& header, std::uintmax_t size) {
  std::uintmax_t needed = 0;
  for (const auto& element : header.elements) {
    if (element.properties.empty()) {
      failMesh(path, "declares PLY element '" + clipForMessage(element.name) + "' on line " +
                         std::to_string(element.line) + " with no property; expected at least one");
    }
    needed += element.count;
  }
  if (needed > size) {
    failMesh(path, "claims " + std::to_string(needed) + " PLY elements in " + std::to_string(size) +
                       " bytes: a truncated or corrupt file");
  }
}

// Reads the header up to its 'end_header' line, which `lines` is left at. Its last line must be
// 'end_header' alone: with more on that line assimp's reader seeks at the end of the file for
// ever.
PlyHeader readHeader(TextLines& lines, const std::filesystem::path& path, std::uintmax_t size) {
  if (head(path, 3) != "ply") failIncomplete(path);
  lines.setLabel(" of its PLY header");
  PlyHeader header;
  std::vector<std::string_view> word;
  while (true) {
    if (!lines.next() || lines.offset() > kMaxHeader) failIncomplete(path);
    splitWords(lines.text(), word);
    if (lines.number() == 1) {
      if (word.size() != 1 || word[0] != "ply") failIncomplete(path);
    } else if (lines.number() == 2) {
      header.format = readFormat(lines, word);
    } else if (!word.empty() && word[0].rfind("end_header", 0) == 0) {
      if (word[0] != "end_header" || word.size() > 1) {
        failMesh(path,
                 "has more than 'end_header' on the PLY header's last line; expected it alone");
      }
      break;
    } else {
      readHeaderLine(lines, word, header);
    }
  }
  lines.setLabel("");
  checkCounts(path, header, size);
  return header;
}

// --- the data ---------------------------------------------------------------------------------

// assimp reads a face's texture coordinates only when there are 6 to 8 of them, as two per
// corner, through the corner list: it must hold the corners they name.
bool texcoordsFit(std::uintmax_t corners, std::uintmax_t texcoords) {
  return texcoords < 6 || texcoords > 8 || corners >= (texcoords + 1) / 2;
}

std::string texcoordsMismatch(std::uintmax_t corners, std::uintmax_t texcoords) {
  return std::to_string(texcoords) + " texture coordinates and " + std::to_string(corners) +
         " corners";
}

// What one element instance's lists hold: the face's corners and texture coordinates.
struct Lists {
  std::uintmax_t corners = 0, texcoords = 0;

  void take(const PlyElement& element, std::size_t property, std::uintmax_t length) {
    if (static_cast<int>(property) == element.corners) corners = length;
    if (static_cast<int>(property) == element.texcoords) texcoords = length;
  }
};

// Whether assimp reads `word` whole as a value of `type`: its number readers stop at the first
// character they do not take and read the next value from there, out of step with the line.
bool isPlyNumber(std::string_view word, const PlyType& type) {
  if (!word.empty() && type.is_signed && (word[0] == '-' || word[0] == '+')) word.remove_prefix(1);
  if (type.integer) return isDigits(word);
  if (!word.empty() && !isDigit(word[0]) && word[0] != '.') {
    std::string lower(word);
    std::transform(lower.begin(), lower.end(), lower.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return lower == "nan" || lower == "inf" || lower == "infinity";
  }
  std::size_t i = 0;
  const auto digits = [&] {
    const std::size_t start = i;
    while (i < word.size() && isDigit(word[i])) ++i;
    return i - start;
  };
  std::size_t mantissa = digits();
  if (i < word.size() && word[i] == '.') {
    ++i;
    mantissa += digits();
  }
  if (mantissa == 0) return false;
  if (i < word.size() && (word[i] == 'e' || word[i] == 'E')) {
    ++i;
    if (i < word.size() && (word[i] == '-' || word[i] == '+')) ++i;
    if (digits() == 0) return false;
  }
  return i == word.size();
}

// One ASCII data line, the instance `index` of `element`.
struct AsciiRow {
  const TextLines& lines;
  const PlyElement& element;
  std::uintmax_t index;
  const std::vector<std::string_view>& word;

  // "line N ('…'), 'face' 2 of 4, <what>; expected <expected>".
  [[noreturn]] void fail(const std::string& what, const std::string& expected) const {
    failMesh(lines.path(), lines.where() + ", '" + clipForMessage(element.name) + "' " +
                               std::to_string(index + 1) + " of " + std::to_string(element.count) +
                               ", " + what + "; expected " + expected);
  }
  std::string one() const {
    return "one '" + clipForMessage(element.name) +
           "' per line, with the values the PLY header declares";
  }
};

// Property `p` of an ASCII row from word `w` on: a list's length, then its values. Returns the
// words it took.
std::size_t checkAsciiProperty(const AsciiRow& row, std::size_t p, std::size_t w, Lists& lists) {
  const PlyProperty& property = row.element.properties[p];
  const std::string of = " for property '" + clipForMessage(property.name) + "'";
  std::uintmax_t values = 1;
  std::size_t taken = 0;
  if (property.length != nullptr) {
    if (w == row.word.size()) row.fail("ends before its list length" + of, row.one());
    const std::string_view length = row.word[w];
    if (isDigits(length) && length.size() <= 5) values = std::stoull(std::string(length));
    if (!isDigits(length) || length.size() > 5 || values > kMaxPlyList) {
      row.fail("has list length '" + clipForMessage(std::string(length)) + "'" + of,
               "a whole number up to " + std::to_string(kMaxPlyList));
    }
    lists.take(row.element, p, values);
    taken = 1;
  }
  const std::size_t left = row.word.size() - w - taken;
  if (left < values) {
    row.fail("has " + std::to_string(left) + (left == 1 ? " value" : " values") + " left" + of +
                 ", which wants " + std::to_string(values),
             row.one());
  }
  for (std::size_t v = w + taken; v < w + taken + values; ++v) {
    if (!isPlyNumber(row.word[v], *property.type)) {
      row.fail("has '" + clipForMessage(std::string(row.word[v])) + "'" + of + " (" +
                   std::string(property.type->name) + ")",
               property.type->integer ? "a whole number" : "a number");
    }
  }
  return taken + static_cast<std::size_t>(values);
}

// assimp reads one element per line, each line exactly the values the header declares (a list:
// its length, then that many values). Returns a face's triangles.
std::uintmax_t checkAsciiRow(const AsciiRow& row) {
  if (row.word.empty()) row.fail("is blank", row.one());
  Lists lists;
  std::size_t w = 0;
  for (std::size_t p = 0; p < row.element.properties.size(); ++p) {
    w += checkAsciiProperty(row, p, w, lists);
  }
  if (w != row.word.size()) {
    row.fail("has " + std::to_string(row.word.size()) + " values where the PLY header declares " +
                 std::to_string(w) + " for one '" + clipForMessage(row.element.name) + "'",
             row.one());
  }
  if (!texcoordsFit(lists.corners, lists.texcoords)) {
    row.fail("has " + texcoordsMismatch(lists.corners, lists.texcoords),
             "two coordinates per corner");
  }
  return faceTriangles(lists.corners);
}

std::uintmax_t checkAsciiData(TextLines& lines, const PlyHeader& header) {
  std::vector<std::string_view> word;
  std::uintmax_t triangles = 0;
  for (const auto& element : header.elements) {
    for (std::uintmax_t k = 0; k < element.count; ++k) {
      if (!lines.next()) {
        failMesh(lines.path(), "has " + std::to_string(k) + " of the " +
                                   std::to_string(element.count) + " '" +
                                   clipForMessage(element.name) +
                                   "' lines its PLY header declares; expected all of them (a "
                                   "truncated file)");
      }
      splitWords(lines.text(), word);
      triangles += checkAsciiRow({lines, element, k, word});
    }
  }
  return triangles;
}

// A binary integer of `type` (1 to 4 bytes) as a signed value.
std::int64_t binaryInteger(const unsigned char* bytes, const PlyType& type, bool big_endian) {
  std::uint64_t bits = 0;
  for (unsigned i = 0; i < type.bytes; ++i) {
    bits |= std::uint64_t{bytes[big_endian ? type.bytes - 1 - i : i]} << (8 * i);
  }
  const unsigned width = 8 * type.bytes;
  if (type.is_signed && (bits >> (width - 1)) != 0) {
    return static_cast<std::int64_t>(bits) - (std::int64_t{1} << width);
  }
  return static_cast<std::int64_t>(bits);
}

[[noreturn]] void failBinaryTruncated(const std::filesystem::path& path,
                                      const PlyElement& element,
                                      std::uintmax_t index) {
  failMesh(path, "has binary PLY data that ends inside '" + clipForMessage(element.name) + "' " +
                     std::to_string(index + 1) + " of " + std::to_string(element.count) +
                     "; expected every element its header declares (a truncated file)");
}

// The binary data being walked.
struct BinaryData {
  const std::filesystem::path& path;
  FileBytes& bytes;
  bool big_endian;
};

// A binary list's length, from 0 to kMaxPlyList.
std::uintmax_t readListLength(const BinaryData& data,
                              const PlyElement& element,
                              std::uintmax_t index,
                              const PlyProperty& property) {
  unsigned char raw[8];
  if (!data.bytes.read(raw, property.length->bytes)) failBinaryTruncated(data.path, element, index);
  const std::int64_t length = binaryInteger(raw, *property.length, data.big_endian);
  if (length < 0 || static_cast<std::uintmax_t>(length) > kMaxPlyList) {
    failMesh(data.path, "has a list '" + clipForMessage(property.name) + "' of " +
                            std::to_string(length) + " values in '" + clipForMessage(element.name) +
                            "' " + std::to_string(index + 1) + " (byte " +
                            std::to_string(data.bytes.offset() - property.length->bytes) +
                            "); expected 0 to " + std::to_string(kMaxPlyList));
  }
  return static_cast<std::uintmax_t>(length);
}

// One binary instance of an element with lists, value by value. Returns a face's triangles.
std::uintmax_t checkBinaryInstance(const BinaryData& data,
                                   const PlyElement& element,
                                   std::uintmax_t index) {
  Lists lists;
  for (std::size_t p = 0; p < element.properties.size(); ++p) {
    const PlyProperty& property = element.properties[p];
    std::uintmax_t values = 1;
    if (property.length != nullptr) {
      values = readListLength(data, element, index, property);
      lists.take(element, p, values);
    }
    if (!data.bytes.skip(values * property.type->bytes)) {
      failBinaryTruncated(data.path, element, index);
    }
  }
  if (!texcoordsFit(lists.corners, lists.texcoords)) {
    failMesh(data.path, "has binary PLY '" + clipForMessage(element.name) + "' " +
                            std::to_string(index + 1) + " of " + std::to_string(element.count) +
                            " with " + texcoordsMismatch(lists.corners, lists.texcoords) +
                            "; expected two coordinates per corner");
  }
  return faceTriangles(lists.corners);
}

// Binary data: walked value by value (an element without lists in one step), each list length
// checked against what the file still holds. Returns the faces' triangles.
std::uintmax_t checkBinaryData(const BinaryData& data, const PlyHeader& header) {
  std::uintmax_t triangles = 0;
  for (const auto& element : header.elements) {
    if (!element.hasLists()) {
      std::uintmax_t width = 0;
      for (const auto& property : element.properties) width += property.type->bytes;
      if (!data.bytes.skip(element.count * width)) {
        failBinaryTruncated(data.path, element, data.bytes.left() / width);
      }
      continue;
    }
    for (std::uintmax_t k = 0; k < element.count; ++k) {
      triangles += checkBinaryInstance(data, element, k);
    }
  }
  return triangles;
}

// assimp takes the byte after a header line's '\r' for the rest of the line end if it is '\n',
// and so drops binary data's first byte when it is 0x0A after a bare '\n' (every value is then
// read one byte off). After "\r\n" it reads the data right, whatever its first byte.
void refuseLeadingLineFeed(const TextLines& lines, FileBytes& bytes) {
  char first = 0;
  if (lines.crlf() || !bytes.peek(first) || first != '\n') return;
  failMesh(lines.path(),
           "has binary PLY data starting with byte 0x0A right after 'end_header' and a bare line "
           "feed, which assimp would skip as part of the line end (reading every value one byte "
           "off); expected \\r\\n line ends in the header, or other first data");
}

}  // namespace

std::uintmax_t checkPly(const std::filesystem::path& path, std::uintmax_t size) {
  TextLines lines(path, size, kMaxLine);
  const PlyHeader header = readHeader(lines, path, size);
  if (header.format == PlyFormat::kAscii) return checkAsciiData(lines, header);
  FileBytes bytes(path, size, lines.offset());
  refuseLeadingLineFeed(lines, bytes);
  return checkBinaryData({path, bytes, header.format == PlyFormat::kBinaryBigEndian}, header);
}

}  // namespace scanplan::kinematics::detail
