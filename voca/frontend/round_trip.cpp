#include "voca/frontend/round_trip.h"

#include <algorithm>

namespace voca {

RoundTripTracker::RoundTripTracker(const FrontendConfig& config) : pattern_(patternBySize(config.pattern)) {
  align_.max_iterations = config.max_iterations;
  align_.min_step_px = static_cast<float>(config.min_step_px);
  align_.coarse_min_step_px = static_cast<float>(config.coarse_min_step_px);
  align_.skip_coarse_outside = config.skip_coarse_outside;
  const int num_levels = config.pyramid_levels + 1;
  backward_levels_ = config.backward_pyramid_levels < 0 ? num_levels : config.backward_pyramid_levels + 1;
}

bool RoundTripTracker::trackForward(std::span<const PatchTemplate> forward, const ImagePyramid& to,
                                    const Eigen::Vector2f& p, const Eigen::Vector2f& flow_guess, int levels,
                                    Eigen::Vector2f& tracked, Eigen::Vector2f& fine_start) const {
  SE2f T_forward(0.f, p + flow_guess);
  const std::span<const PatchTemplate> used = forward.first(static_cast<std::size_t>(levels));
  // Split where the round-trip check starts: the two calls give the same result as one.
  const int split = std::min(levels, backward_levels_);
  if (split < levels && trackPatch(used, to, *pattern_, align_, T_forward, split) != AlignStatus::kConverged)
    return false;
  fine_start = T_forward.translation();
  if (trackPatch(used.first(static_cast<std::size_t>(split)), to, *pattern_, align_, T_forward) !=
      AlignStatus::kConverged)
    return false;
  tracked = T_forward.translation();
  return true;
}

bool RoundTripTracker::checkBackward(const ImagePyramid& from, const ImagePyramid& to, const Eigen::Vector2f& p,
                                     const Eigen::Vector2f& tracked, const Eigen::Vector2f& flow_guess,
                                     const Eigen::Vector2f& fine_start, int levels, float max_recovered_dist2,
                                     TemplateSlots& backward, int backward_slot) const {
  // The backward track starts from the negated guess, so a correct prior lands it near p again. A
  // check on fewer levels than the forward track starts where undoing the forward track's coarse
  // levels would put it: p plus what its finer levels moved.
  const int split = std::min(levels, backward_levels_);
  const Eigen::Vector2f start =
      split < levels ? Eigen::Vector2f(p + (tracked - fine_start)) : Eigen::Vector2f(tracked - flow_guess);
  SE2f T_backward(0.f, start);
  const std::span<const PatchTemplate> templates = backward.buildFinest(backward_slot, to, tracked, *pattern_, split);
  if (trackPatch(templates, from, *pattern_, align_, T_backward) != AlignStatus::kConverged) return false;
  return (T_backward.translation() - p).squaredNorm() <= max_recovered_dist2;
}

bool RoundTripTracker::track(std::span<const PatchTemplate> forward, const ImagePyramid& from, const ImagePyramid& to,
                             const Eigen::Vector2f& p, const Eigen::Vector2f& flow_guess, int levels,
                             float max_recovered_dist2, TemplateSlots& backward, int backward_slot,
                             Eigen::Vector2f& result) const {
  Eigen::Vector2f tracked, fine_start;
  if (!trackForward(forward, to, p, flow_guess, levels, tracked, fine_start)) return false;
  if (!checkBackward(from, to, p, tracked, flow_guess, fine_start, levels, max_recovered_dist2, backward,
                     backward_slot))
    return false;
  result = tracked;
  return true;
}

}  // namespace voca
