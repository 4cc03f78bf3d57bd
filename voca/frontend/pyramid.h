#pragma once
// Float image pyramids for KLT tracking: [1 4 6 4 1]/16 smoothing and 2x subsampling, buffers fixed
// at construction.

#include <array>
#include <cstdint>

#include "voca/core/image.h"

namespace voca {

using FloatImage = Image<float>;
using FloatView = ImageView<const float>;

// Level 0 is the input converted to float, optionally smoothed by [1 2 1]/4 in both directions
// (build's presmooth, chosen per image: the frontend may smooth raw input only); level l+1 is level
// l smoothed by the separable binomial kernel [1 4 6 4 1]/16 (borders replicated) and subsampled by
// taking every second pixel, so pixel (x, y) of level l lies at (2^l x, 2^l y) in level 0 and
// coordinates convert by an exact scale.
//
// Why presmooth: the tracking patterns sample a patch on a 2 px grid, which aliases detail finer
// than a 4 px period; on sharp images that puts even the exact minimum of the patch cost about a
// tenth of a pixel from the truth (a dense grid halves it, bicubic sampling changes nothing). The
// [1 2 1]/4 kernel removes that detail (zero response at Nyquist, half at a 4 px period). It is
// symmetric, so it moves no feature, and filtering both images of a pair is harmless to the
// alignment itself.
class ImagePyramid {
 public:
  static constexpr int kMaxLevels = 8;

  ImagePyramid() = default;
  // num_levels counts all levels including level 0 (the config's `levels` + 1). can_presmooth
  // reserves the full-width scratch rows that build's presmooth needs.
  ImagePyramid(int max_width, int max_height, int num_levels, bool can_presmooth = false);

  // Rebuilds every level from image (at most the capacity given at construction), smoothing level 0
  // when presmooth is set (which needs can_presmooth). No allocation.
  void build(GrayView image, bool presmooth = false);

  int numLevels() const { return num_levels_; }
  FloatView level(int index) const { return levels_[static_cast<std::size_t>(index)].view(); }
  int width() const { return levels_[0].width(); }
  int height() const { return levels_[0].height(); }

 private:
  void downsample(const FloatImage& src, FloatImage& dst);
  void convertSmoothed(GrayView image);

  int num_levels_ = 0;
  bool can_presmooth_ = false;
  int max_width_ = 0, max_height_ = 0;
  std::array<FloatImage, kMaxLevels> levels_;
  FloatImage scratch_;  // horizontally filtered rows of the level being reduced (or of level 0)
};

}  // namespace voca
