#include "voca/frontend/track_thinning.h"

#include <algorithm>
#include <cmath>

namespace voca {

TrackThinner::TrackThinner(double min_distance_px, int max_points, int max_width, int max_height)
    : min_distance2_px2_(static_cast<float>(min_distance_px * min_distance_px)),
      cell_px_(static_cast<float>(min_distance_px / 2.0)) {
  cols_ = static_cast<int>(std::ceil(static_cast<float>(max_width) / cell_px_)) + 1;
  rows_ = static_cast<int>(std::ceil(static_cast<float>(max_height) / cell_px_)) + 1;
  grid_.assign(static_cast<std::size_t>(cols_) * static_cast<std::size_t>(rows_), -1);
  thinned_ids_.reserve(static_cast<std::size_t>(max_points));
}

int TrackThinner::thin(CameraTracks& left, CameraTracks& right) {
  // Cells are half the distance wide: two points closer than it lie at most two cells apart.
  constexpr int kReach = 2;
  const auto cellOf = [&](float v, int cells) {
    return std::clamp(static_cast<int>(std::floor(v / cell_px_)), 0, cells - 1);
  };
  thinned_ids_.clear();
  // Ids are issued in increasing order: the list is oldest first, so the older of two close tracks
  // is always the one already kept.
  left.retain([&](std::size_t i, std::size_t kept) {
    const Eigen::Vector2f p = left.points[i];
    const int cx = cellOf(p.x(), cols_), cy = cellOf(p.y(), rows_);
    for (int y = std::max(0, cy - kReach); y <= std::min(rows_ - 1, cy + kReach); ++y) {
      for (int x = std::max(0, cx - kReach); x <= std::min(cols_ - 1, cx + kReach); ++x) {
        const int other = grid_[static_cast<std::size_t>(y * cols_ + x)];
        if (other >= 0 && (left.points[static_cast<std::size_t>(other)] - p).squaredNorm() < min_distance2_px2_) {
          thinned_ids_.push_back(left.ids[i]);
          return false;
        }
      }
    }
    grid_[static_cast<std::size_t>(cy * cols_ + cx)] = static_cast<int>(kept);
    return true;
  });
  // The grid is cleared through the kept points: far fewer than its cells.
  for (const Eigen::Vector2f& p : left.points) {
    grid_[static_cast<std::size_t>(cellOf(p.y(), rows_) * cols_ + cellOf(p.x(), cols_))] = -1;
  }
  if (thinned_ids_.empty()) return 0;
  // The same tracks in the right camera: both id lists ascend, one merge pass.
  std::size_t d = 0;
  right.retain([&](std::size_t r, std::size_t) {
    while (d < thinned_ids_.size() && thinned_ids_[d] < right.ids[r]) ++d;
    return d == thinned_ids_.size() || thinned_ids_[d] != right.ids[r];
  });
  return static_cast<int>(thinned_ids_.size());
}

}  // namespace voca
