#pragma once
// The sliding-window stereo VO backend: keyframe window with landmarks hosted in keyframes
// (stereographic bearing + inverse distance), Huber-weighted reprojection residuals through any
// camera model, Levenberg-Marquardt with per-landmark Schur elimination, keyframe marginalisation
// into a square-root prior with first-estimate linearisation points, failure detection and reset.

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "voca/backend/backend_config.h"
#include "voca/backend/landmark_store.h"
#include "voca/backend/marginalization_prior.h"
#include "voca/backend/pose_estimate.h"
#include "voca/backend/stereo_residuals.h"
#include "voca/backend/window.h"
#include "voca/backend/window_optimizer.h"
#include "voca/calib/calibration.h"
#include "voca/core/tracked_frame.h"
#include "voca/geometry/se3.h"

namespace voca {

// Sliding-window estimator: the orchestrator of a Window of frames, a LandmarkStore, triangulation,
// the WindowOptimizer and the MarginalizationPrior (voca/backend/*.h). Not thread-safe. All memory is allocated in the
// constructor; process() does not allocate.
class VoEstimator {
 public:
  // Uses the rig's first two cameras (cam0 = left, the reference). Throws InputError for an invalid
  // config or a rig with fewer than two cameras.
  VoEstimator(const BackendConfig& config, const StereoRig& rig);

  // Estimates the frame's pose. The returned reference stays valid until the next call.
  const PoseEstimate& process(const TrackedStereoFrame& frame);

  // Forgets everything; the next frame starts a new trajectory at the identity body pose.
  void reset();

  const BackendConfig& config() const { return optimizer_.config(); }
  int numKeyframes() const { return window_.numKeyframes(); }
  int numLandmarks() const { return landmarks_.size(); }
  // The most landmarks the window holds (BackendConfig::max_landmarks).
  int landmarkCapacity() const { return landmarks_.capacity(); }
  // The window's landmarks in the world frame (T_world_cam0 of their host times the point its bearing
  // and inverse distance give), at most out.size() of them; returns how many were written. Read-only
  // and allocation-free: for viewers, never used by the estimate.
  std::size_t worldLandmarks(std::span<Eigen::Vector3f> out) const;

  // ---- inspection, for tests and diagnostics (these allocate) ----
  // (t_ns, T_world_cam0) of every frame in the window, oldest first.
  std::vector<std::pair<std::int64_t, SE3d>> windowPoses() const;
  // The marginalisation prior's Hessian R^T R over the window's frames (6 rows per frame, oldest first).
  Eigen::MatrixXd priorHessian() const;
  // Runs up to `iterations` LM iterations on the current window (no outlier filter) and returns the
  // final cost; marginalizeOldestKeyframe() moves the oldest keyframe into the prior.
  double optimizeWindow(int iterations);
  // The window's cost as LM's linearisation computes it: must equal optimizeWindow(0).
  double linearizedWindowCost();
  // Removes the window's outliers as optimize() does, with the outlier bits from a cost pass
  // (from_cost_pass) or from the filter's own residual pass; returns the observations left.
  int filterWindowOutliers(bool from_cost_pass);
  bool marginalizeOldestKeyframe();
  // The reference for marginalisation: makes only the changes to observations that marginalising
  // the oldest keyframe makes (re-hosting, dropping its views of landmarks that stay) and keeps the
  // frame in the window, so optimising afterwards gives what an exact marginalisation must reproduce.
  bool dropViewsOfOldestKeyframe();

 private:
  // Steps of process().
  bool initialize(const TrackedStereoFrame& frame, const SE3d& T_w_c);
  void dropNonKeyframes(int keep);
  int removeFrameOutliers(int frame);
  bool isNewKeyframe(int frame) const;
  int chooseKeyframeToMarginalize(int newest) const;
  void prepareMarginalization(int frame);
  void marginalize(int frame);
  void removeFrame(int frame);
  void frameStats(int frame, PoseEstimate& out) const;
  backend::WindowStateRefs state() { return {window_, landmarks_, prior_}; }

  const backend::StereoResiduals& model() const { return optimizer_.model(); }

  backend::WindowOptimizer optimizer_;  // owns the config and the measurement model
  SE3d T_body_cam0_;
  backend::Window window_;
  backend::LandmarkStore landmarks_;
  backend::MarginalizationPrior prior_;
  std::vector<int> scratch_landmarks_;  // the landmarks marginalised with a keyframe
  // Per position of landmarks_.alive(): which of the new frame's two views removeFrameOutliers
  // judged unprojectable (bits 0-1) or beyond the threshold (bits 2-3), and bit 4 for each landmark
  // the frame sees.
  std::vector<std::uint8_t> frame_verdicts_;
  int frames_since_kf_ = 0;

  bool initialized_ = false;
  bool pending_reset_ = false;  // a failure happened; the next successful initialisation is a reset
  SE3d previous_T_w_c_;         // the pose given for the previous frame (tracked, or where a failed one started over)
  SE3d velocity_;               // T_prev_current of the last tracked step, for the constant-velocity guess
  PoseEstimate estimate_;
};

}  // namespace voca
