// The one config-section reader (formats/config/config_section.h) on a section of its own: every
// component's table gets the same errors for unknown keys, wrong types, ranges and choices.

#include <doctest/doctest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "formats/config/config_section.h"
#include "voca/config/config_field.h"
#include "voca/core/error.h"

namespace {

enum class Colour { kRed, kGreen };

struct ToyConfig {
  int count = 3;
  int free_int = 0;
  double ratio = 0.5;
  bool enabled = false;
  Colour colour = Colour::kRed;
};

const voca::ConfigField<ToyConfig> kToyFields[] = {
    {"count", &ToyConfig::count, 1, 10},
    {"free_int", &ToyConfig::free_int},
    {"ratio", &ToyConfig::ratio, 0.0, 1.0},
    {"enabled", &ToyConfig::enabled},
    {"colour", voca::ConfigChoice<ToyConfig>{[](ToyConfig& c, std::string_view text) {
                                               if (text == "red") c.colour = Colour::kRed;
                                               if (text == "green") c.colour = Colour::kGreen;
                                               return text == "red" || text == "green";
                                             },
                                             [] { return std::string("red or green"); }}},
};

ToyConfig read(const char* text) {
  ToyConfig config;
  voca::readConfigSection<ToyConfig>(nlohmann::json::parse(text), "toy.json: toy", kToyFields, config);
  return config;
}

std::string errorOf(const char* text) {
  try {
    read(text);
  } catch (const voca::InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("config section: values land in their members, absent keys keep their defaults") {
  const ToyConfig c = read(R"({"count": 7, "ratio": 0.25, "enabled": true, "colour": "green"})");
  CHECK(c.count == 7);
  CHECK(c.ratio == 0.25);
  CHECK(c.enabled);
  CHECK(c.colour == Colour::kGreen);
  CHECK(c.free_int == 0);
  CHECK(read("{}").count == 3);
  CHECK(read(R"({"ratio": 1})").ratio == 1.0);  // an integer is a valid number
}

TEST_CASE("config section: errors name the file, the key and what was expected") {
  CHECK(errorOf(R"({"cuont": 1})") ==
        "toy.json: toy.cuont: unknown key (known: count, free_int, ratio, enabled, colour)");
  CHECK(errorOf(R"({"count": 2.5})") == "toy.json: toy.count: expected an integer, got 2.5");
  CHECK(errorOf(R"({"count": "2"})") == "toy.json: toy.count: expected an integer, got \"2\"");
  CHECK(errorOf(R"({"ratio": "x"})") == "toy.json: toy.ratio: expected a number, got \"x\"");
  CHECK(errorOf(R"({"enabled": 1})") == "toy.json: toy.enabled: expected true or false, got 1");
  CHECK(errorOf(R"({"colour": 3})") == "toy.json: toy.colour: expected a string, got 3");
  CHECK(errorOf(R"({"colour": "blue"})") == "toy.json: toy.colour: expected red or green, got \"blue\"");
  CHECK(errorOf(R"([1])") == "toy.json: toy: expected a JSON object, got array");
}

TEST_CASE("config section: ranged numbers are checked as read, unranged integers must fit an int") {
  CHECK(errorOf(R"({"count": 11})") == "toy.json: toy.count: expected a value in [1, 10], got 11");
  CHECK(errorOf(R"({"ratio": -0.5})") == "toy.json: toy.ratio: expected a value in [0, 1], got -0.5");
  CHECK(errorOf(R"({"free_int": 5000000000})") == "toy.json: toy.free_int: integer out of range: 5000000000");
  CHECK(read(R"({"free_int": -1000})").free_int == -1000);
}

TEST_CASE("config fields: the range check of a whole struct, in table order") {
  ToyConfig c;
  voca::checkConfigRanges<ToyConfig>(kToyFields, c, "toy");
  c.ratio = 2.0;
  c.count = 0;
  try {
    voca::checkConfigRanges<ToyConfig>(kToyFields, c, "toy");
    FAIL("expected InputError");
  } catch (const voca::InputError& e) {
    CHECK(std::string(e.what()) == "toy.count: expected a value in [1, 10], got 0");
  }
  CHECK(voca::configFieldNames<ToyConfig>(kToyFields) == "count, free_int, ratio, enabled, colour");
}
