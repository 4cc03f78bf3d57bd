#pragma once
// The window's landmarks: a fixed pool, each hosted in a window frame as a stereographic bearing
// and inverse distance, with a bit mask of the (frame, camera) views that observe it. Track ids map
// to pool slots; the alive slots are listed so loops never scan the whole pool.

#include <Eigen/Core>
#include <array>
#include <bit>
#include <cstdint>
#include <vector>

#include "voca/backend/backend_config.h"
#include "voca/backend/id_map.h"
#include "voca/backend/window.h"

namespace voca::backend {

struct Landmark {
  bool alive = false;
  int alive_pos = -1;  // index in LandmarkStore::alive()
  std::uint64_t id = 0;
  int host = -1;
  Eigen::Vector2d s = Eigen::Vector2d::Zero();
  double rho = 0.0;
  Eigen::Vector2d s_backup = Eigen::Vector2d::Zero();
  double rho_backup = 0.0;
  std::uint32_t mask = 0;  // bit maskBit(frame, camera): observed there
  std::array<std::array<Eigen::Vector2d, 2>, kMaxWindowFrames> px;

  int numObs() const { return std::popcount(mask); }
};

class LandmarkStore {
 public:
  // All memory for max_landmarks is taken here.
  explicit LandmarkStore(int max_landmarks = 0);

  // Every landmark dead, every slot free.
  void clear();

  Landmark& operator[](int index) { return landmarks_[static_cast<std::size_t>(index)]; }
  const Landmark& operator[](int index) const { return landmarks_[static_cast<std::size_t>(index)]; }
  // Indices of the alive landmarks. Loops that remove while iterating must run backwards.
  const std::vector<int>& alive() const { return alive_; }
  int size() const { return num_alive_; }
  int capacity() const { return static_cast<int>(landmarks_.size()); }

  // The slot of the landmark of a track, or -1.
  int find(std::uint64_t id) const { return id_to_landmark_.find(id); }
  bool full() const { return free_.empty(); }
  // The slot the next add() fills (not full()); the caller fills the landmark there first.
  int nextFree() const { return free_.back(); }
  // Makes the landmark at nextFree() alive under its id; false (and nothing changes) when the id
  // map is full.
  bool add();
  // Kills a landmark (swap-remove from the alive list: the element moved into its position has
  // been visited already by a backwards loop).
  void remove(int index);

  // Adds the views of a new window frame to the landmarks of its tracks.
  void attach(const Window& window, int frame);
  // Removes a window frame's views: landmarks hosted there die, and so do those left with fewer
  // than two views.
  void dropFrame(int frame);

 private:
  std::vector<Landmark> landmarks_;
  std::vector<int> free_;
  std::vector<int> alive_;
  IdSlotMap id_to_landmark_;
  int num_alive_ = 0;
};

}  // namespace voca::backend
