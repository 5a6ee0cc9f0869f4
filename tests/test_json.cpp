// JSON output (cli/io/json.h): key order, number round trip, non-finite numbers, odd bytes.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli/io/json.h"

namespace scanplan {
namespace {

using cli::Json;

TEST(Json, DocumentKeepsInsertionOrderIndentsAndEndsWithANewline) {
  Json json;
  json["zeta"] = 1;
  json["alpha"] = {{"b", true}, {"a", "x"}};
  EXPECT_EQ(cli::jsonDocument(json),
            "{\n  \"zeta\": 1,\n  \"alpha\": {\n    \"b\": true,\n    \"a\": \"x\"\n  }\n}\n");
  EXPECT_EQ(cli::jsonLine(json), "{\"zeta\":1,\"alpha\":{\"b\":true,\"a\":\"x\"}}\n");
}

TEST(Json, NonFiniteNumbersAreNull) {
  const Json json = {{"nan", std::numeric_limits<double>::quiet_NaN()},
                     {"inf", std::numeric_limits<double>::infinity()},
                     {"-inf", -std::numeric_limits<double>::infinity()}};
  const Json back = Json::parse(cli::jsonLine(json));
  for (const char* key : {"nan", "inf", "-inf"}) EXPECT_TRUE(back.at(key).is_null()) << key;
}

// Every finite double, written and read back, is the same double (bit for bit): random bit
// patterns cover subnormals, huge and tiny exponents and both signs.
TEST(Json, DoublesRoundTripExactly) {
  std::mt19937_64 rng(15);
  for (int i = 0; i < 20000; ++i) {
    const std::uint64_t bits = rng();
    double v = 0.0;
    std::memcpy(&v, &bits, sizeof v);
    if (!std::isfinite(v)) continue;
    const double back = Json::parse(cli::jsonLine(Json(v))).get<double>();
    ASSERT_EQ(std::memcmp(&v, &back, sizeof v), 0) << v << " came back as " << back;
  }
}

TEST(Json, BytesThatAreNotUtf8DoNotFailTheOutput) {
  const Json json = {{"file", std::string("part\xff.stl")}, {"note", "tab\there\n…"}};
  std::string text;
  ASSERT_NO_THROW(text = cli::jsonDocument(json));
  const Json back = Json::parse(text);
  EXPECT_EQ(back.at("file"), "part\xef\xbf\xbd.stl");  // U+FFFD
  EXPECT_EQ(back.at("note"), "tab\there\n…");
}

}  // namespace
}  // namespace scanplan
