#pragma once
// The KLT frontend: temporal and stereo patch tracking with codec motion-vector priors, corner
// detection and persistent track ids, with all memory fixed at construction. It composes, in the
// order a frame passes through them:
//   track_store.h       each camera's last two pyramids and its tracks (ids, positions, templates)
//   temporal_tracker.h  each track into the new image: codec priors, round trips, the flow retry
//   track_thinning.h    crowded tracks giving way when the capacity is full
//   stereo_matcher.h    new points and their right views, re-matching, right-only points, epipolar check
//   round_trip.h        the round-trip-checked KLT that the temporal and stereo steps share

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>

#include "voca/calib/calibration.h"
#include "voca/core/image.h"
#include "voca/core/stereo_frame.h"
#include "voca/core/tracked_frame.h"
#include "voca/frontend/frontend_config.h"
#include "voca/frontend/frontend_stats.h"
#include "voca/frontend/stereo_matcher.h"
#include "voca/frontend/temporal_tracker.h"
#include "voca/frontend/track_store.h"
#include "voca/frontend/track_thinning.h"

namespace voca {

// Upper bounds the frontend allocates for once.
struct FrontendCapacities {
  // The largest max_points: twice what a detection grid of 16 px cells fills on a 4K image (one corner
  // per cell, ~32,000); the bound keeps a mistyped capacity from allocating gigabytes (about 8 KB per
  // point in all).
  static constexpr int kMaxPointsBound = 1 << 16;
  int max_points = 500;  // per camera (template memory: about 6 KB per point and camera)
  int max_width = 0;     // 0 = the calibration's image size
  int max_height = 0;
};

// Stereo KLT tracker. Not thread-safe; one instance per stream. No heap allocation in track()
// after the first frame.
class KltFrontend {
 public:
  // The rig's first two cameras are left (cam0) and right (cam1). Throws InputError for an invalid
  // config or a rig with fewer than two cameras.
  KltFrontend(const FrontendConfig& config, const StereoRig& rig, const FrontendCapacities& capacities = {});

  // Tracks the previous frame's points into this frame, detects new left points in empty cells and
  // matches them into the right image. Images must have the calibration's size (at most the capacity).
  // In StereoGuess::kAverageDepth mode the stereo guess uses the frame's depth_hint_m (the last
  // positive hint seen; the default depth until then). out carries the frame's t_ns, frame_index and
  // frames_missing_before.
  void track(const DecodedStereoFrame& input, TrackedStereoFrame& out, FrontendStats& stats);
  // track() as work items, for a caller that spreads one frame over threads:
  //   const int items = beginFrame(input, stats);
  //   runItem(i, input) once for every i < items: in any order, on any threads, concurrently;
  //   endFrame(input, out, stats) once they have all returned.
  // The items touch disjoint state and their results are joined in the points' order, so every
  // schedule computes what track() does, bit for bit. Each holds about half of the frame's tracking.
  int beginFrame(const DecodedStereoFrame& input, FrontendStats& stats);
  void runItem(int item, const DecodedStereoFrame& input);
  void endFrame(const DecodedStereoFrame& input, TrackedStereoFrame& out, FrontendStats& stats);
  // Forgets every track (the next frame starts from detection).
  void reset();

  // Temporal step of the last frame per camera, for visualisation.
  std::span<const PointTrace> traces(int camera) const { return temporal_[static_cast<std::size_t>(camera)].traces(); }
  const FrontendConfig& config() const { return config_; }

 private:
  // The camera's new image and the start of its temporal step.
  void startCamera(int camera, const DecodedStereoFrame& input);

  // Item 0 tracks the left camera's points before left_split_; item 1 the right camera's (its
  // pyramid and step from start to finish) and the left camera's rest. The left camera usually has
  // more points than the right (not every new point is found in the right image): left_split_ puts
  // about half of all points in each item.
  static constexpr int kWorkItems = 2;
  std::size_t left_split_ = 0;
  FrontendConfig config_;
  int max_points_ = 0;
  int width_ = 0, height_ = 0;
  std::array<CameraTracks, 2> camera_tracks_;
  std::array<TemporalTracker, 2> temporal_;
  StereoMatcher stereo_;
  TrackThinner thinner_;
  std::uint64_t next_track_id_ = 1;
  bool have_previous_ = false;
  bool retry_flow_ = false;  // retry_previous_flow applies to the frame being tracked (its InputScope)
  bool presmooth_ = false;   // presmooth applies to the frame being tracked
  std::chrono::steady_clock::time_point frame_start_;  // when beginFrame started (FrontendStats::time_ms)
};

}  // namespace voca
