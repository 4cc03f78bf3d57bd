#include "voca/frontend/detector.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace voca {

namespace {

constexpr std::array<std::array<int, 2>, 16> kCircle = {{{0, -3},
                                                         {1, -3},
                                                         {2, -2},
                                                         {3, -1},
                                                         {3, 0},
                                                         {3, 1},
                                                         {2, 2},
                                                         {1, 3},
                                                         {0, 3},
                                                         {-1, 3},
                                                         {-2, 2},
                                                         {-3, 1},
                                                         {-3, 0},
                                                         {-3, -1},
                                                         {-2, -2},
                                                         {-1, -3}}};
constexpr int kArc = 9;

// Longest run of set bits in a 16-bit circular mask.
int longestCircularRun(std::uint32_t mask) {
  if (mask == 0xFFFFu) return 16;
  const std::uint32_t doubled = mask | (mask << 16);
  int best = 0, run = 0;
  for (int i = 0; i < 32; ++i) {
    run = ((doubled >> i) & 1u) != 0 ? run + 1 : 0;
    best = std::max(best, run);
  }
  return std::min(best, 16);
}

}  // namespace

int cornerResponse(GrayView image, int x, int y, int threshold) {
  const std::uint8_t* centre = &image(x, y);
  const int c = *centre;
  const std::ptrdiff_t stride = image.stride;
  const auto at = [&](int k) {
    return static_cast<int>(
        centre[kCircle[static_cast<std::size_t>(k)][1] * stride + kCircle[static_cast<std::size_t>(k)][0]]);
  };
  // Any arc of 9 of the 16 pixels covers at least two of the four compass pixels.
  int bright = 0, dark = 0;
  for (int k = 0; k < 16; k += 4) {
    const int v = at(k);
    bright += v > c + threshold;
    dark += v < c - threshold;
  }
  if (bright < 2 && dark < 2) return 0;
  std::uint32_t bright_mask = 0, dark_mask = 0;
  int bright_excess = 0, dark_excess = 0;
  for (int k = 0; k < 16; ++k) {
    const int d = at(k) - c;
    if (d > threshold) {
      bright_mask |= 1u << k;
      bright_excess += d - threshold;
    } else if (d < -threshold) {
      dark_mask |= 1u << k;
      dark_excess += -d - threshold;
    }
  }
  int response = 0;
  if (longestCircularRun(bright_mask) >= kArc) response = std::max(response, bright_excess);
  if (longestCircularRun(dark_mask) >= kArc) response = std::max(response, dark_excess);
  return response;
}

GridDetector::GridDetector(int max_width, int max_height, int grid_size_px) : grid_size_px_(grid_size_px) {
  if (grid_size_px <= 0) throw std::invalid_argument("GridDetector: grid size must be positive");
  const int cells_x = (max_width + grid_size_px - 1) / grid_size_px;
  const int cells_y = (max_height + grid_size_px - 1) / grid_size_px;
  occupied_.assign(static_cast<std::size_t>(cells_x) * static_cast<std::size_t>(cells_y), 0);
  candidates_.reserve(static_cast<std::size_t>(grid_size_px) * static_cast<std::size_t>(grid_size_px));
}

int GridDetector::detect(GrayView image, std::span<const Eigen::Vector2f> existing, const DetectorParams& params,
                         int max_new, std::vector<Eigen::Vector2f>& out) {
  const int g = grid_size_px_;
  const int cells_x = (image.width + g - 1) / g;
  const int cells_y = (image.height + g - 1) / g;
  if (static_cast<std::size_t>(cells_x) * static_cast<std::size_t>(cells_y) > occupied_.size()) {
    throw std::length_error("GridDetector: image larger than the capacity");
  }
  std::fill(occupied_.begin(), occupied_.begin() + cells_x * cells_y, std::uint8_t{0});
  for (const Eigen::Vector2f& p : existing) {
    const int cx = static_cast<int>(std::floor((p.x() + 0.5f) / static_cast<float>(g)));
    const int cy = static_cast<int>(std::floor((p.y() + 0.5f) / static_cast<float>(g)));
    if (cx >= 0 && cy >= 0 && cx < cells_x && cy < cells_y) occupied_[static_cast<std::size_t>(cy * cells_x + cx)] = 1;
  }
  const int border = std::max(params.border_px, 3);
  const float radius2 = params.safe_radius_px * params.safe_radius_px;
  int added = 0;
  for (int cy = 0; cy < cells_y; ++cy) {
    for (int cx = 0; cx < cells_x; ++cx) {
      if (occupied_[static_cast<std::size_t>(cy * cells_x + cx)] != 0) continue;
      if (added >= max_new) return added;
      const int x0 = std::max(cx * g, border), x1 = std::min((cx + 1) * g, image.width - border);
      const int y0 = std::max(cy * g, border), y1 = std::min((cy + 1) * g, image.height - border);
      if (x0 >= x1 || y0 >= y1) continue;
      // A corner at threshold t is one at every lower threshold too, so one pass at the lowest
      // threshold finds every candidate; the halving sequence then only revisits those.
      candidates_.clear();
      for (int y = y0; y < y1; ++y) {
        for (int x = x0; x < x1; ++x) {
          if (radius2 > 0.f) {
            const float dx = static_cast<float>(x) - params.safe_center.x();
            const float dy = static_cast<float>(y) - params.safe_center.y();
            if (dx * dx + dy * dy > radius2) continue;
          }
          if (cornerResponse(image, x, y, params.min_threshold) > 0) candidates_.emplace_back(x, y);
        }
      }
      if (candidates_.empty()) continue;
      for (int threshold = params.max_threshold; threshold >= params.min_threshold; threshold /= 2) {
        int best = 0;
        Eigen::Vector2i best_px(0, 0);
        for (const Eigen::Vector2i& c : candidates_) {
          const int response = cornerResponse(image, c.x(), c.y(), threshold);
          if (response > best) {
            best = response;
            best_px = c;
          }
        }
        if (best > 0) {
          out.emplace_back(static_cast<float>(best_px.x()), static_cast<float>(best_px.y()));
          ++added;
          break;
        }
        if (threshold == 0) break;
      }
    }
  }
  return added;
}

}  // namespace voca
