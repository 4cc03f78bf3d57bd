#pragma once
// The sliding-window stereo VO backend: keyframe window with landmarks hosted in keyframes
// (stereographic bearing + inverse distance), Huber-weighted reprojection residuals through any
// camera model, Levenberg-Marquardt with per-landmark Schur elimination, keyframe marginalisation
// into a square-root prior with first-estimate linearisation points, failure detection and reset.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <array>
#include <cstdint>
#include <string_view>
#include <utility>
#include <vector>

#include "voca/backend/backend_config.h"
#include "voca/backend/id_map.h"
#include "voca/backend/reprojection.h"
#include "voca/calib/calibration.h"
#include "voca/core/tracked_frame.h"
#include "voca/geometry/se3.h"

namespace voca {

// What the backend says about a frame's pose.
enum class TrackingState : std::uint8_t {
  kTracking,  // estimated in the window
  kReset,     // tracking failed; re-initialised from this frame's stereo at the last good pose
  kLost,      // no estimate possible (too few stereo points to start); the last good pose is repeated
};
std::string_view trackingStateName(TrackingState state);

// Why a frame was not tracked.
enum class FailureReason : std::uint8_t {
  kNone,
  kTooFewInliers,
  kExplodingCost,
  kImpossibleMotion,
  kTooFewStereoPoints
};
std::string_view failureReasonName(FailureReason reason);

// The causal output for one frame, final when returned (later optimisation never changes it).
struct PoseEstimate {
  std::int64_t t_ns = 0;
  std::int64_t frame_index = 0;
  SE3d T_world_cam0;
  SE3d T_world_body;  // T_world_cam0 * T_body_cam0^-1: comparable with the dataset's ground truth
  TrackingState state = TrackingState::kLost;
  FailureReason failure = FailureReason::kNone;
  bool keyframe = false;
  int num_keyframes = 0;
  int num_landmarks = 0;  // alive in the window
  int num_inliers = 0;    // this frame's observations attached to landmarks after outlier removal
  int num_outliers = 0;   // this frame's observations removed as outliers
  int new_landmarks = 0;  // triangulated in this frame (keyframes only)
  int lm_iterations = 0;
  double rms_reprojection_px = 0.0;  // this frame's inliers
  double mean_depth_m = 0.0;         // of the landmarks this frame observes (0 when none)
  double time_ms = 0.0;
};

// Sliding-window estimator. Not thread-safe. All memory is allocated in the constructor; process()
// does not allocate.
class VoEstimator {
 public:
  // Uses the rig's first two cameras (cam0 = left, the reference). Throws InputError for an invalid
  // config or a rig with fewer than two cameras.
  VoEstimator(const BackendConfig& config, const StereoRig& rig);

  // Estimates the frame's pose. The returned reference stays valid until the next call.
  const PoseEstimate& process(const TrackedStereoFrame& frame);

  // Forgets everything; the next frame starts a new trajectory at the identity body pose.
  void reset();

  const BackendConfig& config() const { return config_; }
  int numKeyframes() const;
  int numLandmarks() const { return num_landmarks_; }

  // ---- inspection, for tests and diagnostics (these allocate) ----
  // (t_ns, T_world_cam0) of every frame in the window, oldest first.
  std::vector<std::pair<std::int64_t, SE3d>> windowPoses() const;
  // The marginalisation prior's Hessian R^T R over the window's frames (6 rows per frame, oldest first).
  Eigen::MatrixXd priorHessian() const;
  // Runs up to `iterations` LM iterations on the current window (no outlier filter) and returns the
  // final cost; marginalizeOldestKeyframe() moves the oldest keyframe into the prior.
  double optimizeWindow(int iterations);
  bool marginalizeOldestKeyframe();
  // The reference for marginalisation: makes only the changes to observations that marginalising
  // the oldest keyframe makes (re-hosting, dropping its views of landmarks that stay) and keeps the
  // frame in the window, so optimising afterwards gives what an exact marginalisation must reproduce.
  bool dropViewsOfOldestKeyframe();

 private:
  static constexpr int kDim = 6 * kMaxWindowFrames;
  using MatH = Eigen::Matrix<double, kDim, kDim>;
  using VecH = Eigen::Matrix<double, kDim, 1>;
  using Mat63 = Eigen::Matrix<double, 6, 3>;

  struct Observation {
    std::uint64_t id = 0;
    Eigen::Vector2d px = Eigen::Vector2d::Zero();
  };
  struct Frame {
    bool active = false;
    bool keyframe = false;
    bool in_prior = false;  // the prior's linearisation point T_lin is fixed (first estimate)
    std::int64_t t_ns = 0;
    std::int64_t frame_index = 0;
    std::int64_t sequence = 0;  // order of creation
    SE3d T_w_c;
    SE3d T_w_c_lin;
    SE3d T_w_c_backup;
    std::array<std::vector<Observation>, 2> obs;  // sorted by id, capacity fixed
  };
  struct Landmark {
    bool alive = false;
    int alive_pos = -1;  // index in alive_
    std::uint64_t id = 0;
    int host = -1;
    Eigen::Vector2d s = Eigen::Vector2d::Zero();
    double rho = 0.0;
    Eigen::Vector2d s_backup = Eigen::Vector2d::Zero();
    double rho_backup = 0.0;
    std::uint32_t mask = 0;  // bit 2 * frame + camera: observed there
    std::array<std::array<Eigen::Vector2d, 2>, kMaxWindowFrames> px;
  };
  // Per-landmark linearisation, kept for the Schur complement and back-substitution.
  struct LandmarkLin {
    Eigen::Matrix3d H_ll;
    Eigen::Vector3d b_l;
    Eigen::Matrix3d H_ll_inv;  // damped
    std::array<Mat63, kMaxWindowFrames> H_pl;
    std::uint32_t frames = 0;  // bit per frame slot with a non-zero H_pl
    bool valid = false;
  };

  // Every window slot's pose as matrices, taken at the start of a pass over the residuals.
  using FramePoses = std::array<PoseMatrices, kMaxWindowFrames>;

  static int maskBit(int frame, int cam) { return 2 * frame + cam; }
  int numObs(const Landmark& lm) const;
  FramePoses framePoses() const;
  bool residual(const Landmark& lm, int frame, int cam, Eigen::Vector2d& r, ReprojectionJacobians* jac) const;
  // The same with the poses of framePoses() (still current).
  bool residual(const FramePoses& poses, const Landmark& lm, int frame, int cam, Eigen::Vector2d& r,
                ReprojectionJacobians* jac) const;

  // Steps of process().
  bool initialize(const TrackedStereoFrame& frame, const SE3d& T_w_c);
  void dropNonKeyframes(int keep);
  int allocateFrame(const TrackedStereoFrame& frame, const SE3d& T_w_c);
  void attachObservations(int frame);
  void optimizePose(int frame);
  int removeFrameOutliers(int frame, double threshold_px);
  bool isNewKeyframe(int frame) const;
  int triangulateNew(int frame);
  int optimize(int max_iterations, bool filter);
  void filterOutliers();
  int chooseKeyframeToMarginalize(int newest) const;
  void prepareMarginalization(int frame);
  void marginalize(int frame);
  int oldestKeyframe() const;
  void removeLandmark(int index);
  void removeFrame(int frame);
  void frameStats(int frame, PoseEstimate& out) const;

  // LM pieces.
  double cost() const;
  double priorCost() const;
  Eigen::Matrix<double, 6, 1> priorDelta(int frame) const;
  // Normal equations of the residuals (all landmarks, or only_landmarks) plus the prior. Without
  // full_hessian, pose blocks above the diagonal are left out (what the LM solve reads).
  void linearize(MatH& H, VecH& b, const std::vector<int>* only_landmarks, bool full_hessian);
  void backup();
  void restore();
  void applyIncrement(const VecH& dx);

  BackendConfig config_;
  std::array<GenericCamera<double>, 2> cameras_;
  std::array<SE3d, 2> T_cam0_cam_;
  std::array<PoseMatrices, 2> cam0_cam_;  // T_cam0_cam_ as matrices
  SE3d T_body_cam0_;
  double huber_px_ = 1.0;
  double inv_var_ = 4.0;

  std::array<Frame, kMaxWindowFrames> frames_;
  std::int64_t sequence_ = 0;
  std::vector<Landmark> landmarks_;
  std::vector<LandmarkLin> lin_;
  std::vector<int> free_landmarks_;
  std::vector<int> alive_;  // indices of the alive landmarks, so loops never scan the whole pool
  std::vector<int> scratch_landmarks_;
  std::vector<std::uint64_t> scratch_ids_;
  IdSlotMap id_to_landmark_;
  int num_landmarks_ = 0;
  int frames_since_kf_ = 0;

  // Square-root prior 1/2 |R delta + r|^2, stored expanded: H = R^T R, g = R^T r, c = r^T r.
  MatH prior_H_;
  VecH prior_g_;
  double prior_c_ = 0.0;

  // Work space (fixed size, so the solver never allocates).
  MatH H_, H_reduced_;
  VecH b_, b_reduced_, dx_;
  Eigen::LDLT<MatH> ldlt_;
  Eigen::SelfAdjointEigenSolver<MatH> eigen_;

  bool initialized_ = false;
  bool pending_reset_ = false;  // a failure happened; the next successful initialisation is a reset
  SE3d last_good_T_w_c_;
  SE3d previous_T_w_c_;
  bool have_previous_ = false;
  SE3d velocity_;  // T_prev_current of the last tracked step, for the constant-velocity guess
  PoseEstimate estimate_;
};

}  // namespace voca
