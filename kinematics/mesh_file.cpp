#include <scanplan/kinematics/mesh_file.h>

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/mesh_file_formats.h>
#include <scanplan/kinematics/resources.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <sstream>
#include <string>
#include <system_error>

namespace scanplan::kinematics::detail {
namespace {

constexpr const char* kSupported = ".stl .obj .ply .off";

bool isLineEnd(char c) { return c == '\n' || c == '\r' || c == '\f'; }
bool isBlank(char c) { return c == ' ' || c == '\t'; }

std::string byteName(unsigned char byte) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  return std::string("0x") + kHex[byte >> 4] + kHex[byte & 15];
}

}  // namespace

// --- the readers the format checks share --------------------------------------------------------

FileBytes::FileBytes(const std::filesystem::path& path, std::uintmax_t size, std::uintmax_t offset)
    : in_(path, std::ios::binary), buffer_(std::size_t{64} << 10), offset_(offset), size_(size) {
  in_.seekg(static_cast<std::streamoff>(offset));
}

// At least `n` bytes in the buffer from pos_; false when the file has fewer.
bool FileBytes::fill(std::size_t n) {
  if (end_ - pos_ >= n) return true;
  std::copy(buffer_.begin() + static_cast<std::ptrdiff_t>(pos_),
            buffer_.begin() + static_cast<std::ptrdiff_t>(end_), buffer_.begin());
  end_ -= pos_;
  pos_ = 0;
  in_.read(buffer_.data() + end_, static_cast<std::streamsize>(buffer_.size() - end_));
  end_ += static_cast<std::size_t>(in_.gcount());
  return end_ >= n;
}

std::string_view FileBytes::buffered() {
  if (offset_ >= size_ || !fill(1)) return {};
  const auto n = static_cast<std::size_t>(std::min<std::uintmax_t>(end_ - pos_, left()));
  return {buffer_.data() + pos_, n};
}

bool FileBytes::peek(char& c) {
  const std::string_view bytes = buffered();
  if (bytes.empty()) return false;
  c = bytes.front();
  return true;
}

bool FileBytes::read(unsigned char* out, std::size_t n) {
  if (n > left() || !fill(n)) return false;
  std::copy_n(buffer_.begin() + static_cast<std::ptrdiff_t>(pos_), n, out);
  take(n);
  return true;
}

bool FileBytes::skip(std::uintmax_t n) {
  if (n > left()) return false;
  offset_ += n;
  if (n <= end_ - pos_) {
    pos_ += static_cast<std::size_t>(n);
    return true;
  }
  n -= end_ - pos_;
  pos_ = end_ = 0;
  in_.clear();
  in_.seekg(static_cast<std::streamoff>(n), std::ios::cur);
  return true;
}

TextLines::TextLines(const std::filesystem::path& path, std::uintmax_t size, std::size_t max_line)
    : path_(path), bytes_(path, size, 0), number_(0), max_line_(max_line) {}

bool TextLines::next() {
  line_.clear();
  crlf_ = false;
  std::string_view chunk = bytes_.buffered();
  if (chunk.empty()) return false;
  ++number_;
  // Past max_line_ the line is only counted (a hostile one may be a gigabyte), keeping one more
  // character for a '\r' that ends it.
  std::uintmax_t length = 0;
  bool ended = false;
  for (; !chunk.empty() && !ended; chunk = bytes_.buffered()) {
    const std::size_t end = std::min(chunk.find('\n'), chunk.size());
    ended = end < chunk.size();
    const std::size_t room = max_line_ + 1 - std::min(line_.size(), max_line_ + 1);
    line_.append(chunk.substr(0, std::min(end, room)));
    length += end;
    bytes_.take(ended ? end + 1 : end);
  }
  if (!line_.empty() && line_.back() == '\r' && length <= max_line_ + 1) {
    line_.pop_back();
    --length;
    crlf_ = ended;
  }
  checkLine(length);
  return true;
}

void TextLines::checkLine(std::uintmax_t length) {
  if (length > max_line_) {
    line_ = line_.substr(0, 77) + "…";  // 80 bytes: quoted as it is, not with its cut length
    fail("is " + std::to_string(length) + " characters long",
         "at most " + std::to_string(max_line_));
  }
  const auto control = std::find_if(line_.begin(), line_.end(), [](char c) {
    return static_cast<unsigned char>(c) < 0x20 && c != '\t';
  });
  if (control != line_.end()) {
    const auto byte = static_cast<unsigned char>(*control);
    line_.erase(control, line_.end());  // quoted up to the character, not with it
    line_ += "…";
    fail("holds the control character " + byteName(byte) + " at the '…'",
         "text (assimp would end the line there)");
  }
}

std::string TextLines::where() const {
  return "line " + std::to_string(number_) + label_ + " ('" + clipForMessage(line_) + "')";
}

void TextLines::fail(const std::string& what, const std::string& expected) const {
  failMesh(path_, where() + " " + what + "; expected " + expected);
}

std::string head(const std::filesystem::path& path, std::size_t n) {
  std::ifstream in(path, std::ios::binary);
  std::string text(n, '\0');
  in.read(text.data(), static_cast<std::streamsize>(n));
  text.resize(static_cast<std::size_t>(in.gcount()));
  return text;
}

bool isDigit(char c) { return c >= '0' && c <= '9'; }

bool isDigits(std::string_view s) { return !s.empty() && std::all_of(s.begin(), s.end(), isDigit); }

void splitWords(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  std::size_t i = 0;
  while ((i = line.find_first_not_of(" \t", i)) != std::string_view::npos) {
    const std::size_t end = std::min(line.find_first_of(" \t", i), line.size());
    out.push_back(line.substr(i, end - i));
    i = end;
  }
}

std::vector<std::string_view> words(std::string_view line) {
  std::vector<std::string_view> out;
  splitWords(line, out);
  return out;
}

namespace {

// --- STL and OBJ: their triangles, counted before reading --------------------------------------

// A binary STL is the size its count says (assimp's test); an ASCII one makes a triangle of
// every three `vertex` words, up to a NUL byte (assimp reads the text as a C string). Words are
// read as assimp reads them, separated by white space, the name after `solid` and `endsolid`
// skipped (it may hold any word). A facet runs from `facet` to `endfacet` (or, that missing,
// to the next `facet`, `endsolid` or the end) and must hold three vertices: assimp would keep
// three of a polygon's corners and drop the rest.
std::uintmax_t stlTriangles(const std::filesystem::path& path, std::uintmax_t size) {
  const std::string start = head(path, 84);
  if (start.size() == 84) {
    std::uint32_t count = 0;
    std::memcpy(&count, start.data() + 80, sizeof count);
    if (std::uintmax_t{count} * 50 + 84 == size) return count;
  }
  FileBytes bytes(path, size, 0);
  std::uintmax_t vertices = 0, in_facet = 0, line = 1, facet_line = 1;
  std::string word;  // up to 9 bytes: longer than any keyword
  bool name = false;
  const auto endFacet = [&](std::uintmax_t at) {
    if (in_facet != 3) {
      failMesh(path, "line " + std::to_string(at) + ": a facet with " + std::to_string(in_facet) +
                         " vertices; expected 3 (an STL facet is a triangle)");
    }
    in_facet = 0;
  };
  const auto endWord = [&] {
    if (word == "vertex") ++vertices, ++in_facet;
    if (word == "endfacet") endFacet(line);
    if ((word == "facet" || word == "endsolid") && in_facet > 0) endFacet(facet_line);
    if (word == "facet") facet_line = line;
    name = name || word == "solid" || word == "endsolid";
    word.clear();
  };
  for (char c = 0; bytes.peek(c) && c != '\0'; bytes.take()) {
    if (isLineEnd(c) || isBlank(c)) {
      if (!name) endWord();
      if (c == '\n') ++line, name = false;
    } else if (!name && word.size() < 9) {
      word += c;
    }
  }
  if (!name) endWord();
  if (in_facet > 0) endFacet(facet_line);
  return vertices / 3;
}

// A material library an OBJ names (`mtllib`), which assimp opens beside it: a regular file of
// at most kMaxMeshBytes, or none (assimp then goes without materials). A pipe would block the
// read, a device or a huge file would fill the memory.
void checkMaterialLibrary(const std::filesystem::path& obj, const std::string& name) {
  if (name.empty()) return;
  const std::filesystem::path library = obj.parent_path() / name;
  std::error_code ec;
  const auto status = std::filesystem::status(library, ec);
  if (!std::filesystem::exists(status)) return;
  if (!std::filesystem::is_regular_file(status)) {
    failMesh(obj, "names the material library '" + clipForMessage(name) +
                      "' (mtllib), which is not a regular file (a folder, pipe or device); "
                      "expected a .mtl file or none");
  }
  const std::uintmax_t size = std::filesystem::file_size(library, ec);
  if (!ec && size > kMaxMeshBytes) {
    failMesh(obj, "names the material library '" + clipForMessage(name) + "' (mtllib) of " +
                      std::to_string(size >> 20) + " MB; expected at most " +
                      std::to_string(kMaxMeshBytes >> 20) + " MB");
  }
}

// An OBJ face line (`f` and n vertices) makes n − 2 triangles. (A face continued over lines with
// '\' counts short; loadMesh counts again after reading.) Every `mtllib` it names is checked.
std::uintmax_t objTriangles(const std::filesystem::path& path, std::uintmax_t size) {
  constexpr std::size_t kMaxName = 4096;
  FileBytes bytes(path, size, 0);
  std::uintmax_t triangles = 0, words = 0;
  std::string first, rest;  // the line's first word (up to 8 bytes); an mtllib's names
  bool in_word = false;
  const auto endLine = [&] {
    if (first == "f" && words >= 4) triangles += words - 3;
    if (first == "mtllib") {
      std::istringstream names(rest);
      for (std::string name; names >> name;) checkMaterialLibrary(path, name);
    }
    words = 0;
    first.clear();
    rest.clear();
    in_word = false;
  };
  for (char c = 0; bytes.peek(c) && c != '\0'; bytes.take()) {
    if (isLineEnd(c)) {
      endLine();
      continue;
    }
    if (first == "mtllib" && words >= 1 && rest.size() < kMaxName) rest += c;
    if (isBlank(c)) {
      in_word = false;
    } else {
      if (!in_word) ++words;
      in_word = true;
      if (words == 1 && first.size() < 8) first += c;
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
  const std::uintmax_t triangles = ext == ".off"   ? checkOff(path, size)
                                   : ext == ".ply" ? checkPly(path, size)
                                   : ext == ".stl" ? stlTriangles(path, size)
                                                   : objTriangles(path, size);
  if (triangles > kMaxMeshTriangles) {
    failMesh(path, "has " + std::to_string(triangles) + " triangles (counted before reading it); " +
                       "expected at most " + std::to_string(kMaxMeshTriangles) +
                       " (simplify the mesh)");
  }
  // assimp's reading, triangulating and welding peak at about 600 bytes a triangle (a 4 M
  // triangle STL: 2.3 GB).
  constexpr double kLoadBytesPerTriangle = 600.0;
  const double need = kLoadBytesPerTriangle * static_cast<double>(triangles);
  const std::size_t available = availableMemoryBytes();
  if (need > static_cast<double>(available)) {
    failMesh(path, "has " + std::to_string(triangles) + " triangles, which take about " +
                       megabytes(need) + " to load, over the " +
                       megabytes(static_cast<double>(available)) +
                       " this process can still allocate (free memory, ulimit -v); expected a "
                       "smaller mesh or more memory");
  }
}

}  // namespace scanplan::kinematics::detail
