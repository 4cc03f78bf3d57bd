#include "voca/frontend/image_shift.h"

#include <algorithm>
#include <cmath>

namespace voca {

namespace {

// Each output pixel is the mean of a factor x factor block; a partial block at the right or bottom
// edge is dropped.
void reduceBoxes(FloatView src, int factor, FloatImage& dst) {
  const int w = src.width / factor, h = src.height / factor;
  dst.resize(w, h);
  const float norm = 1.f / static_cast<float>(factor * factor);
  for (int y = 0; y < h; ++y) {
    float* out = dst.row(y);
    std::fill(out, out + w, 0.f);
    for (int dy = 0; dy < factor; ++dy) {
      const float* in = src.row(y * factor + dy);
      for (int x = 0; x < w; ++x) {
        for (int dx = 0; dx < factor; ++dx) out[x] += in[x * factor + dx];
      }
    }
    for (int x = 0; x < w; ++x) out[x] *= norm;
  }
}

struct Shift {
  int dx = 0, dy = 0;
  double correlation = -1.0;
};

// Normalised cross-correlation of a(x) and b(x + d) over the pixels both images hold; -1 where the
// overlap is too small or flat.
double correlation(FloatView a, FloatView b, int dx, int dy) {
  const int x0 = std::max(0, -dx), x1 = std::min(a.width, b.width - dx);
  const int y0 = std::max(0, -dy), y1 = std::min(a.height, b.height - dy);
  if (x1 - x0 < 4 || y1 - y0 < 4) return -1.0;
  double sa = 0.0, sb = 0.0, saa = 0.0, sbb = 0.0, sab = 0.0;
  for (int y = y0; y < y1; ++y) {
    const float* ra = a.row(y);
    const float* rb = b.row(y + dy) + dx;
    // Per row in float (at most a few hundred terms of 8-bit values), summed in double.
    float ra_sum = 0.f, rb_sum = 0.f, raa = 0.f, rbb = 0.f, rab = 0.f;
    for (int x = x0; x < x1; ++x) {
      const float va = ra[x], vb = rb[x];
      ra_sum += va;
      rb_sum += vb;
      raa += va * va;
      rbb += vb * vb;
      rab += va * vb;
    }
    sa += ra_sum;
    sb += rb_sum;
    saa += raa;
    sbb += rbb;
    sab += rab;
  }
  const double n = static_cast<double>(x1 - x0) * static_cast<double>(y1 - y0);
  const double var_a = saa - sa * sa / n, var_b = sbb - sb * sb / n;
  if (var_a <= 1e-6 * n || var_b <= 1e-6 * n) return -1.0;
  return (sab - sa * sb / n) / std::sqrt(var_a * var_b);
}

// The best-correlating shift within (cx, cy) +- (rx, ry).
Shift bestShift(FloatView a, FloatView b, int cx, int cy, int rx, int ry) {
  Shift best;
  for (int dy = cy - ry; dy <= cy + ry; ++dy) {
    for (int dx = cx - rx; dx <= cx + rx; ++dx) {
      const double c = correlation(a, b, dx, dy);
      if (c > best.correlation) best = {dx, dy, c};
    }
  }
  return best;
}

}  // namespace

ImageShiftSearch::ImageShiftSearch(int max_width, int max_height) {
  reduced_from_.reserve(max_width, max_height);
  reduced_to_.reserve(max_width, max_height);
}

std::optional<Eigen::Vector2f> ImageShiftSearch::estimate(FloatView from, FloatView to, float scale) {
  constexpr int kMinSize = 8;
  if (from.width != to.width || from.height != to.height) return std::nullopt;
  int factor = 1;
  while (from.width / factor > kSearchWidth) factor *= 2;
  FloatView a = from, b = to;
  if (factor > 1) {
    reduceBoxes(from, factor, reduced_from_);
    reduceBoxes(to, factor, reduced_to_);
    a = reduced_from_.view();
    b = reduced_to_.view();
  }
  if (a.width < kMinSize || a.height < kMinSize) return std::nullopt;
  // A quarter of the image each way keeps at least 9/16 of it in the overlap.
  Shift best = bestShift(a, b, 0, 0, a.width / 4, a.height / 4);
  // The reduced image's shift is within about half a block of the level's: refine on the level.
  if (factor > 1) {
    const int reach = factor / 2 + 1;
    best = bestShift(from, to, best.dx * factor, best.dy * factor, reach, reach);
  }
  if (best.correlation < kMinCorrelation) return std::nullopt;
  return Eigen::Vector2f(static_cast<float>(best.dx), static_cast<float>(best.dy)) * scale;
}

}  // namespace voca
