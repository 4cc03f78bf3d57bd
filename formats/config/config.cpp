#include "formats/config/config.h"

#include <fmt/core.h>

#include <nlohmann/json.hpp>
#include <string_view>

#include "formats/config/builtin_configs.h"
#include "formats/config/config_section.h"
#include "voca/backend/backend_config_fields.h"
#include "voca/core/error.h"

namespace voca {

namespace {

using json = nlohmann::json;
using FrontendField = ConfigField<FrontendConfig>;
using FrontendChoice = ConfigChoice<FrontendConfig>;

// "off", "raw" or "always" (InputScope). true and false are these keys' older form, when they
// applied to every input or none.
template <InputScope FrontendConfig::*kMember>
void readInputScope(FrontendConfig& c, const ConfigValue& value, const std::string& at) {
  const json& v = value.json();
  std::optional<InputScope> scope;
  if (v.is_boolean()) scope = v.get<bool>() ? InputScope::kAlways : InputScope::kOff;
  if (v.is_string()) scope = parseInputScope(v.get<std::string>());
  if (!scope) throw InputError(fmt::format("{}: expected \"off\", \"raw\" or \"always\", got {}", at, v.dump()));
  c.*kMember = *scope;
}

// The frontend's ranges are checked by validateFrontendConfig (open bounds, 24-or-52, relations), so
// its fields carry none.
const FrontendField kFrontendFields[] = {
    {"grid_size_px", &FrontendConfig::grid_size_px},
    {"pyramid_levels", &FrontendConfig::pyramid_levels},
    {"max_iterations", &FrontendConfig::max_iterations},
    {"min_step_px", &FrontendConfig::min_step_px},
    {"coarse_min_step_px", &FrontendConfig::coarse_min_step_px},
    {"pattern", &FrontendConfig::pattern},
    {"max_recovered_dist2_px2", &FrontendConfig::max_recovered_dist2_px2},
    {"stereo_max_recovered_dist2_px2", &FrontendConfig::stereo_max_recovered_dist2_px2},
    {"epipolar_error", &FrontendConfig::epipolar_error},
    {"matching_guess", FrontendChoice{[](FrontendConfig& c, std::string_view text) {
                                        const auto guess = parseStereoGuess(text);
                                        if (guess) c.matching_guess = *guess;
                                        return guess.has_value();
                                      },
                                      [] {
                                        return fmt::format("\"{}\" or \"{}\"",
                                                           stereoGuessName(StereoGuess::kFixedDepth),
                                                           stereoGuessName(StereoGuess::kAverageDepth));
                                      }}},
    {"matching_default_depth_m", &FrontendConfig::matching_default_depth_m},
    {"image_safe_radius_px", &FrontendConfig::image_safe_radius_px},
    {"detection_max_threshold", &FrontendConfig::detection_max_threshold},
    {"detection_min_threshold", &FrontendConfig::detection_min_threshold},
    {"detection_border_px", &FrontendConfig::detection_border_px},
    {"prior_mode", FrontendChoice{[](FrontendConfig& c, std::string_view text) {
                                    const auto mode = parsePriorMode(text);
                                    if (mode) c.prior_mode = *mode;
                                    return mode.has_value();
                                  },
                                  [] { return "one of " + priorModeList(); }}},
    {"consensus_tolerance_px2", &FrontendConfig::consensus_tolerance_px2},
    {"bridge_iframes", &FrontendConfig::bridge_iframes},
    {"prior_reject_inconsistent", &FrontendConfig::prior_reject_inconsistent},
    {"prior_min_block_px", &FrontendConfig::prior_min_block_px},
    {"prior_max_residual_px", &FrontendConfig::prior_max_residual_px},
    {"prior_max_qp", &FrontendConfig::prior_max_qp},
    {"prior_pyramid_levels", &FrontendConfig::prior_pyramid_levels},
    {"backward_pyramid_levels", &FrontendConfig::backward_pyramid_levels},
    {"prior_agree_radius_px", &FrontendConfig::prior_agree_radius_px},
    {"thin_when_full_px", &FrontendConfig::thin_when_full_px},
    {"retry_previous_flow", ConfigReader<FrontendConfig>{&readInputScope<&FrontendConfig::retry_previous_flow>}},
    {"retry_min_lost_fraction", &FrontendConfig::retry_min_lost_fraction},
    {"prior_rescue_min_px", &FrontendConfig::prior_rescue_min_px},
    {"skip_coarse_outside", &FrontendConfig::skip_coarse_outside},
    {"detection_nonoverlap", &FrontendConfig::detection_nonoverlap},
    {"stereo_rematch", &FrontendConfig::stereo_rematch},
    {"presmooth", ConfigReader<FrontendConfig>{&readInputScope<&FrontendConfig::presmooth>}},
};

// The file's top level: one section per component.
const ConfigField<VocaConfig> kConfigSections[] = {
    {"frontend", ConfigReader<VocaConfig>{[](VocaConfig& c, const ConfigValue& value, const std::string& where) {
       c.frontend = parseFrontendConfig(value.json(), where);
     }}},
    {"backend", ConfigReader<VocaConfig>{[](VocaConfig& c, const ConfigValue& value, const std::string& where) {
       c.backend = parseBackendConfig(value.json(), where);
     }}},
};

}  // namespace

FrontendConfig parseFrontendConfig(const json& section, const std::string& context) {
  FrontendConfig config;
  readConfigSection<FrontendConfig>(section, context, kFrontendFields, config);
  validateFrontendConfig(config, context);
  return config;
}

BackendConfig parseBackendConfig(const json& section, const std::string& context) {
  BackendConfig config;
  readConfigSection(section, context, backendConfigFields(), config);
  validateBackendConfig(config, context);
  return config;
}

VocaConfig parseConfig(const json& root, const std::string& context) {
  VocaConfig config;
  readConfigFile<VocaConfig>(root, context, kConfigSections, config, {});
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
  const json root = readJsonFile(file_or_name, "config file");
  return parseConfig(root, file_or_name.string());
}

}  // namespace voca
