#pragma once

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

}  // namespace scanplan
