#include "voca/frontend/frontend.h"

#include <fmt/core.h>
#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>

#include "voca/core/error.h"

namespace voca {

KltFrontend::KltFrontend(const FrontendConfig& config, const StereoRig& rig, const FrontendCapacities& capacities)
    : config_(config) {
  validateFrontendConfig(config_);
  rig.requireStereo();
  const int num_levels = config_.pyramid_levels + 1;
  const RoundTripTracker klt(config_);
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
    camera_tracks_[c] = CameraTracks(max_points_, TemporalTracker::kScratchSlots, max_width, max_height, num_levels,
                                     config_.presmooth != InputScope::kOff);
    temporal_[c] = TemporalTracker(config_, klt, max_points_, max_width, max_height, camera_tracks_[c]);
  }
  stereo_ = StereoMatcher(config_, rig, klt, max_points_, max_width, max_height);
  if (config_.thin_when_full_px > 0.0)
    thinner_ = TrackThinner(config_.thin_when_full_px, max_points_, max_width, max_height);
}

void KltFrontend::reset() {
  for (std::size_t c = 0; c < 2; ++c) {
    camera_tracks_[c].clear();
    temporal_[c].reset();
  }
  have_previous_ = false;
}

void KltFrontend::track(const DecodedStereoFrame& input, TrackedStereoFrame& out, FrontendStats& stats) {
  const int items = beginFrame(input, stats);
  for (int item = 0; item < items; ++item) runItem(item, input);
  endFrame(input, out, stats);
}

int KltFrontend::beginFrame(const DecodedStereoFrame& input, FrontendStats& stats) {
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
  // Both items track left points: its pyramid must exist before either starts.
  startCamera(0, input);
  const std::size_t left = camera_tracks_[0].size(), right = camera_tracks_[1].size();
  left_split_ = std::min(left, (left + right) / 2);
  return kWorkItems;
}

void KltFrontend::startCamera(int camera, const DecodedStereoFrame& input) {
  const auto c = static_cast<std::size_t>(camera);
  camera_tracks_[c].advance(input.images[c].view(), presmooth_);
  temporal_[c].begin(input.has_motion ? &input.motion[c] : nullptr, input.frames_missing_before, have_previous_,
                     retry_flow_, camera_tracks_[c]);
}

void KltFrontend::runItem(int item, const DecodedStereoFrame& input) {
  assert(item >= 0 && item < kWorkItems);
  CameraTracks& left = camera_tracks_[0];
  if (item == 0) {
    temporal_[0].trackShare(0, 0, left_split_, left);
    return;
  }
  CameraTracks& right = camera_tracks_[1];
  startCamera(1, input);
  temporal_[1].trackShare(0, 0, right.size(), right);
  temporal_[1].finish(right);
  temporal_[0].trackShare(1, left_split_, left.size(), left);
}

void KltFrontend::endFrame(const DecodedStereoFrame& input, TrackedStereoFrame& out, FrontendStats& stats) {
  temporal_[0].finish(camera_tracks_[0]);
  for (std::size_t c = 0; c < 2; ++c) {
    const TemporalTracker& temporal = temporal_[c];
    stats.temporal[c] = temporal.stats();
    stats.bridged[c] = temporal.bridged();
    stats.guess_dist_plain_px.insert(stats.guess_dist_plain_px.end(), temporal.guessDistPlain().begin(),
                                     temporal.guessDistPlain().end());
    stats.guess_dist_prior_px.insert(stats.guess_dist_prior_px.end(), temporal.guessDistPrior().begin(),
                                     temporal.guessDistPrior().end());
  }
  CameraTracks& left = camera_tracks_[0];
  CameraTracks& right = camera_tracks_[1];
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
    const CameraTracks& camera = camera_tracks_[c];
    auto& observations = out.observations[c];
    for (std::size_t i = 0; i < camera.size(); ++i) observations.push_back({camera.ids[i], camera.points[i]});
  }
  stats.num_left = static_cast<int>(out.observations[0].size());
  stats.num_right = static_cast<int>(out.observations[1].size());
  stats.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - frame_start_).count();
}

}  // namespace voca
