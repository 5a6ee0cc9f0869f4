#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

namespace scanplan {

/// `text` with what a terminal would not show made visible: control characters as `\r`, `\t`,
/// `\xNN`; invisible or look-alike code points (a byte-order mark, zero-width and non-breaking
/// spaces, direction marks) as `<U+FEFF>`; bytes that are not UTF-8 as `\xNN`. Line breaks and
/// printable UTF-8 (°, …, ×) stay as they are.
std::string visibleText(const std::string& text);

/// The one error type for bad input at a boundary (job file, robot file, mesh, CLI value).
/// The message names the file, the field path, the bad value and what was expected; the app
/// prints it as `scanplan: error: <message>` and exits with the input-error code.
class InputError : public std::runtime_error {
 public:
  /// The message as given, with invisible characters made visible (visibleText): a value that
  /// differs from a valid one only by a byte-order mark must show the difference.
  explicit InputError(const std::string& message) : std::runtime_error(visibleText(message)) {}
};

/// `text` as quoted in an InputError: at most `n` characters, a longer one cut with "…" and its
/// length (a hostile file's line or value may be megabytes).
inline std::string clipForMessage(const std::string& text, std::size_t n = 80) {
  return text.size() <= n
             ? text
             : text.substr(0, n) + "… (" + std::to_string(text.size()) + " characters)";
}

}  // namespace scanplan
