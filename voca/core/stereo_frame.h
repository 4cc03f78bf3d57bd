#pragma once
// The frontend's input: one decoded (or raw) stereo frame with each camera's motion field
// (DESIGN.md section 2, "DecodedStereoFrame").

#include <array>
#include <cstdint>

#include "voca/core/image.h"
#include "voca/motion/motion_field.h"

namespace voca {

// Both cameras' images of one instant, with the codec's motion where the frames were decoded from
// video. Buffers are sized once (reserve) and reused, so filling a frame in steady state does not
// allocate. t_ns and frame_index are stamped by the source and never rewritten downstream.
struct DecodedStereoFrame {
  static constexpr int kNumCameras = 2;

  std::int64_t t_ns = 0;         // sensor time
  std::int64_t frame_index = 0;  // position in the source, from 0
  std::array<GrayImage, kNumCameras> images;
  // Per camera: the picture type the decoder reported and, for inter pictures, the block vectors.
  // Raw images have kUnknown pictures and no vectors.
  std::array<MotionField, kNumCameras> motion;
  bool has_motion = false;  // decoded from video with motion export: the prior modes are active
  bool decoded = false;     // the images came out of a video decoder (the codec has smoothed them)
  // Frames of the source between the previous frame the frontend saw and this one that never
  // reached it (dropped by the live policy, or damaged and skipped). The motion vectors of this
  // frame point into a picture the tracker has not seen when this is non-zero.
  int frames_missing_before = 0;
  // Mean landmark depth the backend estimated for an earlier frame (a fixed number of frames back,
  // so results never depend on thread timing); 0 when there is none yet.
  double depth_hint_m = 0.0;

  void reserve(int max_width, int max_height) {
    for (int c = 0; c < kNumCameras; ++c) {
      images[static_cast<std::size_t>(c)].reserve(max_width, max_height);
      if (motion[static_cast<std::size_t>(c)].maxWidth() < max_width ||
          motion[static_cast<std::size_t>(c)].maxHeight() < max_height) {
        motion[static_cast<std::size_t>(c)] = MotionField(max_width, max_height);
      }
    }
  }
};

}  // namespace voca
