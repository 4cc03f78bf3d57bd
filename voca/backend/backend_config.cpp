#include "voca/backend/backend_config.h"

#include <fmt/core.h>

#include "voca/backend/backend_config_fields.h"
#include "voca/core/error.h"

namespace voca {

namespace {

using Field = ConfigField<BackendConfig>;

const Field kFields[] = {
    {"max_keyframes", &BackendConfig::max_keyframes, 2, kMaxWindowFrames - 1},
    {"min_frames_after_kf", &BackendConfig::min_frames_after_kf, 0, 1000},
    {"max_frames_after_kf", &BackendConfig::max_frames_after_kf, 0, 100000},
    {"new_kf_keypoints_thresh", &BackendConfig::new_kf_keypoints_thresh, 0.0, 1.0},
    {"kf_marg_feature_ratio", &BackendConfig::kf_marg_feature_ratio, 0.0, 1.0},
    {"rehost_landmarks", &BackendConfig::rehost_landmarks},
    {"obs_std_dev_px", &BackendConfig::obs_std_dev_px, 1e-3, 100.0},
    {"obs_huber_thresh_px", &BackendConfig::obs_huber_thresh_px, 1e-3, 1000.0},
    {"outlier_threshold_px", &BackendConfig::outlier_threshold_px, 1e-3, 1000.0},
    {"filter_iteration", &BackendConfig::filter_iteration, 0, 100},
    {"max_frame_outlier_share", &BackendConfig::max_frame_outlier_share, 0.0, 1.0},
    {"min_triangulation_dist_m", &BackendConfig::min_triangulation_dist_m, 0.0, 100.0},
    {"min_inverse_distance", &BackendConfig::min_inverse_distance, 0.0, 1e3},
    {"max_inverse_distance", &BackendConfig::max_inverse_distance, 1e-6, 1e3},
    {"max_iterations", &BackendConfig::max_iterations, 1, 100},
    {"converged_relative_decrease", &BackendConfig::converged_relative_decrease, 0.0, 1.0},
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

}  // namespace

std::span<const ConfigField<BackendConfig>> backendConfigFields() { return kFields; }

void validateBackendConfig(const BackendConfig& config, const std::string& context) {
  checkConfigRanges(backendConfigFields(), config, context);
  if (config.lm_lambda_min > config.lm_lambda_max) {
    throw InputError(fmt::format("{}.lm_lambda_min: {} must not exceed lm_lambda_max = {}", context,
                                 config.lm_lambda_min, config.lm_lambda_max));
  }
  if (config.min_inverse_distance >= config.max_inverse_distance) {
    throw InputError(fmt::format("{}.min_inverse_distance: {} must be below max_inverse_distance = {}", context,
                                 config.min_inverse_distance, config.max_inverse_distance));
  }
}

}  // namespace voca
