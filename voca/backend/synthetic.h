#pragma once
// Synthetic backend input with exact ground truth: points in a room observed along a smooth camera
// trajectory through a calibrated stereo rig, tracked the way the frontend tracks (persistent ids,
// at most one new point per grid cell, a new id when a point reappears), with optional pixel noise.

#include <cstdint>
#include <vector>

#include "voca/calib/calibration.h"
#include "voca/core/tracked_frame.h"
#include "voca/geometry/se3.h"

namespace voca {

// How the synthetic sequence is made.
struct SyntheticObservationsConfig {
  double duration_s = 30.0;
  double fps = 20.0;
  int num_points = 3000;
  int max_points_per_frame = 200;  // tracked points in the left image
  int grid_px = 40;                // one new point per empty cell, as the frontend detects
  double noise_px = 0.0;           // Gaussian, per coordinate
  double motion_scale = 1.0;       // scales velocities: 1 = gentle handheld, 3 = fast
  std::uint32_t seed = 1;
};

// Ground truth and observations of every frame.
struct SyntheticObservations {
  std::vector<std::int64_t> t_ns;
  std::vector<SE3d> T_world_body;  // ground truth in the rig's body frame
  std::vector<TrackedStereoFrame> frames;
};

// The camera's pose T_world_cam0 at time t: a loop through a 10 x 8 x 4 m room, turning once in
// 30 s with superimposed sway (smooth, so velocities stay realistic).
SE3d syntheticCameraPose(double t_s, double motion_scale);

SyntheticObservations makeSyntheticObservations(const StereoRig& rig, const SyntheticObservationsConfig& config);

}  // namespace voca
