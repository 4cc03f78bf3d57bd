#include "voca/frontend/pyramid.h"

#include "voca/frontend/pyramid_kernels.h"

#include <algorithm>
#include <stdexcept>

namespace voca {

namespace {
int halfSize(int n) { return (n + 1) / 2; }
}  // namespace

ImagePyramid::ImagePyramid(int max_width, int max_height, int num_levels, bool can_presmooth)
    : num_levels_(num_levels), can_presmooth_(can_presmooth), max_width_(max_width), max_height_(max_height) {
  if (num_levels < 1 || num_levels > kMaxLevels) throw std::invalid_argument("ImagePyramid: levels out of range");
  int w = max_width, h = max_height;
  for (int l = 0; l < num_levels; ++l) {
    levels_[static_cast<std::size_t>(l)].resize(w, h);
    w = halfSize(w);
    h = halfSize(h);
  }
  scratch_.resize(can_presmooth ? max_width : halfSize(max_width), max_height);
}

void ImagePyramid::build(GrayView image, bool presmooth) {
  if (image.width > max_width_ || image.height > max_height_) {
    throw std::length_error("ImagePyramid: image larger than the capacity");
  }
  if (presmooth && !can_presmooth_) throw std::logic_error("ImagePyramid: built without presmooth capacity");
  FloatImage& base = levels_[0];
  base.resize(image.width, image.height);
  if (presmooth) {
    convertSmoothed(image);
  } else {
    for (int y = 0; y < image.height; ++y) {
      const std::uint8_t* src = image.row(y);
      float* dst = base.row(y);
      for (int x = 0; x < image.width; ++x) dst[x] = static_cast<float>(src[x]);
    }
  }
  for (int l = 1; l < num_levels_; ++l) {
    downsample(levels_[static_cast<std::size_t>(l - 1)], levels_[static_cast<std::size_t>(l)]);
  }
}

void ImagePyramid::convertSmoothed(GrayView image) {
  const int w = image.width, h = image.height;
  FloatImage& base = levels_[0];
  scratch_.resize(w, h);
  // Horizontal [1 2 1]/4 (borders replicated), then vertical: plain loops the compiler vectorises.
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* s = image.row(y);
    float* t = scratch_.row(y);
    t[0] = 0.25f * (3.f * static_cast<float>(s[0]) + static_cast<float>(s[std::min(1, w - 1)]));
    for (int x = 1; x < w - 1; ++x) {
      t[x] = 0.25f * (static_cast<float>(s[x - 1]) + 2.f * static_cast<float>(s[x]) + static_cast<float>(s[x + 1]));
    }
    if (w > 1) t[w - 1] = 0.25f * (3.f * static_cast<float>(s[w - 1]) + static_cast<float>(s[w - 2]));
  }
  for (int y = 0; y < h; ++y) {
    const float* above = scratch_.row(std::max(y - 1, 0));
    const float* centre = scratch_.row(y);
    const float* below = scratch_.row(std::min(y + 1, h - 1));
    float* d = base.row(y);
    for (int x = 0; x < w; ++x) d[x] = 0.25f * (above[x] + 2.f * centre[x] + below[x]);
  }
}

void ImagePyramid::downsample(const FloatImage& src, FloatImage& dst) {
  const int sw = src.width(), sh = src.height();
  const int dw = halfSize(sw), dh = halfSize(sh);
  dst.resize(dw, dh);
  scratch_.resize(dw, sh);
  // Horizontal pass, evaluated only at the even columns that survive subsampling.
  for (int y = 0; y < sh; ++y) {
    const float* s = src.row(y);
    float* t = scratch_.row(y);
    const auto clamped = [&](int x) {
      const int c = 2 * x;
      const float m2 = s[std::max(c - 2, 0)], m1 = s[std::max(c - 1, 0)];
      const float p1 = s[std::min(c + 1, sw - 1)], p2 = s[std::min(c + 2, sw - 1)];
      return (m2 + p2 + 4.f * (m1 + p1) + 6.f * s[c]) * (1.f / 16.f);
    };
    // Interior columns need no border clamping (a plain loop the compiler vectorises).
    const int interior_end = (sw - 3) / 2 + 1;  // last x with 2x + 2 <= sw - 1, plus one
    int x = 0;
    for (; x < std::min(1, dw); ++x) t[x] = clamped(x);
    // A block of four outputs from x reads up to s[2x + 9]; what is left after the blocks goes scalar.
    const int vector_end = std::max(x, std::min(interior_end, (sw - 2) / 2));
    x = pyramid_kernels::reduceRow<simd4::Native>(s, t, x, vector_end);
    for (; x < interior_end; ++x) {
      const float* c = s + 2 * x;
      t[x] = (c[-2] + c[2] + 4.f * (c[-1] + c[1]) + 6.f * c[0]) * (1.f / 16.f);
    }
    for (; x < dw; ++x) t[x] = clamped(x);
  }
  // Vertical pass at the even rows.
  for (int y = 0; y < dh; ++y) {
    const int c = 2 * y;
    const float* m2 = scratch_.row(std::max(c - 2, 0));
    const float* m1 = scratch_.row(std::max(c - 1, 0));
    const float* c0 = scratch_.row(c);
    const float* p1 = scratch_.row(std::min(c + 1, sh - 1));
    const float* p2 = scratch_.row(std::min(c + 2, sh - 1));
    float* d = dst.row(y);
    for (int x = 0; x < dw; ++x) d[x] = (m2[x] + p2[x] + 4.f * (m1[x] + p1[x]) + 6.f * c0[x]) * (1.f / 16.f);
  }
}

}  // namespace voca
