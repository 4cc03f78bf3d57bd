#pragma once
// The measurement model of the window: a landmark's reprojection into one camera of one window
// frame through the rig's camera models, and the Huber-robust weighting of the residuals.

#include <Eigen/Core>
#include <array>

#include "voca/backend/landmark_store.h"
#include "voca/backend/reprojection.h"
#include "voca/backend/window.h"
#include "voca/calib/calibration.h"
#include "voca/geometry/se3.h"

namespace voca::backend {

// Every window slot's pose as matrices, taken at the start of a pass over the residuals (see
// PoseMatrices: converting the quaternions per residual was a large share of the backend's time).
using WindowPoses = std::array<PoseMatrices, kMaxWindowFrames>;
WindowPoses windowPoses(const Window& window);

class StereoResiduals {
 public:
  StereoResiduals() = default;
  // Uses the rig's first two cameras (checked by the caller); observation noise and Huber threshold in pixels.
  StereoResiduals(const StereoRig& rig, double obs_std_dev_px, double huber_px);

  // Reprojection of lm into camera `cam` of window slot `frame`, minus its observation there.
  // False when the point cannot be projected or the residual is not finite.
  bool residual(const Window& window, const Landmark& lm, int frame, int cam, Eigen::Vector2d& r,
                ReprojectionJacobians* jac) const {
    Eigen::Vector2d uv;
    const auto c = static_cast<std::size_t>(cam);
    if (!reprojectLandmark(cameras_[c], window[lm.host].T_w_c, window[frame].T_w_c, T_cam0_cam_[c], lm.s, lm.rho, uv,
                           jac)) {
      return false;
    }
    r = uv - lm.px[static_cast<std::size_t>(frame)][c];
    return r.allFinite();
  }
  // The same with the window's poses from windowPoses() (still current).
  bool residual(const WindowPoses& poses, const Landmark& lm, int frame, int cam, Eigen::Vector2d& r,
                ReprojectionJacobians* jac) const {
    Eigen::Vector2d uv;
    const auto c = static_cast<std::size_t>(cam);
    if (!reprojectLandmark(cameras_[c], poses[static_cast<std::size_t>(lm.host)],
                           poses[static_cast<std::size_t>(frame)], cam0_cam_[c], lm.s, lm.rho, uv, jac)) {
      return false;
    }
    r = uv - lm.px[static_cast<std::size_t>(frame)][c];
    return r.allFinite();
  }
  // The same with the landmark's HostBearing, built from poses[lm.host] (with_jacobian when jac is
  // asked for): what a pass over all of a landmark's residuals computes once. Without
  // pose_jacobians only jac->d_landmark is set.
  bool residual(const WindowPoses& poses, const HostBearing& bearing, const Landmark& lm, int frame, int cam,
                Eigen::Vector2d& r, ReprojectionJacobians* jac, bool pose_jacobians = true) const {
    Eigen::Vector2d uv;
    const auto c = static_cast<std::size_t>(cam);
    if (!reprojectLandmark(cameras_[c], poses[static_cast<std::size_t>(lm.host)], bearing,
                           poses[static_cast<std::size_t>(frame)], cam0_cam_[c], lm.rho, uv, jac, pose_jacobians)) {
      return false;
    }
    r = uv - lm.px[static_cast<std::size_t>(frame)][c];
    return r.allFinite();
  }
  // Weight of a residual of norm e in the normal equations (inverse variance times the Huber weight).
  double weight(double e) const { return inv_var_ * (e <= huber_px_ ? 1.0 : huber_px_ / e); }
  // Its robust cost.
  double cost(double e) const { return inv_var_ * (e <= huber_px_ ? 0.5 * e * e : huber_px_ * (e - 0.5 * huber_px_)); }

  const GenericCamera<double>& camera(int cam) const { return cameras_[static_cast<std::size_t>(cam)]; }
  const SE3d& T_cam0_cam(int cam) const { return T_cam0_cam_[static_cast<std::size_t>(cam)]; }

 private:
  std::array<GenericCamera<double>, 2> cameras_;
  std::array<SE3d, 2> T_cam0_cam_;
  std::array<PoseMatrices, 2> cam0_cam_;  // T_cam0_cam_ as matrices
  double huber_px_ = 1.0;
  double inv_var_ = 4.0;
};

}  // namespace voca::backend
