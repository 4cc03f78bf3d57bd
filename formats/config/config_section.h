#pragma once
// Reads one JSON config section through its component's ConfigField table. The errors are the same
// for every section: "<context>.<key>: unknown key (known: ...)", "...: expected an integer / a
// number / true or false / a string, got <value>", a ranged number outside its range, and
// "...: expected <the names>, got "x"" for a choice naming no value. `context` names the file and the section, e.g.
// "x.json: backend".

#include <fmt/core.h>

#include <cstdint>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <variant>

#include "voca/config/config_field.h"
#include "voca/core/error.h"

namespace voca {

// Integers a config may hold when its field gives no range of its own (keeps the cast to int safe).
inline constexpr std::int64_t kConfigIntLimit = 1'000'000'000;

template <class Config>
void readConfigSection(const nlohmann::json& section, const std::string& context,
                       std::span<const ConfigField<Config>> fields, Config& config) {
  if (!section.is_object()) {
    throw InputError(fmt::format("{}: expected a JSON object, got {}", context, section.type_name()));
  }
  for (auto item = section.begin(); item != section.end(); ++item) {
    const std::string& name = item.key();
    const nlohmann::json& value = item.value();
    const ConfigField<Config>* field = nullptr;
    for (const ConfigField<Config>& candidate : fields) {
      if (candidate.name == name) field = &candidate;
    }
    const std::string where = context + "." + name;
    if (field == nullptr) {
      throw InputError(fmt::format("{}: unknown key (known: {})", where, configFieldNames(fields)));
    }
    if (const auto* as_int = std::get_if<int Config::*>(&field->target)) {
      if (!value.is_number_integer()) {
        throw InputError(fmt::format("{}: expected an integer, got {}", where, value.dump()));
      }
      const auto v = value.get<std::int64_t>();
      checkConfigRange(*field, static_cast<double>(v), context);
      if (v < -kConfigIntLimit || v > kConfigIntLimit) {
        throw InputError(fmt::format("{}: integer out of range: {}", where, v));
      }
      config.*(*as_int) = static_cast<int>(v);
    } else if (const auto* as_double = std::get_if<double Config::*>(&field->target)) {
      if (!value.is_number()) throw InputError(fmt::format("{}: expected a number, got {}", where, value.dump()));
      checkConfigRange(*field, value.get<double>(), context);
      config.*(*as_double) = value.get<double>();
    } else if (const auto* as_bool = std::get_if<bool Config::*>(&field->target)) {
      if (!value.is_boolean()) throw InputError(fmt::format("{}: expected true or false, got {}", where, value.dump()));
      config.*(*as_bool) = value.get<bool>();
    } else {
      const auto& choice = std::get<ConfigChoice<Config>>(field->target);
      if (!value.is_string()) throw InputError(fmt::format("{}: expected a string, got {}", where, value.dump()));
      const std::string text = value.get<std::string>();
      if (!choice.assign(config, text)) {
        throw InputError(fmt::format("{}: expected {}, got \"{}\"", where, choice.expected(), text));
      }
    }
  }
}

}  // namespace voca
