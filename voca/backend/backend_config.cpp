#include "voca/backend/backend_config.h"

#include <fmt/core.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string_view>
#include <variant>

#include "voca/core/error.h"

namespace voca {

namespace {

using json = nlohmann::json;

// One key of the section: where it lives in the struct and its allowed (closed) range.
struct Key {
  std::string_view name;
  std::variant<int BackendConfig::*, double BackendConfig::*, bool BackendConfig::*> member;
  double min = 0.0;
  double max = 0.0;
};

const Key kKeys[] = {
    {"max_keyframes", &BackendConfig::max_keyframes, 2, kMaxWindowFrames - 1},
    {"min_frames_after_kf", &BackendConfig::min_frames_after_kf, 0, 1000},
    {"new_kf_keypoints_thresh", &BackendConfig::new_kf_keypoints_thresh, 0.0, 1.0},
    {"kf_marg_feature_ratio", &BackendConfig::kf_marg_feature_ratio, 0.0, 1.0},
    {"obs_std_dev_px", &BackendConfig::obs_std_dev_px, 1e-3, 100.0},
    {"obs_huber_thresh_px", &BackendConfig::obs_huber_thresh_px, 1e-3, 1000.0},
    {"outlier_threshold_px", &BackendConfig::outlier_threshold_px, 1e-3, 1000.0},
    {"filter_iteration", &BackendConfig::filter_iteration, 0, 100},
    {"min_triangulation_dist_m", &BackendConfig::min_triangulation_dist_m, 0.0, 100.0},
    {"min_inverse_distance", &BackendConfig::min_inverse_distance, 0.0, 1e3},
    {"max_inverse_distance", &BackendConfig::max_inverse_distance, 1e-6, 1e3},
    {"max_iterations", &BackendConfig::max_iterations, 1, 100},
    {"use_lm", &BackendConfig::use_lm},
    {"lm_lambda_initial", &BackendConfig::lm_lambda_initial, 0.0, 1e6},
    {"lm_lambda_min", &BackendConfig::lm_lambda_min, 0.0, 1e6},
    {"lm_lambda_max", &BackendConfig::lm_lambda_max, 0.0, 1e12},
    {"init_pose_weight", &BackendConfig::init_pose_weight, 1.0, 1e16},
    {"pose_only_iterations", &BackendConfig::pose_only_iterations, 0, 100},
    {"max_landmarks", &BackendConfig::max_landmarks, 10, 1000000},
    {"max_observations_per_camera", &BackendConfig::max_observations_per_camera, 10, 1000000},
    {"min_inliers", &BackendConfig::min_inliers, 3, 100000},
    {"max_rms_reprojection_px", &BackendConfig::max_rms_reprojection_px, 1e-3, 1e6},
    {"max_translation_per_frame_m", &BackendConfig::max_translation_per_frame_m, 1e-6, 1e6},
    {"max_rotation_per_frame_deg", &BackendConfig::max_rotation_per_frame_deg, 1e-3, 180.0},
};

std::string knownKeys() {
  std::string names;
  for (const Key& k : kKeys) {
    if (!names.empty()) names += ", ";
    names += k.name;
  }
  return names;
}

void checkRange(const Key& key, double value, const std::string& context) {
  if (!(value >= key.min && value <= key.max) || !std::isfinite(value)) {
    throw InputError(
        fmt::format("{}.{}: expected a value in [{}, {}], got {}", context, key.name, key.min, key.max, value));
  }
}

}  // namespace

void validateBackendConfig(const BackendConfig& config, const std::string& context) {
  for (const Key& key : kKeys) {
    if (const auto* m = std::get_if<int BackendConfig::*>(&key.member)) {
      checkRange(key, static_cast<double>(config.*(*m)), context);
    } else if (const auto* d = std::get_if<double BackendConfig::*>(&key.member)) {
      checkRange(key, config.*(*d), context);
    }
  }
  if (config.lm_lambda_min > config.lm_lambda_max) {
    throw InputError(fmt::format("{}.lm_lambda_min: {} must not exceed lm_lambda_max = {}", context,
                                 config.lm_lambda_min, config.lm_lambda_max));
  }
  if (config.min_inverse_distance >= config.max_inverse_distance) {
    throw InputError(fmt::format("{}.min_inverse_distance: {} must be below max_inverse_distance = {}", context,
                                 config.min_inverse_distance, config.max_inverse_distance));
  }
}

BackendConfig parseBackendConfig(const json& section, const std::string& context) {
  if (!section.is_object()) {
    throw InputError(fmt::format("{}: expected a JSON object, got {}", context, section.type_name()));
  }
  BackendConfig config;
  for (const auto& [name, value] : section.items()) {
    const Key* key = nullptr;
    for (const Key& k : kKeys) {
      if (k.name == name) key = &k;
    }
    const std::string where = context + "." + name;
    if (key == nullptr) throw InputError(fmt::format("{}: unknown key (known: {})", where, knownKeys()));
    if (const auto* m = std::get_if<int BackendConfig::*>(&key->member)) {
      if (!value.is_number_integer())
        throw InputError(fmt::format("{}: expected an integer, got {}", where, value.dump()));
      const auto v = value.get<std::int64_t>();
      checkRange(*key, static_cast<double>(v), context);
      config.*(*m) = static_cast<int>(v);
    } else if (const auto* d = std::get_if<double BackendConfig::*>(&key->member)) {
      if (!value.is_number()) throw InputError(fmt::format("{}: expected a number, got {}", where, value.dump()));
      checkRange(*key, value.get<double>(), context);
      config.*(*d) = value.get<double>();
    } else {
      if (!value.is_boolean()) throw InputError(fmt::format("{}: expected true or false, got {}", where, value.dump()));
      config.*std::get<bool BackendConfig::*>(key->member) = value.get<bool>();
    }
  }
  validateBackendConfig(config, context);
  return config;
}

}  // namespace voca
