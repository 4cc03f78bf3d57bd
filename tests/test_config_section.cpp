// The one config reader (formats/config/config_section.h) on tables of its own: every component's
// table gets the same errors for unknown keys, wrong types, ranges and choices, in sections and in
// whole files with nested sections.

#include <doctest/doctest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

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
  std::string label = "toy";
  std::vector<std::string> tags;
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
    {"label", &ToyConfig::label},
    {"tags", &ToyConfig::tags},
};

// A file with nested sections: a list of toys, each read through the toy table, and a path.
struct ToyFile {
  std::vector<ToyConfig> toys;
  std::filesystem::path data;
};

const voca::ConfigField<ToyFile> kToyFileFields[] = {
    {"toys", voca::ConfigReader<ToyFile>{[](ToyFile& f, const voca::ConfigValue& value, const std::string& where) {
       value.forEachItem(where, [&](const voca::ConfigValue& item, const std::string& item_where) {
         item.readSection<ToyConfig>(item_where, kToyFields, f.toys.emplace_back());
       });
     }}},
    {"data", voca::ConfigReader<ToyFile>{[](ToyFile& f, const voca::ConfigValue& value, const std::string& where) {
       f.data = value.path(where);
     }}},
};

ToyFile readFile(const char* text) {
  ToyFile file;
  voca::readConfigFile<ToyFile>(nlohmann::json::parse(text), "f.json", kToyFileFields, file, "/base/dir");
  return file;
}

std::string fileErrorOf(const char* text) {
  try {
    readFile(text);
  } catch (const voca::InputError& e) {
    return e.what();
  }
  return "";
}

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
  const ToyConfig named = read(R"({"label": "x", "tags": ["a", "b"]})");
  CHECK(named.label == "x");
  CHECK(named.tags == std::vector<std::string>{"a", "b"});
}

TEST_CASE("config section: errors name the file, the key and what was expected") {
  CHECK(errorOf(R"({"cuont": 1})") ==
        "toy.json: toy.cuont: unknown key (known: count, free_int, ratio, enabled, colour, label, tags)");
  CHECK(errorOf(R"({"count": 2.5})") == "toy.json: toy.count: expected an integer, got 2.5");
  CHECK(errorOf(R"({"count": "2"})") == "toy.json: toy.count: expected an integer, got \"2\"");
  CHECK(errorOf(R"({"ratio": "x"})") == "toy.json: toy.ratio: expected a number, got \"x\"");
  CHECK(errorOf(R"({"enabled": 1})") == "toy.json: toy.enabled: expected true or false, got 1");
  CHECK(errorOf(R"({"colour": 3})") == "toy.json: toy.colour: expected a string, got 3");
  CHECK(errorOf(R"({"colour": "blue"})") == "toy.json: toy.colour: expected red or green, got \"blue\"");
  CHECK(errorOf(R"([1])") == "toy.json: toy: expected a JSON object, got array");
  CHECK(errorOf(R"({"label": 1})") == "toy.json: toy.label: expected a string, got 1");
  CHECK(errorOf(R"({"tags": []})") == "toy.json: toy.tags: expected a non-empty array of strings, got []");
  CHECK(errorOf(R"({"tags": ["a", 2]})") == "toy.json: toy.tags[1]: expected a string, got 2");
}

TEST_CASE("config file: nested sections and arrays of them, key paths from the file down, paths relative to it") {
  const ToyFile file = readFile(R"({"toys": [{"count": 5}, {"colour": "green"}], "data": "../seq"})");
  REQUIRE(file.toys.size() == 2);
  CHECK(file.toys[0].count == 5);
  CHECK(file.toys[1].colour == Colour::kGreen);
  CHECK(file.data == std::filesystem::path("/base/seq"));
  CHECK(readFile(R"({"data": "/abs/seq"})").data == std::filesystem::path("/abs/seq"));
  CHECK(fileErrorOf(R"({"toyz": 1})") == "f.json: toyz: unknown key (known: toys, data)");
  CHECK(fileErrorOf(R"({"toys": [{"count": 1}, {"cuont": 1}]})") ==
        "f.json: toys[1].cuont: unknown key (known: count, free_int, ratio, enabled, colour, label, tags)");
  CHECK(fileErrorOf(R"({"toys": [{"count": 0}]})") == "f.json: toys[0].count: expected a value in [1, 10], got 0");
  CHECK(fileErrorOf(R"({"toys": {}})") == "f.json: toys: expected a non-empty array, got {}");
  CHECK(fileErrorOf(R"({"data": 3})") == "f.json: data: expected a string, got 3");
  CHECK(fileErrorOf(R"([])") == "f.json: expected a JSON object, got array");
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
  CHECK(voca::configFieldNames<ToyConfig>(kToyFields) == "count, free_int, ratio, enabled, colour, label, tags");
}
