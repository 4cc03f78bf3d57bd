#pragma once
// What the backend says about each frame: its pose, whether it was tracked, and why not. Kept apart
// from the estimator so that code which only reads estimates (the pipeline's slots, sinks, the
// library API) does not compile the estimator's window, optimiser and Eigen solvers.

#include <cstdint>
#include <string_view>

#include "voca/geometry/se3.h"

namespace voca {

// What the backend says about a frame's pose.
enum class TrackingState : std::uint8_t {
  kTracking,  // estimated in the window
  kReset,     // tracking failed; re-initialised from this frame's stereo at the last good pose
  kLost,      // no estimate possible (too few stereo points to start); the last good pose is repeated
};
std::string_view trackingStateName(TrackingState state);

// Why a frame was not tracked.
enum class FailureReason : std::uint8_t {
  kNone,
  kTooFewInliers,
  kExplodingCost,
  kImpossibleMotion,
  kTooFewStereoPoints
};
std::string_view failureReasonName(FailureReason reason);

// The causal output for one frame, final when returned (later optimisation never changes it).
struct PoseEstimate {
  std::int64_t t_ns = 0;
  std::int64_t frame_index = 0;
  SE3d T_world_cam0;
  SE3d T_world_body;  // T_world_cam0 * T_body_cam0^-1: comparable with the dataset's ground truth
  TrackingState state = TrackingState::kLost;
  FailureReason failure = FailureReason::kNone;
  bool keyframe = false;
  int num_keyframes = 0;
  int num_landmarks = 0;    // alive in the window
  int num_inliers = 0;      // this frame's observations attached to landmarks after outlier removal
  int num_outliers = 0;     // this frame's observations removed as outliers
  int new_landmarks = 0;    // triangulated in this frame (keyframes only)
  int pose_iterations = 0;  // robust steps on this frame's pose alone, before the window
  int lm_iterations = 0;
  int lm_linearizations = 0;         // of the window, in those iterations
  int lm_cost_passes = 0;            // of the window without Jacobians, judging steps expected to converge
  double rms_reprojection_px = 0.0;  // this frame's inliers
  double mean_depth_m = 0.0;         // of the landmarks this frame observes (0 when none)
  double time_ms = 0.0;
};

// Why a frame that was not tracked (state kReset or kLost) was not, for messages: its failure, or
// for a reset that follows lost frames (their failure was reported with them) that tracking started
// again there.
std::string_view untrackedCause(const PoseEstimate& estimate);

}  // namespace voca
