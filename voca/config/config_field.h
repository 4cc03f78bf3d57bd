#pragma once
// The keys of a config section, listed once per component as a table of ConfigField: the JSON name,
// the struct member it fills and, for numbers, the closed range it must lie in. The one parser
// (config_section.h, with JSON) reads any section through such a table, so every section gives the
// same errors; this header stays free of JSON so a component's public API does not carry it.

#include <fmt/core.h>

#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <variant>

#include "voca/core/error.h"

namespace voca {

// A string key that names one value of a fixed set (an enum member).
template <class Config>
struct ConfigChoice {
  bool (*assign)(Config& config, std::string_view text);  // false: `text` names no value
  std::string (*expected)();  // what the names are, for "expected <this>, got "x"", e.g. "a or b"
};

template <class Config>
struct ConfigField {
  using Target = std::variant<int Config::*, double Config::*, bool Config::*, ConfigChoice<Config>>;

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

// InputError "<context>.<key>: expected a value in [min, max], got v" when a number lies outside its
// field's range (NaN and infinities never pass).
template <class Config>
void checkConfigRange(const ConfigField<Config>& field, double value, const std::string& context) {
  if (!field.hasRange()) return;
  if (!(value >= field.min && value <= field.max) || !std::isfinite(value)) {
    throw InputError(
        fmt::format("{}.{}: expected a value in [{}, {}], got {}", context, field.name, field.min, field.max, value));
  }
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
