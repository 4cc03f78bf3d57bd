#pragma once
// Reads a JSON config through its ConfigField table: a section of the VOCA config ("frontend",
// "backend") or a whole file with nested sections (a benchmark suite). The errors are the same for
// every table: "<key path>: unknown key (known: ...)", "...: expected an integer / a number / true or
// false / a string / a non-empty array of strings, got <value>", a ranged number outside its range,
// and "...: expected <the names>, got "x"" for a choice naming no value. Key paths name the file and
// the key: "x.json: backend.max_frames", "suite.json: sequences[0].name".

#include <fmt/core.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <span>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "voca/config/config_field.h"
#include "voca/core/error.h"

namespace voca {

// Reads a whole JSON file. Every way the text can fail (syntax, a number too large for a double,
// invalid UTF-8) is an InputError "<file>: not valid JSON: ..."; a missing file is "<file>: cannot
// open the <what>". A key given twice in one object is an InputError too: JSON parsers keep one of
// the two silently, so a second "frontend" section would replace the first.
inline nlohmann::json readJsonFile(const std::filesystem::path& file, const std::string& what) {
  std::ifstream in(file);
  if (!in) throw InputError(fmt::format("{}: cannot open the {}", file.string(), what));
  std::vector<std::set<std::string>> open_objects;  // the keys seen in each object being read
  const nlohmann::json::parser_callback_t reject_duplicate_keys = [&](int, nlohmann::json::parse_event_t event,
                                                                      nlohmann::json& parsed) {
    using Event = nlohmann::json::parse_event_t;
    if (event == Event::object_start) {
      open_objects.emplace_back();
    } else if (event == Event::object_end) {
      open_objects.pop_back();
    } else if (event == Event::key && !open_objects.back().insert(parsed.get<std::string>()).second) {
      throw InputError(fmt::format("{}: key \"{}\" appears twice in one object; merge the two", file.string(),
                                   parsed.get<std::string>()));
    }
    return true;
  };
  try {
    return nlohmann::json::parse(in, reject_duplicate_keys);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: not valid JSON: {}", file.string(), e.what()));
  }
}

// Integers a config may hold when its field gives no range of its own (keeps the cast to int safe).
inline constexpr std::int64_t kConfigIntLimit = 1'000'000'000;

// One value of a config file and the folder of that file, against which relative paths resolve. The
// readers throw InputError "<where>: expected ..., got <value>" like the table's own keys.
class ConfigValue {
 public:
  ConfigValue(const nlohmann::json& json, std::filesystem::path base_dir)
      : json_(&json), base_dir_(std::move(base_dir)) {}

  const nlohmann::json& json() const { return *json_; }
  const std::filesystem::path& baseDir() const { return base_dir_; }

  std::string string(const std::string& where) const {
    if (!json_->is_string()) throw InputError(fmt::format("{}: expected a string, got {}", where, json_->dump()));
    return json_->get<std::string>();
  }

  bool boolean(const std::string& where) const {
    if (!json_->is_boolean()) throw InputError(fmt::format("{}: expected true or false, got {}", where, json_->dump()));
    return json_->get<bool>();
  }

  std::vector<std::string> strings(const std::string& where) const {
    if (!json_->is_array() || json_->empty()) {
      throw InputError(fmt::format("{}: expected a non-empty array of strings, got {}", where, json_->dump()));
    }
    std::vector<std::string> result;
    forEachItem(where, [&](const ConfigValue& item, const std::string& at) { result.push_back(item.string(at)); });
    return result;
  }

  // A path as written in the file: absolute, or relative to the file's folder.
  std::filesystem::path path(const std::string& where) const {
    const std::filesystem::path written(string(where));
    return (written.is_absolute() ? written : base_dir_ / written).lexically_normal();
  }

  // Calls visit(item, "<where>[i]") for each item of a non-empty array.
  template <class Visit>
  void forEachItem(const std::string& where, Visit&& visit) const {
    if (!json_->is_array() || json_->empty()) {
      throw InputError(fmt::format("{}: expected a non-empty array, got {}", where, json_->dump()));
    }
    for (std::size_t i = 0; i < json_->size(); ++i) {
      visit(ConfigValue((*json_)[i], base_dir_), fmt::format("{}[{}]", where, i));
    }
  }

  // A nested section read through its own table; its keys are "<where>.<key>".
  template <class Config>
  void readSection(const std::string& where, std::span<const ConfigField<Config>> fields, Config& config) const;

 private:
  const nlohmann::json* json_;
  std::filesystem::path base_dir_;
};

namespace config_detail {

// Reads the object `value` key by key through `fields`; keyPath(key) names a key in errors.
template <class Config, class KeyPath>
void readKeys(const ConfigValue& value, const std::string& where, KeyPath keyPath,
              std::span<const ConfigField<Config>> fields, Config& config) {
  if (!value.json().is_object()) {
    throw InputError(fmt::format("{}: expected a JSON object, got {}", where, value.json().type_name()));
  }
  for (auto item = value.json().begin(); item != value.json().end(); ++item) {
    const std::string& name = item.key();
    const ConfigValue field_value(item.value(), value.baseDir());
    const nlohmann::json& json = item.value();
    const ConfigField<Config>* field = nullptr;
    for (const ConfigField<Config>& candidate : fields) {
      if (candidate.name == name) field = &candidate;
    }
    const std::string at = keyPath(name);
    if (field == nullptr) {
      throw InputError(fmt::format("{}: unknown key (known: {})", at, configFieldNames(fields)));
    }
    if (const auto* as_int = std::get_if<int Config::*>(&field->target)) {
      if (!json.is_number_integer()) throw InputError(fmt::format("{}: expected an integer, got {}", at, json.dump()));
      const auto v = json.get<std::int64_t>();
      checkConfigRangeAt(*field, static_cast<double>(v), at);
      if (v < -kConfigIntLimit || v > kConfigIntLimit) {
        throw InputError(fmt::format("{}: integer out of range: {}", at, v));
      }
      config.*(*as_int) = static_cast<int>(v);
    } else if (const auto* as_double = std::get_if<double Config::*>(&field->target)) {
      if (!json.is_number()) throw InputError(fmt::format("{}: expected a number, got {}", at, json.dump()));
      checkConfigRangeAt(*field, json.get<double>(), at);
      config.*(*as_double) = json.get<double>();
    } else if (const auto* as_bool = std::get_if<bool Config::*>(&field->target)) {
      config.*(*as_bool) = field_value.boolean(at);
    } else if (const auto* as_string = std::get_if<std::string Config::*>(&field->target)) {
      config.*(*as_string) = field_value.string(at);
    } else if (const auto* as_strings = std::get_if<std::vector<std::string> Config::*>(&field->target)) {
      config.*(*as_strings) = field_value.strings(at);
    } else if (const auto* choice = std::get_if<ConfigChoice<Config>>(&field->target)) {
      const std::string text = field_value.string(at);
      if (!choice->assign(config, text)) {
        throw InputError(fmt::format("{}: expected {}, got \"{}\"", at, choice->expected(), text));
      }
    } else {
      std::get<ConfigReader<Config>>(field->target).read(config, field_value, at);
    }
  }
}

}  // namespace config_detail

// A section named `context` (e.g. "x.json: frontend"); its keys are "<context>.<key>". Relative
// paths in it resolve against `base_dir`.
template <class Config>
void readConfigSection(const nlohmann::json& section, const std::string& context,
                       std::span<const ConfigField<Config>> fields, Config& config,
                       const std::filesystem::path& base_dir = {}) {
  config_detail::readKeys(
      ConfigValue(section, base_dir), context, [&](const std::string& key) { return context + "." + key; }, fields,
      config);
}

// The top level of the file named `file`; its keys are "<file>: <key>". Relative paths in it resolve
// against `base_dir`, normally the file's folder.
template <class Config>
void readConfigFile(const nlohmann::json& root, const std::string& file, std::span<const ConfigField<Config>> fields,
                    Config& config, const std::filesystem::path& base_dir) {
  config_detail::readKeys(
      ConfigValue(root, base_dir), file, [&](const std::string& key) { return file + ": " + key; }, fields, config);
}

template <class Config>
void ConfigValue::readSection(const std::string& where, std::span<const ConfigField<Config>> fields,
                              Config& config) const {
  readConfigSection(*json_, where, fields, config, base_dir_);
}

}  // namespace voca
