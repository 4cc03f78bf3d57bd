#pragma once
// thin_when_full_px: when every track survived and the capacity is full, no new point can be
// detected; the younger of two left tracks closer than the distance gives way, in both cameras, so
// that detection can fill the emptier parts of the image again.

#include <cstdint>
#include <vector>

#include "voca/frontend/track_store.h"

namespace voca {

class TrackThinner {
 public:
  TrackThinner() = default;
  // Buffers for max_points tracks in images up to max_width x max_height.
  TrackThinner(double min_distance_px, int max_points, int max_width, int max_height);

  // Drops the younger of every two left tracks closer than the distance, and the same tracks' right
  // views. Returns how many left tracks were dropped.
  int thin(CameraTracks& left, CameraTracks& right);

 private:
  float min_distance2_px2_ = 0.f;
  // A grid of cells half the distance wide, so a cell holds at most one kept point, with each kept
  // point's index or -1, and the ids dropped in one call.
  float cell_px_ = 0.f;
  int cols_ = 0, rows_ = 0;
  std::vector<int> grid_;
  std::vector<std::uint64_t> thinned_ids_;
};

}  // namespace voca
