#include "voca/frontend/track_store.h"

namespace voca {

void FreeSlots::resetTo(int count) {
  free_.clear();
  for (int slot = count - 1; slot >= 0; --slot) free_.push_back(slot);
}

void FreeSlots::giveAllTo(FreeSlots& to) {
  to.free_.insert(to.free_.end(), free_.begin(), free_.end());
  free_.clear();
}

TemplateSlots::TemplateSlots(int slot_count, int num_levels)
    : num_levels_(num_levels),
      templates_(static_cast<std::size_t>(slot_count) * static_cast<std::size_t>(num_levels)),
      built_levels_(static_cast<std::size_t>(slot_count), 0) {}

CameraTracks::CameraTracks(int max_points, int extra_slots, int max_width, int max_height, int num_levels,
                           bool can_presmooth)
    : templates(max_points + extra_slots, num_levels) {
  for (ImagePyramid& pyramid : pyramids) pyramid = ImagePyramid(max_width, max_height, num_levels, can_presmooth);
  ids.reserve(static_cast<std::size_t>(max_points));
  points.reserve(static_cast<std::size_t>(max_points));
  slots.reserve(static_cast<std::size_t>(max_points));
  free_slots.reserve(static_cast<std::size_t>(templates.slotCount()));
  clear();
}

void CameraTracks::advance(GrayView image, bool presmooth) {
  current = 1 - current;
  pyramids[static_cast<std::size_t>(current)].build(image, presmooth);
}

void CameraTracks::clear() {
  ids.clear();
  points.clear();
  slots.clear();
  free_slots.resetTo(templates.slotCount());
}

}  // namespace voca
