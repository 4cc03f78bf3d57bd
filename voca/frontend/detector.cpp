#include "voca/frontend/detector.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <utility>

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

using CircleOffsets = std::array<std::ptrdiff_t, 16>;

CircleOffsets circleOffsets(std::ptrdiff_t stride) {
  CircleOffsets offsets{};
  for (std::size_t k = 0; k < 16; ++k) offsets[k] = kCircle[k][1] * stride + kCircle[k][0];
  return offsets;
}

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

// a - b clamped at 0, in a form the vectoriser maps to one saturating subtraction.
inline std::uint8_t satSub(std::uint8_t a, std::uint8_t b) { return static_cast<std::uint8_t>(std::max(a, b) - b); }

// The compass pre-test over n consecutive pixels of a row: whether any of them has, among its four
// compass pixels (circle pixels 0, 4, 8, 12), a neighbouring pair (one of north/south and one of
// east/west) both brighter than it by more than t, or both darker by more than t. Every arc of 9
// circle pixels holds two neighbouring compass pixels, so a row that fails holds no corner at
// threshold t. Branch-free over uint8 so that GCC vectorises it for SSE2 and NEON alike; the caller
// keeps 3 pixels of image around the row segment.
bool compassRow(const std::uint8_t* __restrict centre, std::ptrdiff_t stride, int n, std::uint8_t t) {
  const std::uint8_t* __restrict up = centre - 3 * stride;
  const std::uint8_t* __restrict down = centre + 3 * stride;
  const std::uint8_t ceiling = static_cast<std::uint8_t>(255 - t);
  std::uint8_t any = 0;
  for (int i = 0; i < n; ++i) {
    const std::uint8_t c = centre[i];
    // min(c + t, 255) and max(c - t, 0): a clamped bound excludes everything, as the int test does.
    const std::uint8_t hi = static_cast<std::uint8_t>(255 - satSub(ceiling, c));
    const std::uint8_t lo = satSub(c, t);
    const std::uint8_t north = up[i], east = centre[i + 3], south = down[i], west = centre[i - 3];
    const bool bright = ((north > hi) | (south > hi)) & ((east > hi) | (west > hi));
    const bool dark = ((north < lo) | (south < lo)) & ((east < lo) | (west < lo));
    any |= static_cast<std::uint8_t>(bright | dark);
  }
  return any != 0;
}

// The largest, over the 16 arcs of 9 circle pixels, of the smallest of the arc's values: circle pixel
// k's value is b[k]. Written with fully unrolled fixed loops so that a caller's loop over pixels is
// vectorised whole (window minima of 2, 4, then 8 + 1 pixels).
inline std::uint8_t bestArcMin(const std::uint8_t* b) {
  std::uint8_t b2[16], b4[16];
  _Pragma("GCC unroll 16") for (int j = 0; j < 16; ++j) b2[j] = std::min(b[j], b[(j + 1) & 15]);
  _Pragma("GCC unroll 16") for (int j = 0; j < 16; ++j) b4[j] = std::min(b2[j], b2[(j + 2) & 15]);
  std::uint8_t best = 0;
  _Pragma("GCC unroll 16") for (int j = 0; j < 16; ++j) {
    best = std::max(best, std::min({b4[j], b4[(j + 4) & 15], b[(j + 8) & 15]}));
  }
  return best;
}

// The arc strengths of n consecutive pixels of a row: bright[i] (dark[i]) is the largest, over the
// 9-pixel arcs, of the smallest brightening (darkening) of the arc relative to centre[i], clamped at
// 0. The pixel passes the segment test at a threshold t >= 0 exactly when t < max(bright, dark), so
// one evaluation answers every threshold of the halving sequence. Branch-free over uint8 (16 lanes
// per SSE2/NEON vector); the caller keeps 3 pixels of image around the row segment.
void strengthRow(const std::uint8_t* __restrict centre, const CircleOffsets& offsets, int n,
                 std::uint8_t* __restrict bright, std::uint8_t* __restrict dark) {
  const CircleOffsets off = offsets;
  for (int i = 0; i < n; ++i) {
    const std::uint8_t c = centre[i];
    std::uint8_t b[16], d[16];
    _Pragma("GCC unroll 16") for (int k = 0; k < 16; ++k) {
      const std::uint8_t v = centre[i + off[static_cast<std::size_t>(k)]];
      b[k] = satSub(v, c);
      d[k] = satSub(c, v);
    }
    bright[i] = bestArcMin(b);
    dark[i] = bestArcMin(d);
  }
}

// cornerResponse() for a threshold t >= 0 given the pixel's arc strengths: the sum of the excess
// over t of the circle pixels in each direction that passes the segment test, the larger one.
int excessResponse(const std::uint8_t* centre, const CircleOffsets& offsets, int t, int bright, int dark) {
  const int c = *centre;
  int bright_excess = 0, dark_excess = 0;
  for (std::size_t k = 0; k < 16; ++k) {
    const int diff = centre[offsets[k]] - c;
    bright_excess += std::max(diff - t, 0);
    dark_excess += std::max(-diff - t, 0);
  }
  int response = 0;
  if (bright > t) response = bright_excess;
  if (dark > t) response = std::max(response, dark_excess);
  return response;
}

// How close to the image's edge detect() takes a corner: the configured border, and at least the
// 3 px the segment test's circle reaches.
int detectionBorder(int border_px) { return std::max(border_px, 3); }

// Of the grid cell [start, start + grid) along an image side of `size` pixels, the pixels at least
// `border` from both edges, as [first, end) (empty when first >= end).
std::pair<int, int> cellInterior(int start, int grid, int size, int border) {
  return {std::max(start, border), std::min(start + grid, size - border)};
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

int detectionCells(int width, int height, int grid_size_px, int border_px) {
  if (grid_size_px <= 0) return 0;
  const int border = detectionBorder(border_px);
  const auto cellsAlong = [&](int size) {
    int cells = 0;
    for (int start = 0; start < size; start += grid_size_px) {
      const auto [first, end] = cellInterior(start, grid_size_px, size, border);
      cells += first < end ? 1 : 0;
    }
    return cells;
  };
  return cellsAlong(width) * cellsAlong(height);
}

GridDetector::GridDetector(int max_width, int max_height, int grid_size_px) : grid_size_px_(grid_size_px) {
  if (grid_size_px <= 0) throw std::invalid_argument("GridDetector: grid size must be positive");
  const int cells_x = (max_width + grid_size_px - 1) / grid_size_px;
  const int cells_y = (max_height + grid_size_px - 1) / grid_size_px;
  occupied_.assign(static_cast<std::size_t>(cells_x) * static_cast<std::size_t>(cells_y), 0);
  row_buffers_.assign(2 * static_cast<std::size_t>(grid_size_px), 0);
  candidates_.reserve(static_cast<std::size_t>(grid_size_px) * static_cast<std::size_t>(grid_size_px));
}

int GridDetector::detect(GrayView image, std::span<const Eigen::Vector2f> existing, const DetectorParams& params,
                         int max_new, std::vector<Eigen::Vector2f>& out, std::span<const std::uint8_t> blocked) {
  const int g = grid_size_px_;
  const int cells_x = (image.width + g - 1) / g;
  const int cells_y = (image.height + g - 1) / g;
  if (static_cast<std::size_t>(cells_x) * static_cast<std::size_t>(cells_y) > occupied_.size()) {
    throw std::length_error("GridDetector: image larger than the capacity");
  }
  if (params.max_threshold < 0) throw std::invalid_argument("GridDetector: max_threshold must not be negative");
  if (!blocked.empty() && blocked.size() != static_cast<std::size_t>(cells_x) * static_cast<std::size_t>(cells_y)) {
    throw std::invalid_argument("GridDetector: the blocked-cell mask does not match the image's grid");
  }
  if (blocked.empty()) {
    std::fill(occupied_.begin(), occupied_.begin() + cells_x * cells_y, std::uint8_t{0});
  } else {
    std::copy(blocked.begin(), blocked.end(), occupied_.begin());
  }
  for (const Eigen::Vector2f& p : existing) {
    const int cx = static_cast<int>(std::floor((p.x() + 0.5f) / static_cast<float>(g)));
    const int cy = static_cast<int>(std::floor((p.y() + 0.5f) / static_cast<float>(g)));
    if (cx >= 0 && cy >= 0 && cx < cells_x && cy < cells_y) occupied_[static_cast<std::size_t>(cy * cells_x + cx)] = 1;
  }
  // The threshold sequence: max_threshold halved while it stays >= min_threshold, ending at 0 at most.
  std::array<int, 33> thresholds{};
  int num_thresholds = 0;
  for (int t = params.max_threshold; t >= params.min_threshold; t /= 2) {
    thresholds[static_cast<std::size_t>(num_thresholds++)] = t;
    if (t == 0) break;
  }
  // No 8-bit difference exceeds 255, so a sequence that ends there finds nothing.
  if (num_thresholds == 0 || thresholds[static_cast<std::size_t>(num_thresholds - 1)] >= 255) return 0;
  const int lowest = thresholds[static_cast<std::size_t>(num_thresholds - 1)];

  const CircleOffsets offsets = circleOffsets(image.stride);
  const int border = detectionBorder(params.border_px);
  const float radius2 = params.safe_radius_px * params.safe_radius_px;
  int added = 0;
  for (int cy = 0; cy < cells_y; ++cy) {
    for (int cx = 0; cx < cells_x; ++cx) {
      if (occupied_[static_cast<std::size_t>(cy * cells_x + cx)] != 0) continue;
      if (added >= max_new) return added;
      const auto [x0, x1] = cellInterior(cx * g, g, image.width, border);
      const auto [y0, y1] = cellInterior(cy * g, g, image.height, border);
      if (x0 >= x1 || y0 >= y1) continue;
      // One pass finds every pixel that is a corner at the lowest threshold, with its arc strength;
      // the halving sequence then only needs the strongest of them.
      candidates_.clear();
      int cell_strength = 0;
      const int n = x1 - x0;
      std::uint8_t* bright = row_buffers_.data();
      std::uint8_t* dark = bright + g;
      for (int y = y0; y < y1; ++y) {
        if (radius2 > 0.f) {
          // A row segment wholly outside the mask is skipped. Exact in double, with a margin far
          // above the float rounding of the per-pixel test below, so no pixel it would take is lost.
          const double dx = std::max({0.0, x0 - static_cast<double>(params.safe_center.x()),
                                      static_cast<double>(params.safe_center.x()) - (x1 - 1)});
          const double dy = y - static_cast<double>(params.safe_center.y());
          if (dx * dx + dy * dy > 1.001 * static_cast<double>(radius2) + 1.0) continue;
        }
        const std::uint8_t* row = &image(x0, y);
        // The cheap compass test skips the rows of flat areas; textured rows get the full test.
        if (!compassRow(row, image.stride, n, static_cast<std::uint8_t>(lowest))) continue;
        strengthRow(row, offsets, n, bright, dark);
        for (int i = 0; i < n; ++i) {
          const int strength = std::max(bright[i], dark[i]);
          if (strength <= lowest) continue;
          const int x = x0 + i;
          if (radius2 > 0.f) {
            const float dx = static_cast<float>(x) - params.safe_center.x();
            const float dy = static_cast<float>(y) - params.safe_center.y();
            if (dx * dx + dy * dy > radius2) continue;
          }
          candidates_.push_back({x, y, bright[i], dark[i]});
          cell_strength = std::max(cell_strength, strength);
        }
      }
      if (candidates_.empty()) continue;
      // The first threshold of the sequence that some candidate passes; only those compete, by response.
      int threshold = lowest;
      for (int k = 0; k < num_thresholds; ++k) {
        if (cell_strength > thresholds[static_cast<std::size_t>(k)]) {
          threshold = thresholds[static_cast<std::size_t>(k)];
          break;
        }
      }
      int best = 0;
      const Candidate* winner = nullptr;
      for (const Candidate& c : candidates_) {
        if (std::max(c.bright, c.dark) <= threshold) continue;
        const int response = excessResponse(&image(c.x, c.y), offsets, threshold, c.bright, c.dark);
        if (response > best) {
          best = response;
          winner = &c;
        }
      }
      out.emplace_back(static_cast<float>(winner->x), static_cast<float>(winner->y));
      ++added;
    }
  }
  return added;
}

}  // namespace voca
