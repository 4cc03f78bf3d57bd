#include "voca/backend/landmark_store.h"

namespace voca::backend {

LandmarkStore::LandmarkStore(int max_landmarks) : id_to_landmark_(max_landmarks) {
  const auto n = static_cast<std::size_t>(max_landmarks);
  landmarks_.resize(n);
  free_.reserve(n);
  alive_.reserve(n);
  clear();
}

void LandmarkStore::clear() {
  free_.clear();
  alive_.clear();
  for (int i = capacity() - 1; i >= 0; --i) {
    landmarks_[static_cast<std::size_t>(i)].alive = false;
    free_.push_back(i);
  }
  id_to_landmark_.clear();
  num_alive_ = 0;
}

bool LandmarkStore::add() {
  const int index = free_.back();
  Landmark& lm = landmarks_[static_cast<std::size_t>(index)];
  if (!id_to_landmark_.insert(lm.id, index)) return false;
  lm.alive = true;
  lm.alive_pos = static_cast<int>(alive_.size());
  alive_.push_back(index);
  free_.pop_back();
  ++num_alive_;
  return true;
}

void LandmarkStore::remove(int index) {
  Landmark& lm = landmarks_[static_cast<std::size_t>(index)];
  if (!lm.alive) return;
  id_to_landmark_.erase(lm.id);
  lm.alive = false;
  lm.mask = 0;
  const int last = alive_.back();
  alive_[static_cast<std::size_t>(lm.alive_pos)] = last;
  landmarks_[static_cast<std::size_t>(last)].alive_pos = lm.alive_pos;
  alive_.pop_back();
  free_.push_back(index);
  --num_alive_;
}

void LandmarkStore::attach(const Window& window, int frame) {
  const WindowFrame& f = window[frame];
  for (int c = 0; c < 2; ++c) {
    for (const Observation& o : f.obs[static_cast<std::size_t>(c)]) {
      const int index = id_to_landmark_.find(o.id);
      if (index < 0) continue;
      Landmark& lm = landmarks_[static_cast<std::size_t>(index)];
      lm.mask |= 1u << maskBit(frame, c);
      lm.px[static_cast<std::size_t>(frame)][static_cast<std::size_t>(c)] = o.px;
    }
  }
}

void LandmarkStore::dropFrame(int frame) {
  const std::uint32_t bits = frameBits(frame);
  for (int k = static_cast<int>(alive_.size()) - 1; k >= 0; --k) {
    const int i = alive_[static_cast<std::size_t>(k)];
    Landmark& lm = landmarks_[static_cast<std::size_t>(i)];
    if (!lm.alive) continue;
    if (lm.host == frame) {
      remove(i);
      continue;
    }
    lm.mask &= ~bits;
    if (lm.numObs() < 2) remove(i);
  }
}

}  // namespace voca::backend
