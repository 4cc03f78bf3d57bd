#include "voca/config/config.h"

#include <fmt/core.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "voca/config/builtin_configs.h"
#include "voca/core/error.h"

namespace voca {

namespace {

using json = nlohmann::json;

void requireObject(const json& value, const std::string& context) {
  if (!value.is_object())
    throw InputError(fmt::format("{}: expected a JSON object, got {}", context, value.type_name()));
}

int readInt(const json& value, const std::string& key) {
  if (!value.is_number_integer()) throw InputError(fmt::format("{}: expected an integer, got {}", key, value.dump()));
  const auto v = value.get<std::int64_t>();
  if (v < -1'000'000'000 || v > 1'000'000'000) throw InputError(fmt::format("{}: integer out of range: {}", key, v));
  return static_cast<int>(v);
}

double readReal(const json& value, const std::string& key) {
  if (!value.is_number()) throw InputError(fmt::format("{}: expected a number, got {}", key, value.dump()));
  return value.get<double>();
}

bool readBool(const json& value, const std::string& key) {
  if (!value.is_boolean()) throw InputError(fmt::format("{}: expected true or false, got {}", key, value.dump()));
  return value.get<bool>();
}

std::string readString(const json& value, const std::string& key) {
  if (!value.is_string()) throw InputError(fmt::format("{}: expected a string, got {}", key, value.dump()));
  return value.get<std::string>();
}

}  // namespace

FrontendConfig parseFrontendConfig(const json& section, const std::string& context) {
  requireObject(section, context);
  FrontendConfig c;
  for (const auto& [key, value] : section.items()) {
    const std::string name = context + "." + key;
    if (key == "grid_size_px") {
      c.grid_size_px = readInt(value, name);
    } else if (key == "pyramid_levels") {
      c.pyramid_levels = readInt(value, name);
    } else if (key == "max_iterations") {
      c.max_iterations = readInt(value, name);
    } else if (key == "pattern") {
      c.pattern = readInt(value, name);
    } else if (key == "max_recovered_dist2_px2") {
      c.max_recovered_dist2_px2 = readReal(value, name);
    } else if (key == "epipolar_error") {
      c.epipolar_error = readReal(value, name);
    } else if (key == "matching_guess") {
      const std::string text = readString(value, name);
      const auto guess = parseStereoGuess(text);
      if (!guess) {
        throw InputError(
            fmt::format("{}: expected \"reproj_fixed_depth\" or \"reproj_avg_depth\", got \"{}\"", name, text));
      }
      c.matching_guess = *guess;
    } else if (key == "matching_default_depth_m") {
      c.matching_default_depth_m = readReal(value, name);
    } else if (key == "image_safe_radius_px") {
      c.image_safe_radius_px = readReal(value, name);
    } else if (key == "detection_max_threshold") {
      c.detection_max_threshold = readInt(value, name);
    } else if (key == "detection_min_threshold") {
      c.detection_min_threshold = readInt(value, name);
    } else if (key == "detection_border_px") {
      c.detection_border_px = readInt(value, name);
    } else if (key == "prior_mode") {
      const std::string text = readString(value, name);
      const auto mode = parsePriorMode(text);
      if (!mode) {
        throw InputError(fmt::format("{}: expected one of {}, got \"{}\"", name, priorModeList(), text));
      }
      c.prior_mode = *mode;
    } else if (key == "consensus_tolerance_px2") {
      c.consensus_tolerance_px2 = readReal(value, name);
    } else if (key == "bridge_iframes") {
      c.bridge_iframes = readBool(value, name);
    } else if (key == "detection_nonoverlap") {
      c.detection_nonoverlap = readBool(value, name);
    } else if (key == "presmooth") {
      c.presmooth = readBool(value, name);
    } else {
      throw InputError(fmt::format(
          "{}: unknown key (known: grid_size_px, pyramid_levels, max_iterations, pattern, max_recovered_dist2_px2, "
          "epipolar_error, matching_guess, matching_default_depth_m, image_safe_radius_px, detection_max_threshold, "
          "detection_min_threshold, detection_border_px, prior_mode, consensus_tolerance_px2, bridge_iframes, "
          "detection_nonoverlap, presmooth)",
          name));
    }
  }
  validateFrontendConfig(c, context);
  return c;
}

VocaConfig parseConfig(const json& root, const std::string& context) {
  requireObject(root, context);
  VocaConfig config;
  for (const auto& [key, value] : root.items()) {
    if (key == "frontend") {
      config.frontend = parseFrontendConfig(value, context + ": frontend");
    } else if (key == "backend") {
      config.backend = parseBackendConfig(value, context + ": backend");
    } else {
      throw InputError(fmt::format("{}: unknown top-level key \"{}\" (known: frontend, backend)", context, key));
    }
  }
  return config;
}

VocaConfig builtinConfig(const std::string& name) {
  std::string known;
  for (const BuiltinConfig& config : builtinConfigs()) {
    if (config.name == name) return parseConfig(json::parse(config.json), fmt::format("built-in config '{}'", name));
    known += fmt::format("{}{}", known.empty() ? "" : ", ", config.name);
  }
  throw InputError(fmt::format("unknown built-in config '{}' (shipped: {})", name, known));
}

VocaConfig loadConfig(const std::filesystem::path& file_or_name) {
  const std::string& text_name = file_or_name.native();
  if (!std::filesystem::exists(file_or_name) && !file_or_name.has_extension() && !file_or_name.has_parent_path()) {
    return builtinConfig(text_name);
  }
  std::ifstream in(file_or_name);
  if (!in) throw InputError(fmt::format("{}: cannot open the config file", file_or_name.string()));
  std::stringstream text;
  text << in.rdbuf();
  json root;
  try {
    root = json::parse(text.str());
  } catch (const json::parse_error& e) {
    throw InputError(fmt::format("{}: not valid JSON: {}", file_or_name.string(), e.what()));
  }
  return parseConfig(root, file_or_name.string());
}

}  // namespace voca
