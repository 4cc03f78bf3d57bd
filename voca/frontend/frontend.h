#pragma once
// The KLT frontend: temporal and stereo patch tracking with codec motion-vector priors, corner
// detection and persistent track ids, with all memory fixed at construction.

#include <Eigen/Core>
#include <array>
#include <chrono>
#include <cstdint>
#include <span>
#include <vector>

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
  // track() in three steps, for a caller that tracks the two cameras on two threads: beginFrame,
  // then trackCamera(0) and trackCamera(1), which touch disjoint state and may run concurrently
  // (each builds its camera's pyramid and tracks its points into it), then endFrame (thinning,
  // detection, stereo matching, the epipolar check, the output). The same results as track(), bit
  // for bit, in either order of the two cameras.
  void beginFrame(const DecodedStereoFrame& input, FrontendStats& stats);
  void trackCamera(int camera, const DecodedStereoFrame& input, FrontendStats& stats);
  void endFrame(const DecodedStereoFrame& input, TrackedStereoFrame& out, FrontendStats& stats);
  // trackCamera() in three steps, to share one camera's points between two threads: beginCamera
  // (its pyramid and prior field), then trackPart(camera, 0, 0, k) and trackPart(camera, 1, k, n)
  // for any split k of its n = trackedPoints(camera) points, which may run concurrently with each
  // other and with the other camera's steps, then endCamera (the shares joined in the points' order,
  // the frame-level retry). The same results as trackCamera(), bit for bit, for every k.
  void beginCamera(int camera, const DecodedStereoFrame& input, FrontendStats& stats);
  std::size_t trackedPoints(int camera) const { return cameras_[static_cast<std::size_t>(camera)].size(); }
  void trackPart(int camera, int part, std::size_t begin, std::size_t end);
  void endCamera(int camera, FrontendStats& stats);
  // Forgets every track (the next frame starts from detection).
  void reset();

  // Temporal step of the last frame per camera, for visualisation.
  std::span<const PointTrace> traces(int camera) const { return temporal_[static_cast<std::size_t>(camera)].traces(); }
  const FrontendConfig& config() const { return config_; }

 private:
  FrontendConfig config_;
  int max_points_ = 0;
  int width_ = 0, height_ = 0;
  std::array<CameraTracks, 2> cameras_;
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
