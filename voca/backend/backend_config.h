#pragma once
// Parameters of the sliding-window VO backend (the JSON "backend" section; defaults are the paper's
// EuRoC values, Basalt's config.vio_* keys).

#include <string>

namespace voca {

// Compile-time bound on the window (keyframes + the newest frame), so the reduced camera system is
// a fixed-size matrix and never touches the heap.
inline constexpr int kMaxWindowFrames = 10;

struct BackendConfig {
  // Window and keyframes.
  int max_keyframes = 7;        // vio_max_kfs (at most kMaxWindowFrames - 1)
  int min_frames_after_kf = 1;  // vio_min_frames_after_kf
  // A keyframe at least every this many frames (0 = only when tracks need one, as Basalt). Where
  // tracks live long (flying backwards, a slow pan) the window's keyframes would otherwise grow old
  // while every new frame hangs on landmarks fixed in them by tracks that drift with each frame.
  int max_frames_after_kf = 0;
  double new_kf_keypoints_thresh = 0.8;  // vio_new_kf_keypoints_thresh: keyframe when connected / tracked < this
  double kf_marg_feature_ratio = 0.2;    // vio_kf_marg_feature_ratio: marginalise a keyframe whose landmarks are lost
  // Landmarks hosted in a marginalised keyframe that the newest frame still tracks: false
  // marginalises them with their host, as Basalt does; true moves them to another keyframe, which
  // keeps them alive but drops their views in the marginalised frame (a pose-only prior cannot hold
  // them), and the window then shifts on the next frame.
  bool rehost_landmarks = false;
  // Residuals.
  double obs_std_dev_px = 0.5;        // vio_obs_std_dev
  double obs_huber_thresh_px = 1.0;   // vio_obs_huber_thresh
  double outlier_threshold_px = 3.0;  // vio_outlier_threshold
  int filter_iteration = 4;           // vio_filter_iteration: outlier filter after this many LM iterations
  // The new frame's observations beyond outlier_threshold_px after the pose-only step are removed
  // only while they are at most this share of the frame's: when more disagree with that pose, the
  // pose is the likelier culprit (a motion the constant-velocity guess missed, a blurred frame), and
  // the window optimisation's filter judges them instead. 1 removes them always (Basalt).
  double max_frame_outlier_share = 0.5;
  // Triangulation.
  double min_triangulation_dist_m = 0.05;  // vio_min_triangulation_dist
  double min_inverse_distance = 1e-3;      // 1/m; farther points carry no translation information
  double max_inverse_distance = 3.0;       // 1/m; Basalt's plausibility bound (closer than 0.33 m is rejected)
  // Optimisation.
  int max_iterations = 7;  // vio_max_iterations
  // LM stops once an accepted step lowers the cost by less than this fraction (converging before
  // filter_iteration runs the outlier filter first, then goes on). 1e-6 runs almost every frame
  // to max_iterations.
  double converged_relative_decrease = 1e-6;
  bool use_lm = true;               // vio_use_lm (false: Gauss-Newton at lm_lambda_initial)
  double lm_lambda_initial = 1e-4;  // vio_lm_lambda_initial
  double lm_lambda_min = 1e-5;      // vio_lm_lambda_min
  double lm_lambda_max = 1e2;       // vio_lm_lambda_max
  double init_pose_weight = 1e8;    // vio_init_pose_weight: prior fixing the first pose
  int pose_only_iterations = 6;     // robust Gauss-Newton steps on the new frame before the window
  // Capacities (fixed memory).
  int max_landmarks = 2000;
  int max_observations_per_camera = 1000;
  // Failure detection and reset.
  int min_inliers = 12;                  // observations of the new frame that must survive
  double max_rms_reprojection_px = 3.0;  // rms error of the new frame's inliers after optimisation
  double max_translation_per_frame_m = 3.0;
  double max_rotation_per_frame_deg = 45.0;
};

// Checks every value against its allowed range; throws InputError naming `context`.<key>, the
// allowed range and the value found.
void validateBackendConfig(const BackendConfig& config, const std::string& context = "backend");

}  // namespace voca
