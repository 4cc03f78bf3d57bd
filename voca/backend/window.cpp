#include "voca/backend/window.h"

#include <algorithm>
#include <stdexcept>

namespace voca::backend {

const Observation* WindowFrame::find(int cam, std::uint64_t id) const {
  const std::vector<Observation>& list = obs[static_cast<std::size_t>(cam)];
  const auto it = std::lower_bound(list.begin(), list.end(), id,
                                   [](const Observation& o, std::uint64_t key) { return o.id < key; });
  return it != list.end() && it->id == id ? &*it : nullptr;
}

Window::Window(int max_observations) : capacity_(static_cast<std::size_t>(std::max(0, max_observations))) {
  for (WindowFrame& f : frames_) {
    for (auto& o : f.obs) o.reserve(capacity_);
  }
}

void Window::clear() {
  for (int i = 0; i < kMaxWindowFrames; ++i) release(i);
}

int Window::add(const TrackedStereoFrame& frame, const SE3d& T_w_c) {
  int slot = -1;
  for (int i = 0; i < kMaxWindowFrames; ++i) {
    if (!frames_[static_cast<std::size_t>(i)].active) {
      slot = i;
      break;
    }
  }
  // The window never holds more than max_keyframes + 1 <= kMaxWindowFrames frames.
  if (slot < 0) throw std::logic_error("VoEstimator: window overflow");
  WindowFrame& f = frames_[static_cast<std::size_t>(slot)];
  f.active = true;
  f.keyframe = false;
  f.in_prior = false;
  f.t_ns = frame.t_ns;
  f.frame_index = frame.frame_index;
  f.sequence = sequence_++;
  f.T_w_c = T_w_c;
  for (std::size_t c = 0; c < 2; ++c) {
    auto& list = f.obs[c];
    list.clear();
    for (const KeypointObservation& o : frame.observations[c]) {
      if (list.size() >= capacity_) break;
      if (!o.px.allFinite()) continue;
      list.push_back({o.track_id, o.px.cast<double>()});
    }
    std::sort(list.begin(), list.end(), [](const Observation& a, const Observation& b) { return a.id < b.id; });
    list.erase(
        std::unique(list.begin(), list.end(), [](const Observation& a, const Observation& b) { return a.id == b.id; }),
        list.end());
  }
  return slot;
}

void Window::release(int slot) {
  WindowFrame& f = frames_[static_cast<std::size_t>(slot)];
  f.active = f.keyframe = f.in_prior = false;
  for (auto& o : f.obs) o.clear();
}

int Window::numKeyframes() const {
  int n = 0;
  for (const WindowFrame& f : frames_) n += f.active && f.keyframe;
  return n;
}

int Window::newest() const {
  int newest = -1;
  for (int g = 0; g < kMaxWindowFrames; ++g) {
    const WindowFrame& fg = frames_[static_cast<std::size_t>(g)];
    if (fg.active && (newest < 0 || fg.sequence > frames_[static_cast<std::size_t>(newest)].sequence)) newest = g;
  }
  return newest;
}

int Window::oldestKeyframe() const {
  int oldest = -1;
  for (int i = 0; i < kMaxWindowFrames; ++i) {
    const WindowFrame& f = frames_[static_cast<std::size_t>(i)];
    if (f.active && f.keyframe && (oldest < 0 || f.sequence < frames_[static_cast<std::size_t>(oldest)].sequence)) {
      oldest = i;
    }
  }
  return numKeyframes() < 2 ? -1 : oldest;
}

std::vector<int> Window::orderedSlots() const {
  std::vector<int> order;
  for (int i = 0; i < kMaxWindowFrames; ++i) {
    if (frames_[static_cast<std::size_t>(i)].active) order.push_back(i);
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return frames_[static_cast<std::size_t>(a)].sequence < frames_[static_cast<std::size_t>(b)].sequence;
  });
  return order;
}

}  // namespace voca::backend
