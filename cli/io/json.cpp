#include "cli/io/json.h"

namespace scanplan::cli {

// nlohmann writes NaN and ±infinity as null. A name or message that is not UTF-8 (a file name
// from the shell) is written with U+FFFD rather than failing the whole output.
std::string jsonDocument(const Json& json) {
  return json.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

std::string jsonLine(const Json& json) {
  return json.dump(-1, ' ', false, Json::error_handler_t::replace) + "\n";
}

}  // namespace scanplan::cli
