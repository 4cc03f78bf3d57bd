#pragma once
// Stereo matching: new left points detected in empty cells and found in the right image, left tracks
// without a right view matched there again, right-only points where the left camera does not see,
// and the epipolar check that pairs must pass.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "voca/calib/calibration.h"
#include "voca/core/image.h"
#include "voca/frontend/detector.h"
#include "voca/frontend/frontend_config.h"
#include "voca/frontend/frontend_stats.h"
#include "voca/frontend/round_trip.h"
#include "voca/frontend/track_store.h"

namespace voca {

class StereoMatcher {
 public:
  StereoMatcher() = default;
  // The rig's cameras 0 (left) and 1 (right); buffers for max_points per camera and images up to
  // max_width x max_height.
  StereoMatcher(const FrontendConfig& config, const StereoRig& rig, const RoundTripTracker& klt, int max_points,
                int max_width, int max_height);

  // The depth the stereo guess puts a left point at in StereoGuess::kAverageDepth mode.
  void setAverageDepth(double depth_m) { average_depth_m_ = depth_m; }

  // Detects new left points in the empty cells of left_image (left.cur()'s image), issues their ids
  // from next_track_id and tracks each into the right image, while the right camera has room.
  void detectAndMatch(GrayView left_image, CameraTracks& left, CameraTracks& right, std::uint64_t& next_track_id,
                      FrontendStats& stats);
  // stereo_rematch: matches the left tracks that have no right view into the right image again.
  void rematch(CameraTracks& left, CameraTracks& right, FrontendStats& stats);
  // detection_nonoverlap: new right points in the cells the left camera does not see.
  void detectRightOnly(GrayView right_image, CameraTracks& right, std::uint64_t& next_track_id, FrontendStats& stats);
  // Drops the right views of pairs whose unit bearings fail |f0^T E f1| <= epipolar_error.
  void filterEpipolar(const CameraTracks& left, CameraTracks& right, FrontendStats& stats);

 private:
  // Where the left point p is first looked for in the right image (the config's matching_guess).
  Eigen::Vector2f stereoGuess(const Eigen::Vector2f& p) const;
  // Right-image grid cells that the left camera sees (blocked for right-only detection).
  void computeRightOverlap(const StereoRig& rig);

  FrontendConfig config_;
  RoundTripTracker klt_;
  int num_levels_ = 0;
  float round_trip2_ = 0.f;  // the left-to-right match's round-trip tolerance (squared px)
  int max_points_ = 0;
  std::array<GenericCamera<double>, 2> cameras_;
  SE3d T_cam1_cam0_;
  Eigen::Matrix3d essential_;  // f0^T E f1 = 0 for unit bearings f0 (cam0), f1 (cam1)
  double average_depth_m_ = 0.0;
  DetectorParams left_detector_params_;
  DetectorParams right_detector_params_;     // safe radius around the right camera's principal point
  std::vector<std::uint8_t> right_overlap_;  // per right-image cell, non-zero: the left camera sees it
  GridDetector detector_;
  std::vector<Eigen::Vector2f> new_points_;
  // rematch: the tracks found again, then the right camera's lists merged with them in id order.
  std::vector<std::uint64_t> rematch_ids_, merged_ids_;
  std::vector<Eigen::Vector2f> rematch_points_, merged_points_;
  std::vector<int> rematch_slots_, merged_slots_;
};

}  // namespace voca
