#include "pipeline/runtime/frame_slot.h"

namespace voca::pipeline {

void FrameSlot::reserve(int width, int height, int max_points) {
  for (GrayImage& image : raw.images) image.reserve(width, height);
  frame.reserve(width, height);
  tracked.reserve(static_cast<std::size_t>(max_points));
  frontend_stats.reserve(static_cast<std::size_t>(max_points));
  left_traces.reserve(static_cast<std::size_t>(max_points));
}

}  // namespace voca::pipeline
