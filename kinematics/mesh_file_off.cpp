// OFF. assimp 5.2 (OFFImporter::InternReadFile) reads an OFF file's vertex and face lines into a
// 4 kB buffer on the stack: a longer line writes a byte past it, and its rest is read as the next
// line. It skips a face line whose vertex count is 0 or over 9 by decrementing the mesh's face
// count: more such lines than faces wrap it to 4 billion, and the faces are then read far past
// their array (found by valgrind on the fuzzer's inputs); fewer drop faces without a word (a hole
// in the part). It clamps a face index past the last vertex to the last vertex, reads a negative
// one as 0, and stops without a word where the file ends early. So the header must be the OFF
// keyword and whole-number counts that fit the file, alone on their line; every line at most
// kMaxOffLine characters; every vertex and face line present; and every face a vertex count from
// 1 to 9 followed by as many indices of the file's vertices.

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/mesh_file.h>
#include <scanplan/kinematics/mesh_file_formats.h>

#include <string>
#include <vector>

namespace scanplan::kinematics::detail {
namespace {

struct OffHeader {
  std::uintmax_t vertices = 0, faces = 0;
};

// The next line that is not empty: assimp's line reader takes a run of line ends as one.
bool nextLine(TextLines& lines) {
  while (lines.next()) {
    if (!lines.text().empty()) return true;
  }
  return false;
}

bool isBlankOrComment(std::string_view line) {
  const std::size_t first = line.find_first_not_of(" \t");
  return first == std::string_view::npos || line[first] == '#';
}

// assimp's variants: [ST][C][N][4][n]OFF, 'n' adding a dimension before the counts (`dimension`).
bool isOffKeyword(const std::string& keyword, bool& dimension) {
  std::size_t i = keyword.rfind("ST", 0) == 0 ? 2 : 0;
  for (const char flag : {'C', 'N', '4', 'n'}) {
    if (i < keyword.size() && keyword[i] == flag) ++i;
  }
  dimension = i > 0 && keyword[i - 1] == 'n';
  return keyword.compare(i, std::string::npos, "OFF") == 0;
}

// One header word: the keyword first, then whole numbers. Returns how many words the header has.
std::size_t takeHeaderWord(const TextLines& lines,
                           std::vector<std::string>& header,
                           std::size_t wanted) {
  if (header.size() == 1) {
    bool dimension = false;
    if (!isOffKeyword(header[0], dimension)) {
      lines.fail("does not start with the OFF keyword",
                 "'OFF' (or COFF, NOFF, STOFF, 4OFF, nOFF …)");
    }
    return dimension ? wanted + 1 : wanted;
  }
  if (!isDigits(header.back()) || header.back().size() > 10) {
    lines.fail("has '" + clipForMessage(header.back()) + "' in the OFF header",
               "whole numbers: the vertex, face and edge counts");
  }
  return wanted;
}

// The header as assimp reads it: the keyword, an 'n' variant's dimension, then the vertex, face
// and edge counts; '#' starts a comment, blank lines are skipped. The counts must end their line.
OffHeader readHeader(TextLines& lines) {
  std::vector<std::string> header;
  std::vector<std::string_view> word;
  std::size_t wanted = 4;
  while (header.size() < wanted) {
    if (!nextLine(lines)) {
      failMesh(lines.path(),
               "ends before its OFF header is complete; expected 'OFF', then the vertex, face "
               "and edge counts");
    }
    splitWords(lines.text(), word);
    for (std::size_t w = 0; w < word.size() && word[w][0] != '#'; ++w) {
      if (header.size() == wanted) {
        lines.fail("has more after the edge count",
                   "the vertex, face and edge counts alone on a line (is the edge count missing?)");
      }
      header.emplace_back(word[w]);
      wanted = takeHeaderWord(lines, header, wanted);
    }
  }
  return {std::stoull(header[wanted - 3]), std::stoull(header[wanted - 2])};
}

// Counts above 0 that fit the file: each vertex and face takes a few bytes at least.
void checkCounts(const std::filesystem::path& path, const OffHeader& header, std::uintmax_t size) {
  const auto v = header.vertices, f = header.faces;
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
}

[[noreturn]] void failTruncated(const TextLines& lines,
                                const char* what,
                                std::uintmax_t found,
                                std::uintmax_t declared) {
  failMesh(lines.path(), "has " + std::to_string(found) + " of the " + std::to_string(declared) +
                             " " + what +
                             " its OFF header declares; expected all of them (a truncated file)");
}

// One face line: its vertex count (1 to 9) and that many indices, each a plain number below the
// vertex count. Returns its triangles.
std::uintmax_t checkFace(const TextLines& lines,
                         std::uintmax_t face,
                         std::uintmax_t faces,
                         std::uintmax_t vertices,
                         std::vector<std::string_view>& word) {
  const auto fail = [&](const std::string& what, const std::string& expected) {
    failMesh(lines.path(), lines.where() + ", OFF face " + std::to_string(face + 1) + " of " +
                               std::to_string(faces) + ", " + what + "; expected " + expected);
  };
  const std::string range = "from 0 to " + std::to_string(vertices - 1);
  splitWords(lines.text(), word);
  const bool counted = !word.empty() && isDigits(word[0]) && word[0].size() <= 2;
  const std::uintmax_t n = counted ? std::stoull(std::string(word[0])) : 0;
  if (n < 1 || n > 9) {
    fail("does not start with a face's vertex count from 1 to 9",
         "1 to 9 (assimp's OFF reader drops other faces; triangulate larger ones), then as many "
         "vertex indices");
  }
  if (word.size() - 1 < n) {
    fail("has " + std::to_string(word.size() - 1) + " of its " + std::to_string(n) +
             " vertex indices",
         std::to_string(n) + " indices " + range);
  }
  for (std::size_t k = 1; k <= n; ++k) {
    const std::string index = clipForMessage(std::string(word[k]));
    if (!isDigits(word[k])) fail("has vertex index '" + index + "'", "an index " + range);
    if (word[k].size() > 10 || std::stoull(index) >= vertices) {
      fail("has vertex index " + index + " out of range: the file has " + std::to_string(vertices) +
               " vertices",
           "indices " + range);
    }
  }
  return faceTriangles(n);
}

}  // namespace

std::uintmax_t checkOff(const std::filesystem::path& path, std::uintmax_t size) {
  TextLines lines(path, size, kMaxOffLine);
  const OffHeader header = readHeader(lines);
  checkCounts(path, header, size);
  // Vertex lines start at the first line after the counts that is not blank or a comment.
  for (std::uintmax_t k = 0; k < header.vertices; ++k) {
    do {
      if (!nextLine(lines)) failTruncated(lines, "vertices", k, header.vertices);
    } while (k == 0 && isBlankOrComment(lines.text()));
  }
  std::uintmax_t triangles = 0;
  std::vector<std::string_view> word;
  for (std::uintmax_t k = 0; k < header.faces; ++k) {
    if (!nextLine(lines)) failTruncated(lines, "faces", k, header.faces);
    triangles += checkFace(lines, k, header.faces, header.vertices, word);
  }
  return triangles;
}

}  // namespace scanplan::kinematics::detail
