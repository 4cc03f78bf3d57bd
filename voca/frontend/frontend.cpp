#include "voca/frontend/frontend.h"

#include <fmt/core.h>
#include <algorithm>
#include <chrono>
#include <cmath>

#include "voca/core/error.h"

namespace voca {

KltFrontend::KltFrontend(const FrontendConfig& config, const StereoRig& rig, const FrontendCapacities& capacities)
    : config_(config) {
  validateFrontendConfig(config_);
  if (rig.cameras.size() < 2) {
    throw InputError(
        fmt::format("{}: the frontend needs a stereo calibration (2 cameras), got {}", rig.source, rig.cameras.size()));
  }
  const int num_levels = config_.pyramid_levels + 1;
  AlignParams align;
  align.max_iterations = config_.max_iterations;
  align.min_step_px = static_cast<float>(config_.min_step_px);
  align.coarse_min_step_px = static_cast<float>(config_.coarse_min_step_px);
  align.skip_coarse_outside = config_.skip_coarse_outside;
  const int backward_levels = config_.backward_pyramid_levels < 0 ? num_levels : config_.backward_pyramid_levels + 1;
  const RoundTripTracker klt(*patternBySize(config_.pattern), align, backward_levels);
  max_points_ = capacities.max_points;
  if (max_points_ < 1 || max_points_ > FrontendCapacities::kMaxPointsBound) {
    throw InputError(fmt::format("frontend capacity: max_points {} must be between 1 and {}", max_points_,
                                 FrontendCapacities::kMaxPointsBound));
  }
  width_ = rig.cameras[0].width;
  height_ = rig.cameras[0].height;
  const int max_width = std::max({capacities.max_width, rig.cameras[0].width, rig.cameras[1].width});
  const int max_height = std::max({capacities.max_height, rig.cameras[0].height, rig.cameras[1].height});
  if (max_width <= 0 || max_height <= 0) throw InputError("frontend capacity: unknown image size");

  for (std::size_t c = 0; c < 2; ++c) {
    cameras_[c] = CameraTracks(max_points_, TemporalTracker::kScratchSlots, max_width, max_height, num_levels,
                               config_.presmooth != InputScope::kOff);
    temporal_[c] = TemporalTracker(config_, klt, max_points_, max_width, max_height, cameras_[c]);
  }
  stereo_ = StereoMatcher(config_, rig, klt, max_points_, max_width, max_height);
  if (config_.thin_when_full_px > 0.0)
    thinner_ = TrackThinner(config_.thin_when_full_px, max_points_, max_width, max_height);
}

void KltFrontend::reset() {
  for (std::size_t c = 0; c < 2; ++c) {
    cameras_[c].clear();
    temporal_[c].reset();
  }
  have_previous_ = false;
}

void KltFrontend::track(const DecodedStereoFrame& input, TrackedStereoFrame& out, FrontendStats& stats) {
  beginFrame(input, stats);
  trackCamera(0, input, stats);
  trackCamera(1, input, stats);
  endFrame(input, out, stats);
}

void KltFrontend::beginFrame(const DecodedStereoFrame& input, FrontendStats& stats) {
  frame_start_ = std::chrono::steady_clock::now();
  for (int c = 0; c < 2; ++c) {
    const GrayImage& image = input.images[static_cast<std::size_t>(c)];
    if (image.width() != width_ || image.height() != height_) {
      throw InputError(fmt::format("frontend: camera {} image is {}x{}, the calibration says {}x{}", c, image.width(),
                                   image.height(), width_, height_));
    }
  }
  stats.reserve(static_cast<std::size_t>(max_points_));
  stats.clear();
  stats.frame_index = input.frame_index;
  if (std::isfinite(input.depth_hint_m) && input.depth_hint_m > 0.0) stereo_.setAverageDepth(input.depth_hint_m);
  presmooth_ = appliesTo(config_.presmooth, input.decoded);
  retry_flow_ = appliesTo(config_.retry_previous_flow, input.decoded);
}

void KltFrontend::trackCamera(int camera, const DecodedStereoFrame& input, FrontendStats& stats) {
  beginCamera(camera, input, stats);
  trackPart(camera, 0, 0, trackedPoints(camera));
  endCamera(camera, stats);
}

void KltFrontend::beginCamera(int camera, const DecodedStereoFrame& input, FrontendStats& stats) {
  const auto c = static_cast<std::size_t>(camera);
  cameras_[c].advance(input.images[c].view(), presmooth_);
  temporal_[c].begin(input.has_motion ? &input.motion[c] : nullptr, input.frames_missing_before, have_previous_,
                     retry_flow_, cameras_[c]);
  stats.bridged[c] = temporal_[c].bridged();
}

void KltFrontend::trackPart(int camera, int part, std::size_t begin, std::size_t end) {
  const auto c = static_cast<std::size_t>(camera);
  temporal_[c].trackShare(part, begin, end, cameras_[c]);
}

void KltFrontend::endCamera(int camera, FrontendStats& stats) {
  const auto c = static_cast<std::size_t>(camera);
  temporal_[c].finish(cameras_[c]);
  stats.temporal[c] = temporal_[c].stats();
}

void KltFrontend::endFrame(const DecodedStereoFrame& input, TrackedStereoFrame& out, FrontendStats& stats) {
  for (const TemporalTracker& temporal : temporal_) {
    stats.guess_dist_plain_px.insert(stats.guess_dist_plain_px.end(), temporal.guessDistPlain().begin(),
                                     temporal.guessDistPlain().end());
    stats.guess_dist_prior_px.insert(stats.guess_dist_prior_px.end(), temporal.guessDistPrior().begin(),
                                     temporal.guessDistPrior().end());
  }
  CameraTracks& left = cameras_[0];
  CameraTracks& right = cameras_[1];
  // Every track survived and the capacity is full: no point could be detected. Crowded tracks give
  // way (thin_when_full_px).
  if (have_previous_ && config_.thin_when_full_px > 0.0 && static_cast<int>(left.size()) >= max_points_)
    stats.thinned = thinner_.thin(left, right);
  if (have_previous_ && config_.stereo_rematch) stereo_.rematch(left, right, stats);
  stereo_.detectAndMatch(input.images[0].view(), left, right, next_track_id_, stats);
  if (config_.detection_nonoverlap) stereo_.detectRightOnly(input.images[1].view(), right, next_track_id_, stats);
  stereo_.filterEpipolar(left, right, stats);
  have_previous_ = true;

  out.reserve(static_cast<std::size_t>(max_points_));
  out.clear();
  out.t_ns = input.t_ns;
  out.frame_index = input.frame_index;
  out.frames_missing_before = input.frames_missing_before;
  for (std::size_t c = 0; c < 2; ++c) {
    const CameraTracks& camera = cameras_[c];
    auto& observations = out.observations[c];
    for (std::size_t i = 0; i < camera.size(); ++i) observations.push_back({camera.ids[i], camera.points[i]});
  }
  stats.num_left = static_cast<int>(out.observations[0].size());
  stats.num_right = static_cast<int>(out.observations[1].size());
  stats.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - frame_start_).count();
}

}  // namespace voca
