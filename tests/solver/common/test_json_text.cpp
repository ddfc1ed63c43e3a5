// Strict JSON text for scenes and experiment configs: positions, duplicate keys, number overflow.
#include "softkin/solver/common/json_text.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace softkin {
namespace {

std::string ErrorOf(const std::string& text) {
  try {
    (void)ParseJsonText(text, "c.json");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(JsonText, ReadsValidTextUnchanged) {
  const nlohmann::json j = ParseJsonText(R"({"a": [1, 2.5, {"b": "x"}], "c": null})", "c.json");
  EXPECT_EQ(j, nlohmann::json::parse(R"({"a": [1, 2.5, {"b": "x"}], "c": null})"));
}

TEST(JsonText, SyntaxErrorsGiveLineAndColumn) {
  const std::string m = ErrorOf("{\"a\": 1,\n  \"b\": }");
  EXPECT_EQ(m.rfind("c.json:2:8: invalid JSON: ", 0), 0u) << m;
}

TEST(JsonText, DuplicateKeysNameTheirObject) {
  EXPECT_EQ(ErrorOf(R"({"seed": 1, "seed": 2})"),
            "c.json: duplicate key 'seed'; expected each key once");
  EXPECT_EQ(ErrorOf(R"({"solver": {"tolerance": 1, "tolerance": 2}})"),
            "c.json: solver: duplicate key 'tolerance'; expected each key once");
  // The same key in two different objects is fine.
  EXPECT_EQ(ErrorOf(R"({"a": {"x": 1}, "b": {"x": 1}, "l": [{"x": 1}, {"x": 2}]})"), "");
}

// Numbers beyond double's range used to leak nlohmann's bare message with no file or key.
TEST(JsonText, NumbersOutOfRangeNameTheirKey) {
  const std::string m = ErrorOf(R"({"mesh": {"scale": 1e400}})");
  EXPECT_EQ(m.rfind("c.json: mesh.scale: number overflow", 0), 0u) << m;
  EXPECT_NE(m.find("expected a number within"), std::string::npos) << m;
  const std::string a = ErrorOf(R"({"levels": [0.5, -1e999]})");
  EXPECT_EQ(a.rfind("c.json: levels[1]: number overflow", 0), 0u) << a;
}

}  // namespace
}  // namespace softkin
