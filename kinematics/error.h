#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

namespace scanplan {

/// The one error type for bad input at a boundary (job file, robot file, mesh, CLI value).
/// The message names the file, the field path, the bad value and what was expected; the app
/// prints it as `scanplan: error: <message>` and exits with the input-error code.
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

/// `text` as quoted in an InputError: at most `n` characters, a longer one cut with "…" and its
/// length (a hostile file's line or value may be megabytes).
inline std::string clipForMessage(const std::string& text, std::size_t n = 80) {
  return text.size() <= n
             ? text
             : text.substr(0, n) + "… (" + std::to_string(text.size()) + " characters)";
}

}  // namespace scanplan
