#include <scanplan/kinematics/error.h>

#include <cstdint>
#include <cstdio>

namespace scanplan {

namespace {

// Code points a terminal prints as nothing, or as a plain space: C1 controls, the no-break and
// other typographic spaces, zero-width characters, direction marks and controls, the word
// joiner and invisible operators, the ideographic space, the byte-order mark, interlinear
// annotation marks and tag characters.
bool invisible(std::uint32_t c) {
  return (c >= 0x80 && c <= 0xA0) || c == 0xAD || c == 0x34F || c == 0x61C || c == 0x115F ||
         c == 0x1160 || c == 0x180E || (c >= 0x2000 && c <= 0x200F) ||
         (c >= 0x2028 && c <= 0x202F) || (c >= 0x205F && c <= 0x206F) || c == 0x3000 ||
         c == 0x3164 || c == 0xFEFF || (c >= 0xFFF9 && c <= 0xFFFB) ||
         (c >= 0xE0000 && c <= 0xE007F);
}

std::string hexByte(unsigned char b) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "\\x%02X", static_cast<unsigned>(b));
  return buf;
}

// The length of the UTF-8 sequence starting at text[i] and its code point; 0 when the bytes there
// are not well-formed UTF-8 (overlong forms, surrogates and values past U+10FFFF included).
std::size_t decodeUtf8(const std::string& text, std::size_t i, std::uint32_t& c) {
  const auto at = [&](std::size_t k) { return static_cast<unsigned char>(text[i + k]); };
  const unsigned char b = at(0);
  std::size_t n = 0;
  if (b >= 0xC2 && b <= 0xDF) {
    n = 2, c = b & 0x1Fu;
  } else if (b >= 0xE0 && b <= 0xEF) {
    n = 3, c = b & 0x0Fu;
  } else if (b >= 0xF0 && b <= 0xF4) {
    n = 4, c = b & 0x07u;
  } else {
    return 0;
  }
  if (i + n > text.size()) return 0;
  for (std::size_t k = 1; k < n; ++k) {
    if ((at(k) & 0xC0u) != 0x80u) return 0;
    c = (c << 6) | (at(k) & 0x3Fu);
  }
  const bool overlong = (n == 3 && c < 0x800) || (n == 4 && c < 0x10000);
  const bool outside = (c >= 0xD800 && c <= 0xDFFF) || c > 0x10FFFF;
  return overlong || outside ? 0 : n;
}

}  // namespace

std::string visibleText(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    const auto b = static_cast<unsigned char>(text[i]);
    if (b == '\n' || (b >= 0x20 && b < 0x7F)) {
      out += static_cast<char>(b);
      ++i;
    } else if (b == '\r' || b == '\t') {
      out += b == '\r' ? "\\r" : "\\t";
      ++i;
    } else if (b < 0x80) {
      out += hexByte(b);  // other C0 controls and DEL
      ++i;
    } else if (std::uint32_t c = 0; const std::size_t n = decodeUtf8(text, i, c)) {
      if (invisible(c)) {
        char buf[16];
        std::snprintf(buf, sizeof buf, "<U+%04X>", static_cast<unsigned>(c));
        out += buf;
      } else {
        out.append(text, i, n);
      }
      i += n;
    } else {
      out += hexByte(b);
      ++i;
    }
  }
  return out;
}

}  // namespace scanplan
