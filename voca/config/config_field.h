#pragma once
// The keys of a config section, listed once per component as a table of ConfigField: the JSON name,
// the struct member it fills and, for numbers, the closed range it must lie in. The one parser
// (formats/config/config_section.h, with JSON) reads any section of any file (the VOCA config, a
// benchmark suite) through such a table, so every section gives the same errors; this header stays
// free of JSON so a component's public API does not carry it.

#include <fmt/core.h>

#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "voca/core/error.h"

namespace voca {

// One JSON value of a config file, as a ConfigReader sees it; defined with the parser.
class ConfigValue;

// A string key that names one value of a fixed set (an enum member).
template <class Config>
struct ConfigChoice {
  bool (*assign)(Config& config, std::string_view text);  // false: `text` names no value
  std::string (*expected)();  // what the names are, for "expected <this>, got "x"", e.g. "a or b"
};

// A key whose value has structure (a nested section, an array of sections, a path relative to the
// file, a string with its own grammar): read by a function that reports errors at `where`.
template <class Config>
struct ConfigReader {
  void (*read)(Config& config, const ConfigValue& value, const std::string& where);
};

template <class Config>
struct ConfigField {
  // A list of strings must be a non-empty array.
  using Target = std::variant<int Config::*, double Config::*, bool Config::*, std::string Config::*,
                              std::vector<std::string> Config::*, ConfigChoice<Config>, ConfigReader<Config>>;

  std::string_view name;
  Target target;
  // Closed range of a number; the default (infinite) leaves range checks to the component's own
  // validation (relations between keys, open bounds, special values).
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();

  bool hasRange() const { return std::isfinite(min) || std::isfinite(max); }
};

// "a, b, c": the key names of a table, for "unknown key" messages.
template <class Config>
std::string configFieldNames(std::span<const ConfigField<Config>> fields) {
  std::string names;
  for (const ConfigField<Config>& field : fields) {
    if (!names.empty()) names += ", ";
    names += field.name;
  }
  return names;
}

// InputError "<where>: expected a value in [min, max], got v" when a number lies outside its field's
// range (NaN and infinities never pass); `where` is the key's full path, e.g. "x.json: backend.max_frames".
template <class Config>
void checkConfigRangeAt(const ConfigField<Config>& field, double value, const std::string& where) {
  if (!field.hasRange()) return;
  if (!(value >= field.min && value <= field.max) || !std::isfinite(value)) {
    throw InputError(fmt::format("{}: expected a value in [{}, {}], got {}", where, field.min, field.max, value));
  }
}

// The same for a key of the section named `context` ("<context>.<key>").
template <class Config>
void checkConfigRange(const ConfigField<Config>& field, double value, const std::string& context) {
  checkConfigRangeAt(field, value, fmt::format("{}.{}", context, field.name));
}

// Checks every ranged number of `config` against its table, in table order.
template <class Config>
void checkConfigRanges(std::span<const ConfigField<Config>> fields, const Config& config, const std::string& context) {
  for (const ConfigField<Config>& field : fields) {
    if (const auto* as_int = std::get_if<int Config::*>(&field.target)) {
      checkConfigRange(field, static_cast<double>(config.*(*as_int)), context);
    } else if (const auto* as_double = std::get_if<double Config::*>(&field.target)) {
      checkConfigRange(field, config.*(*as_double), context);
    }
  }
}

}  // namespace voca
