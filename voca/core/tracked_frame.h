#pragma once
// The frontend's per-frame output and the backend's input: keypoint observations per camera.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace voca {

// One keypoint seen in one camera. track_id is persistent over time and shared by the left and
// right observation of the same point, so the backend can associate them with a landmark.
struct KeypointObservation {
  std::uint64_t track_id = 0;
  Eigen::Vector2f px = Eigen::Vector2f::Zero();  // pixel position, (0,0) = centre of the top-left pixel
};

// Observations of one stereo frame. The vectors are reserved once (reserve()) and cleared per
// frame, so filling them in steady state does not allocate.
struct TrackedStereoFrame {
  static constexpr int kNumCameras = 2;

  std::int64_t t_ns = 0;
  std::int64_t frame_index = 0;
  // Source frames skipped just before this one (dropped or damaged): the motion since the previous
  // tracked frame spans frames_missing_before + 1 frame intervals.
  int frames_missing_before = 0;
  std::array<std::vector<KeypointObservation>, kNumCameras> observations;

  void reserve(std::size_t max_points) {
    for (auto& camera : observations) camera.reserve(max_points);
  }
  void clear() {
    for (auto& camera : observations) camera.clear();
  }
};

}  // namespace voca
