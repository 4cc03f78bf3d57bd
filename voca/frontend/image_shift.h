#pragma once

#include <Eigen/Core>

#include <optional>

#include "voca/frontend/pyramid.h"

namespace voca {

// The image motion of a whole camera between two frames as one translation, found by exhaustive
// search: what the temporal retry starts from when no tracked step has measured the camera's flow
// yet (the first step of a run, or the first after KltFrontend::reset). The search runs on the coarsest pyramid
// level, reduced further by box averaging to at most kSearchWidth columns, over shifts of up to a
// quarter of the image each way, then refines on the coarsest level itself: it reaches far beyond
// the pyramid's KLT basin, to within a coarsest-level pixel, which the retry's KLT then refines.
class ImageShiftSearch {
 public:
  static constexpr int kSearchWidth = 64;
  // Below this normalised cross-correlation the best shift is no match (the images share no
  // structure at that scale: a texture finer than the coarsest level, or another scene).
  static constexpr float kMinCorrelation = 0.5f;

  ImageShiftSearch() = default;
  // Room for coarsest levels up to this size: estimate() then allocates nothing.
  ImageShiftSearch(int max_width, int max_height);

  // The shift d, in level-0 pixels, with to(x + d) ~ from(x); `from` and `to` are the same level
  // of two pyramids of one size, `scale` level-0 pixels per pixel of it. Empty when the level is too
  // small to search or no shift correlates.
  std::optional<Eigen::Vector2f> estimate(FloatView from, FloatView to, float scale);

 private:
  FloatImage reduced_from_, reduced_to_;
};

}  // namespace voca
