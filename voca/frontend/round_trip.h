#pragma once
// KLT tracking of one point checked by a round trip: forward from one image into another, back from
// the result, kept when the back track returns near the start. Temporal tracks (previous image to
// current) and stereo matches (left image to right) both go through it.

#include <Eigen/Core>
#include <span>

#include "voca/frontend/frontend_config.h"
#include "voca/frontend/patch.h"
#include "voca/frontend/pyramid.h"
#include "voca/frontend/track_store.h"

namespace voca {

class RoundTripTracker {
 public:
  RoundTripTracker() = default;
  // The config's pattern and alignment keys; a validated config (validateFrontendConfig).
  explicit RoundTripTracker(const FrontendConfig& config);

  const PatchPattern& pattern() const { return *pattern_; }

  // p tracked from `from` into `to`, starting at p + flow_guess, on the finest `levels` pyramid
  // levels: true and the converged position when both directions converge and the round trip
  // returns within max_recovered_dist2 (squared px). `forward` holds p's templates in `from` (shared
  // by every guess of one point); `backward_slot` of `backward` receives the templates at the result
  // in `to`, on the levels the back track runs on.
  bool track(std::span<const PatchTemplate> forward, const ImagePyramid& from, const ImagePyramid& to,
             const Eigen::Vector2f& p, const Eigen::Vector2f& flow_guess, int levels, float max_recovered_dist2,
             TemplateSlots& backward, int backward_slot, Eigen::Vector2f& result) const;
  // The two halves of track(): the forward track alone, and the round-trip check of its result.
  // fine_start: where the forward track's levels below backward_levels started (p + flow_guess when
  // the check runs on every level the forward track ran on).
  bool trackForward(std::span<const PatchTemplate> forward, const ImagePyramid& to, const Eigen::Vector2f& p,
                    const Eigen::Vector2f& flow_guess, int levels, Eigen::Vector2f& tracked,
                    Eigen::Vector2f& fine_start) const;
  bool checkBackward(const ImagePyramid& from, const ImagePyramid& to, const Eigen::Vector2f& p,
                     const Eigen::Vector2f& tracked, const Eigen::Vector2f& flow_guess,
                     const Eigen::Vector2f& fine_start, int levels, float max_recovered_dist2, TemplateSlots& backward,
                     int backward_slot) const;

 private:
  const PatchPattern* pattern_ = nullptr;
  AlignParams align_;
  // The back track runs on at most this many of the finest levels (backward_pyramid_levels + 1): a
  // forward track on more levels is checked from its finer ones.
  int backward_levels_ = 0;
};

}  // namespace voca
