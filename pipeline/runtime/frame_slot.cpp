#include "pipeline/runtime/frame_slot.h"

namespace voca::pipeline {

void FrameSlot::reserve(int width, int height, int max_points, int max_landmarks) {
  for (GrayImage& image : raw.images) image.reserve(width, height);
  // A compressed picture is almost always smaller than the raw 4:2:0 one; reserving that much means
  // the packet buffers never grow after start (a rarer larger packet still fits, by one reallocation).
  const std::size_t raw_picture = static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3 / 2;
  for (decode::Packet& packet : encoded.packets) packet.bytes.reserve(raw_picture);
  frame.reserve(width, height);
  tracked.reserve(static_cast<std::size_t>(max_points));
  frontend_stats.reserve(static_cast<std::size_t>(max_points));
  left_traces.reserve(static_cast<std::size_t>(max_points));
  landmarks_world.reserve(static_cast<std::size_t>(max_landmarks));
}

}  // namespace voca::pipeline
