#pragma once
// The measurement model of the window: a landmark's reprojection into one camera of one window
// frame through the rig's camera models, and the Huber-robust weighting of the residuals.

#include <Eigen/Core>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>

#include "voca/backend/landmark_store.h"
#include "voca/backend/reprojection.h"
#include "voca/backend/window.h"
#include "voca/calib/calibration.h"
#include "voca/geometry/se3.h"

namespace voca::backend {

// A window slot's pose as the residual passes use it: T_w_c0 as matrices, and the rotation from
// world axes into each camera of the rig, taken once at the start of a pass because converting
// quaternions and chaining rotations per residual would be a large share of the backend's time.
struct FramePose {
  PoseMatrices T_w_c0;
  std::array<Eigen::Matrix3d, 2> R_cam_w;
};
using WindowPoses = std::array<FramePose, kMaxWindowFrames>;

class StereoResiduals {
 public:
  StereoResiduals() = default;
  // Uses the rig's first two cameras (checked by the caller); observation noise and Huber threshold in pixels.
  StereoResiduals(const StereoRig& rig, double obs_std_dev_px, double huber_px);

  // Every window slot's pose as FramePose.
  WindowPoses windowPoses(const Window& window) const;

  // Reprojection of lm into camera `cam` of window slot `frame`, minus its observation there; false
  // when the point cannot be projected or the residual is not finite. Takes the window's poses from
  // windowPoses() (still current) and the landmark's HostBearing, built from poses[lm.host]
  // (with_jacobian when jac is asked for): what a pass over all of a landmark's residuals computes once. In the host
  // frame no pose Jacobian is set (its relative pose is the fixed extrinsic) unless Jacobians are asked for with
  // kHostAndTarget or kTargetOnly; the residual itself is the same whether Jacobians are asked for or not.
  bool residual(const WindowPoses& poses, const HostBearing& bearing, const Landmark& lm, int frame, int cam,
                Eigen::Vector2d& r, ReprojectionJacobians* jac,
                PoseJacobians pose_jacobians = PoseJacobians::kHostAndTarget) const {
    Eigen::Vector2d uv;
    const auto c = static_cast<std::size_t>(cam);
    const auto f = static_cast<std::size_t>(frame);
    const bool target_jacobian =
        pose_jacobians == PoseJacobians::kHostAndTarget || pose_jacobians == PoseJacobians::kTargetOnly;
    if (frame == lm.host && (jac == nullptr || !target_jacobian)) {
      if (!reprojectInHost(cameras_[c], cam0_cam_[c].R_inv, offset_cam_[c], cam == 0, bearing, lm.rho, uv,
                           jac != nullptr ? &jac->d_landmark : nullptr)) {
        return false;
      }
    } else if (!reprojectLandmark(cameras_[c], poses[static_cast<std::size_t>(lm.host)].T_w_c0.t, bearing,
                                  targetCamera(poses, f, c), lm.rho, uv, jac, pose_jacobians)) {
      return false;
    }
    r = uv - lm.px[f][c];
    return r.allFinite();
  }
  // Every residual of lm, at the bits of lm.mask, into r[i] for the i-th bit in mask order (and,
  // when jac is set, the Jacobians the window's linearisation asks for into jac[i]: the host's pose
  // Jacobian in frames other than the host, none in the host frame). The same values as residual()
  // one by one; each camera's projections go two at a time through GenericCamera::projectPair.
  // Returns the bits whose residual is valid (projected and finite); r and jac hold
  // 2 * kMaxWindowFrames entries.
  std::uint32_t landmarkResiduals(const WindowPoses& poses, const HostBearing& bearing, const Landmark& lm,
                                  Eigen::Vector2d* r, ReprojectionJacobians* jac) const {
    constexpr std::size_t kMaxResiduals = 2 * kMaxWindowFrames;
    std::array<PointInTarget, kMaxResiduals> points;
    std::array<Eigen::Vector2d, kMaxResiduals> uv;
    std::array<Eigen::Matrix<double, 2, 3>, kMaxResiduals> d_uv_d_p;
    std::array<std::array<std::size_t, kMaxResiduals>, 2> of_camera;
    std::array<std::size_t, 2> in_camera{0, 0};
    const auto host = static_cast<std::size_t>(lm.host);
    std::size_t count = 0;
    for (std::uint32_t m = lm.mask; m != 0; m &= m - 1, ++count) {
      const int bit = std::countr_zero(m);
      const auto f = static_cast<std::size_t>(bit / 2), c = static_cast<std::size_t>(bit % 2);
      if (f == host) {
        points[count].p_cam = pointInHost(cam0_cam_[c].R_inv, offset_cam_[c], c == 0, bearing, lm.rho);
      } else {
        points[count] = pointInTarget(poses[host].T_w_c0.t, bearing, targetCamera(poses, f, c), lm.rho);
      }
      of_camera[c][in_camera[c]++] = count;
    }
    std::uint32_t projected = 0;  // by position in mask order
    for (std::size_t c = 0; c < 2; ++c) {
      std::size_t k = 0;
      for (; k + 1 < in_camera[c]; k += 2) {
        const std::size_t a = of_camera[c][k], b = of_camera[c][k + 1];
        const unsigned pair =
            cameras_[c].projectPair({&points[a].p_cam, &points[b].p_cam}, {&uv[a], &uv[b]},
                                    {jac != nullptr ? &d_uv_d_p[a] : nullptr, jac != nullptr ? &d_uv_d_p[b] : nullptr});
        projected |= (pair & 1u) << a | (pair >> 1) << b;
      }
      if (k < in_camera[c]) {
        const std::size_t a = of_camera[c][k];
        if (cameras_[c].project(points[a].p_cam, uv[a], jac != nullptr ? &d_uv_d_p[a] : nullptr)) projected |= 1u << a;
      }
    }
    std::uint32_t valid = 0;
    count = 0;
    for (std::uint32_t m = lm.mask; m != 0; m &= m - 1, ++count) {
      if ((projected & (1u << count)) == 0) continue;
      const int bit = std::countr_zero(m);
      const auto f = static_cast<std::size_t>(bit / 2), c = static_cast<std::size_t>(bit % 2);
      if (jac != nullptr) {
        if (f == host) {
          hostJacobian(d_uv_d_p[count], cam0_cam_[c].R_inv, offset_cam_[c], c == 0, bearing, jac[count].d_landmark);
        } else {
          targetJacobians(d_uv_d_p[count], points[count], bearing, targetCamera(poses, f, c), lm.rho, jac[count],
                          PoseJacobians::kHost);
        }
      }
      r[count] = uv[count] - lm.px[f][c];
      if (r[count].allFinite()) valid |= 1u << bit;
    }
    return valid;
  }

  // Weight of a residual of norm e in the normal equations (inverse variance times the Huber weight).
  double weight(double e) const { return inv_var_ * (e <= huber_px_ ? 1.0 : huber_px_ / e); }
  // Its robust cost.
  double cost(double e) const { return inv_var_ * (e <= huber_px_ ? 0.5 * e * e : huber_px_ * (e - 0.5 * huber_px_)); }

  const GenericCamera<double>& camera(int cam) const { return cameras_[static_cast<std::size_t>(cam)]; }
  const SE3d& T_cam0_cam(int cam) const { return T_cam0_cam_[static_cast<std::size_t>(cam)]; }

 private:
  // Camera c of window slot f as the residual passes use it.
  TargetCamera targetCamera(const WindowPoses& poses, std::size_t f, std::size_t c) const {
    return TargetCamera{poses[f].R_cam_w[c], poses[f].T_w_c0.t, offset_cam_[c]};
  }

  std::array<GenericCamera<double>, 2> cameras_;
  std::array<SE3d, 2> T_cam0_cam_;
  std::array<PoseMatrices, 2> cam0_cam_;       // T_cam0_cam_ as matrices
  std::array<Eigen::Vector3d, 2> offset_cam_;  // R_cam_cam0 * t_cam0_cam (see TargetCamera)
  double huber_px_ = 1.0;
  double inv_var_ = 4.0;
};

}  // namespace voca::backend
