#pragma once
// The backend's measurement model: a landmark hosted in a keyframe's left camera as a stereographic
// bearing and an inverse distance, reprojected into any camera of any frame, with analytic Jacobians.

#include <Eigen/Core>

#include "voca/camera/generic_camera.h"
#include "voca/geometry/se3.h"

namespace voca {

// Unit bearing from 2-D stereographic coordinates s (the projection from the south pole onto the
// plane z = 0): b = (2 s, 1 - |s|^2) / (1 + |s|^2). Regular everywhere except the backward direction.
inline Eigen::Vector3d stereographicUnproject(const Eigen::Vector2d& s,
                                              Eigen::Matrix<double, 3, 2>* d_b_d_s = nullptr) {
  const double n2 = s.squaredNorm();
  const double inv = 1.0 / (1.0 + n2);
  const Eigen::Vector3d b(2.0 * s.x() * inv, 2.0 * s.y() * inv, (1.0 - n2) * inv);
  if (d_b_d_s != nullptr) {
    const double inv2 = inv * inv;
    (*d_b_d_s)(0, 0) = 2.0 * inv - 4.0 * s.x() * s.x() * inv2;
    (*d_b_d_s)(0, 1) = -4.0 * s.x() * s.y() * inv2;
    (*d_b_d_s)(1, 0) = (*d_b_d_s)(0, 1);
    (*d_b_d_s)(1, 1) = 2.0 * inv - 4.0 * s.y() * s.y() * inv2;
    (*d_b_d_s)(2, 0) = -4.0 * s.x() * inv2;
    (*d_b_d_s)(2, 1) = -4.0 * s.y() * inv2;
  }
  return b;
}

// Inverse of stereographicUnproject for any non-zero direction (normalised first).
inline Eigen::Vector2d stereographicProject(const Eigen::Vector3d& direction) {
  const Eigen::Vector3d b = direction.normalized();
  return b.head<2>() / (1.0 + b.z());
}

// Jacobians of the projected pixel. Pose increments xi = (v, w) act as t <- t + v, R <- exp(w) R
// (world-frame rotation), landmark increments as (s, inverse distance) <- + (ds, drho).
struct ReprojectionJacobians {
  Eigen::Matrix<double, 2, 6> d_host;
  Eigen::Matrix<double, 2, 6> d_target;
  Eigen::Matrix<double, 2, 3> d_landmark;
};

// A pose's rotation as a matrix, both ways, with its translation: computed once per pose and pass
// over the window's residuals, because converting the quaternions of host, target and extrinsic
// for every residual was a large share of the backend's time. Holds exactly what the conversion
// per residual gave, so results do not change.
struct PoseMatrices {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();      // T's rotation (frame -> parent)
  Eigen::Matrix3d R_inv = Eigen::Matrix3d::Identity();  // its transpose
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  PoseMatrices() = default;
  explicit PoseMatrices(const SE3d& T) { set(T); }
  void set(const SE3d& T) {
    R = T.rotationMatrix();
    R_inv = R.transpose();
    t = T.translation();
  }
};

// What every residual of one landmark shares: its unit bearing in the host's cam0 (with the
// derivative by s when Jacobians are wanted) and that bearing in world axes. Computed once per
// landmark and pass over the residuals instead of once per residual; the same values either way.
struct HostBearing {
  Eigen::Vector3d b;
  Eigen::Matrix<double, 3, 2> d_b_d_s;  // set only with_jacobian
  Eigen::Vector3d Rb_w;                 // host.R * b

  HostBearing() = default;
  HostBearing(const PoseMatrices& host, const Eigen::Vector2d& s, bool with_jacobian) {
    b = stereographicUnproject(s, with_jacobian ? &d_b_d_s : nullptr);
    Rb_w = host.R * b;
  }
};

// Projects the landmark (bearing from HostBearing and inverse distance rho in the host frame's cam0)
// into camera `camera` of the target frame, whose pose in that frame's cam0 is cam0_cam. host and
// target hold T_world_cam0 of the host and target frames; bearing must have been built from host
// (with_jacobian when jacobians are asked for). Works in homogeneous coordinates scaled by rho, so a
// point at infinity (rho = 0) is fine. Returns false when the camera model cannot project it.
// Without pose_jacobians only jacobians->d_landmark is set (what a residual in the host frame needs).
inline bool reprojectLandmark(const GenericCamera<double>& camera, const PoseMatrices& host, const HostBearing& bearing,
                              const PoseMatrices& target, const PoseMatrices& cam0_cam, double rho, Eigen::Vector2d& uv,
                              ReprojectionJacobians* jacobians = nullptr, bool pose_jacobians = true) {
  const Eigen::Matrix3d& R_w_h = host.R;
  const Eigen::Matrix3d& R_t_w = target.R_inv;
  const Eigen::Matrix3d& R_cam_cam0 = cam0_cam.R_inv;
  const Eigen::Vector3d dt_w = host.t - target.t;
  const Eigen::Vector3d& Rb_w = bearing.Rb_w;
  // v: the point relative to the target origin, in world axes, scaled by rho.
  const Eigen::Vector3d v_w = Rb_w + dt_w * rho;
  const Eigen::Vector3d p_cam = R_cam_cam0 * (R_t_w * v_w - cam0_cam.t * rho);
  Eigen::Matrix<double, 2, 3> d_uv_d_p;
  if (!camera.project(p_cam, uv, jacobians != nullptr ? &d_uv_d_p : nullptr)) return false;
  if (jacobians != nullptr) {
    const Eigen::Matrix<double, 2, 3> d_uv_d_cam0 = d_uv_d_p * R_cam_cam0;
    const Eigen::Matrix<double, 2, 3> d_uv_d_v = d_uv_d_cam0 * R_t_w;
    if (pose_jacobians) {
      jacobians->d_host.leftCols<3>() = d_uv_d_v * rho;
      jacobians->d_host.rightCols<3>() = -d_uv_d_v * SO3d::hat(Rb_w);
      jacobians->d_target.leftCols<3>() = -d_uv_d_v * rho;
      // R_t <- exp(w) R_t turns R_t^T v into R_t^T exp(-w) v ~ R_t^T (v + v^ w).
      jacobians->d_target.rightCols<3>() = d_uv_d_v * SO3d::hat(v_w);
    }
    jacobians->d_landmark.leftCols<2>() = d_uv_d_v * R_w_h * bearing.d_b_d_s;
    jacobians->d_landmark.col(2) = d_uv_d_v * dt_w - d_uv_d_cam0 * cam0_cam.t;
  }
  return true;
}

// The same with the landmark's stereographic bearing s.
inline bool reprojectLandmark(const GenericCamera<double>& camera, const PoseMatrices& host, const PoseMatrices& target,
                              const PoseMatrices& cam0_cam, const Eigen::Vector2d& s, double rho, Eigen::Vector2d& uv,
                              ReprojectionJacobians* jacobians = nullptr) {
  return reprojectLandmark(camera, host, HostBearing(host, s, jacobians != nullptr), target, cam0_cam, rho, uv,
                           jacobians);
}

// The same from the poses themselves: T_world_host, T_world_target and T_cam0_cam.
inline bool reprojectLandmark(const GenericCamera<double>& camera, const SE3d& T_world_host, const SE3d& T_world_target,
                              const SE3d& T_cam0_cam, const Eigen::Vector2d& s, double rho, Eigen::Vector2d& uv,
                              ReprojectionJacobians* jacobians = nullptr) {
  return reprojectLandmark(camera, PoseMatrices(T_world_host), PoseMatrices(T_world_target), PoseMatrices(T_cam0_cam),
                           s, rho, uv, jacobians);
}

}  // namespace voca
