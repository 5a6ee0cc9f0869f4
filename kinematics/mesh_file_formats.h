#pragma once
// Internals of the mesh-file pre-check (mesh_file.h), shared by its parts: mesh_file.cpp (the
// file's kind and size, STL and OBJ, the readers below), mesh_file_ply.cpp, mesh_file_off.cpp.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace scanplan::kinematics::detail {

/// A file's bytes from an offset, read in order through a 64 kB buffer.
class FileBytes {
 public:
  /// `size`: the file's size in bytes; `offset`: the first byte to read.
  FileBytes(const std::filesystem::path& path, std::uintmax_t size, std::uintmax_t offset);
  /// The offset of the next byte.
  std::uintmax_t offset() const { return offset_; }
  /// The bytes left after offset().
  std::uintmax_t left() const { return size_ - offset_; }
  /// The bytes buffered from offset() on (read in when none are left); empty at the end.
  std::string_view buffered();
  /// The next byte without taking it; false at the end.
  bool peek(char& c);
  /// Takes `n` of the bytes buffered() gave (peek(): one).
  void take(std::size_t n = 1) {
    pos_ += n;
    offset_ += n;
  }
  /// Takes `n` bytes (at most 8) into `out`; false, taking nothing, when fewer are left.
  bool read(unsigned char* out, std::size_t n);
  /// Skips `n` bytes; false, skipping nothing, when fewer are left.
  bool skip(std::uintmax_t n);

 private:
  bool fill(std::size_t n);

  std::ifstream in_;
  std::vector<char> buffer_;
  std::size_t pos_ = 0, end_ = 0;
  std::uintmax_t offset_, size_;
};

/// The lines of a text file, as assimp's PLY and OFF readers split them where
/// they agree: a line ends at '\n', a '\r' before it is dropped. A line holding any other byte
/// below 0x20 but a tab is refused (assimp ends a line at '\r', '\f' and '\0' too, so the two
/// would read the file differently), and so is one longer than `max_line` characters.
class TextLines {
 public:
  /// `size`: the file's size in bytes.
  TextLines(const std::filesystem::path& path, std::uintmax_t size, std::size_t max_line);
  /// Reads the next line; false at the end of the file.
  bool next();
  const std::filesystem::path& path() const { return path_; }
  std::string_view text() const { return line_; }
  /// The line's number, from 1.
  std::size_t number() const { return number_; }
  /// The offset of the byte after the line's end.
  std::uintmax_t offset() const { return bytes_.offset(); }
  /// Whether the line ended with "\r\n" (not a bare '\n', nor the end of the file).
  bool crlf() const { return crlf_; }
  /// Said after "line N" in messages, e.g. " of its PLY header".
  void setLabel(std::string label) { label_ = std::move(label); }
  /// "line N<label> ('<the line, clipped>')".
  std::string where() const;
  /// Throws the InputError "mesh file '<path>' <where()> <what>; expected <expected>".
  [[noreturn]] void fail(const std::string& what, const std::string& expected) const;

 private:
  void checkLine(std::uintmax_t length);

  const std::filesystem::path& path_;
  FileBytes bytes_;
  std::string line_;
  std::string label_;
  std::size_t number_, max_line_;
  bool crlf_ = false;
};

/// The first `n` bytes of a file (fewer when it is shorter).
std::string head(const std::filesystem::path& path, std::size_t n);
bool isDigit(char c);
/// A non-empty word of decimal digits only.
bool isDigits(std::string_view s);
/// Blank-separated words (spaces and tabs), as assimp's text readers split a line, into `out`.
void splitWords(std::string_view line, std::vector<std::string_view>& out);
std::vector<std::string_view> words(std::string_view line);

/// The triangles a face of `corners` corners makes (none for a point or a line).
inline std::uintmax_t faceTriangles(std::uintmax_t corners) {
  return corners >= 3 ? corners - 2 : 0;
}

/// The PLY check (mesh_file_ply.cpp): the header as the format writes it, then the data walked
/// as declared. Returns the triangles of the face element's corner lists.
std::uintmax_t checkPly(const std::filesystem::path& path, std::uintmax_t size);
/// The OFF check (mesh_file_off.cpp): the header, every vertex line and every face. Returns the
/// faces' triangles.
std::uintmax_t checkOff(const std::filesystem::path& path, std::uintmax_t size);

}  // namespace scanplan::kinematics::detail
