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
// for every residual would be a large share of the backend's time. Holds exactly what converting per
// residual gives, so the values are the same either way.
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
  Eigen::Matrix<double, 3, 2> d_b_d_s;   // set only with_jacobian
  Eigen::Vector3d Rb_w;                  // host.R * b
  Eigen::Matrix<double, 3, 2> d_Rb_d_s;  // host.R * d_b_d_s, set only with_jacobian

  HostBearing() = default;
  HostBearing(const PoseMatrices& host, const Eigen::Vector2d& s, bool with_jacobian) {
    b = stereographicUnproject(s, with_jacobian ? &d_b_d_s : nullptr);
    Rb_w = host.R * b;
    if (with_jacobian) d_Rb_d_s.noalias() = host.R * d_b_d_s;
  }
};

// A target camera as the residual passes use it: the rotation from world axes into the camera
// (R_cam_cam0 * R_target^T, once per frame and camera instead of two rotations per residual), the
// target frame's cam0 origin in the world, and the camera's offset in its own axes
// (R_cam_cam0 * t_cam0_cam, zero for cam0).
struct TargetCamera {
  const Eigen::Matrix3d& R_cam_w;
  const Eigen::Vector3d& t_w_target;
  const Eigen::Vector3d& offset_cam;
};

// A hat(w) and hat(w) X for w's skew matrix, from the two non-zero terms of each entry: the 3x3
// products spend a third of their multiplications on its zeros. Each entry sums the same two
// products as the matrix product does, so the values are the same (up to the sign of a zero).
template <int Rows>
Eigen::Matrix<double, Rows, 3> timesHat(const Eigen::Matrix<double, Rows, 3>& A, const Eigen::Vector3d& w) {
  Eigen::Matrix<double, Rows, 3> Y;
  Y.col(0) = A.col(1) * w(2) - A.col(2) * w(1);
  Y.col(1) = A.col(2) * w(0) - A.col(0) * w(2);
  Y.col(2) = A.col(0) * w(1) - A.col(1) * w(0);
  return Y;
}
template <int Cols>
Eigen::Matrix<double, 3, Cols> hatTimes(const Eigen::Vector3d& w, const Eigen::Matrix<double, 3, Cols>& X) {
  Eigen::Matrix<double, 3, Cols> Y;
  Y.row(0) = w(1) * X.row(2) - w(2) * X.row(1);
  Y.row(1) = w(2) * X.row(0) - w(0) * X.row(2);
  Y.row(2) = w(0) * X.row(1) - w(1) * X.row(0);
  return Y;
}

// Which pose Jacobians reprojectLandmark fills: none (a residual in its host frame, whose relative
// pose is the fixed extrinsic), the host's only (the window's linearisation derives the target's
// from it, see WindowOptimizer::linearize), both, or the target's alone without the landmark's (the
// pose-only step, which moves nothing else).
enum class PoseJacobians { kNone, kHost, kHostAndTarget, kTargetOnly };

// The landmark (bearing from HostBearing, built from the host's pose, and inverse distance rho in
// the host frame's cam0, whose origin is t_w_host) in a camera of a target frame, before projection.
// Works in homogeneous coordinates scaled by rho, so a point at infinity (rho = 0) is fine.
struct PointInTarget {
  Eigen::Vector3d dt_w;   // t_w_host - t_w_target
  Eigen::Vector3d v_w;    // the point relative to the target origin, in world axes, scaled by rho
  Eigen::Vector3d p_cam;  // in the target camera, scaled by rho
};
inline PointInTarget pointInTarget(const Eigen::Vector3d& t_w_host, const HostBearing& bearing,
                                   const TargetCamera& target, double rho) {
  PointInTarget point;
  point.dt_w = t_w_host - target.t_w_target;
  point.v_w = bearing.Rb_w + point.dt_w * rho;
  point.p_cam = target.R_cam_w * point.v_w - target.offset_cam * rho;
  return point;
}

// The Jacobians of its pixel from the camera's d_uv_d_p: d_landmark (except with kTargetOnly) and
// the pose blocks as `poses` says.
inline void targetJacobians(const Eigen::Matrix<double, 2, 3>& d_uv_d_p, const PointInTarget& point,
                            const HostBearing& bearing, const TargetCamera& target, double rho,
                            ReprojectionJacobians& jacobians, PoseJacobians poses) {
  const Eigen::Vector3d& Rb_w = bearing.Rb_w;
  const Eigen::Matrix<double, 2, 3> d_uv_d_v = d_uv_d_p * target.R_cam_w;
  if (poses == PoseJacobians::kHost || poses == PoseJacobians::kHostAndTarget) {
    jacobians.d_host.leftCols<3>() = d_uv_d_v * rho;
    jacobians.d_host.rightCols<3>() = -timesHat(d_uv_d_v, Rb_w);
  }
  if (poses == PoseJacobians::kHostAndTarget || poses == PoseJacobians::kTargetOnly) {
    jacobians.d_target.leftCols<3>() = -d_uv_d_v * rho;
    // R_t <- exp(w) R_t turns R_t^T v into R_t^T exp(-w) v ~ R_t^T (v + v^ w).
    jacobians.d_target.rightCols<3>() = timesHat(d_uv_d_v, point.v_w);
  }
  if (poses == PoseJacobians::kTargetOnly) return;
  jacobians.d_landmark.leftCols<2>() = d_uv_d_v * bearing.d_Rb_d_s;
  jacobians.d_landmark.col(2) = d_uv_d_v * point.dt_w - d_uv_d_p * target.offset_cam;
}

// Projects the landmark into a camera of a target frame (pointInTarget, the camera, then
// targetJacobians). Returns false when the camera model cannot project it.
inline bool reprojectLandmark(const GenericCamera<double>& camera, const Eigen::Vector3d& t_w_host,
                              const HostBearing& bearing, const TargetCamera& target, double rho, Eigen::Vector2d& uv,
                              ReprojectionJacobians* jacobians = nullptr,
                              PoseJacobians poses = PoseJacobians::kHostAndTarget) {
  const PointInTarget point = pointInTarget(t_w_host, bearing, target, rho);
  Eigen::Matrix<double, 2, 3> d_uv_d_p;
  if (!camera.project(point.p_cam, uv, jacobians != nullptr ? &d_uv_d_p : nullptr)) return false;
  if (jacobians != nullptr) targetJacobians(d_uv_d_p, point, bearing, target, rho, *jacobians, poses);
  return true;
}

// A residual's Jacobian by its target pose is its Jacobian by its host pose times
//   D = [[-I, dt^], [0, -I]],  dt = t_w_host - t_w_target,
// (above: d_host = [rho A, -A Rb^], d_target = [-rho A, A (Rb + rho dt)^]). So the window's
// linearisation sums J_host^T W J_host per (host, target) pair and maps it to the target's blocks
// once per pair instead of forming J_target per residual. These apply D without forming it:
// D^T X = [-X_top; -dt^ X_top - X_bottom] ...
template <int Cols>
Eigen::Matrix<double, 6, Cols> hostToTargetTransposed(const Eigen::Vector3d& dt,
                                                      const Eigen::Matrix<double, 6, Cols>& X) {
  Eigen::Matrix<double, 6, Cols> Y;
  Y.template topRows<3>() = -X.template topRows<3>();
  Y.template bottomRows<3>() = -hatTimes<Cols>(dt, X.template topRows<3>());
  Y.template bottomRows<3>() -= X.template bottomRows<3>();
  return Y;
}
// ... and X D = [-X_left, X_left dt^ - X_right].
template <int Rows>
Eigen::Matrix<double, Rows, 6> timesHostToTarget(const Eigen::Vector3d& dt, const Eigen::Matrix<double, Rows, 6>& X) {
  Eigen::Matrix<double, Rows, 6> Y;
  Y.template leftCols<3>() = -X.template leftCols<3>();
  Y.template rightCols<3>() = timesHat<Rows>(X.template leftCols<3>(), dt);
  Y.template rightCols<3>() -= X.template rightCols<3>();
  return Y;
}

// The same for a camera of the host frame itself: the point is the bearing moved by the fixed
// extrinsic (cam0: the bearing itself), with no pose Jacobian. R_cam_cam0 and offset_cam as in
// TargetCamera; cam0 says the camera is the host's cam0 (identity extrinsic).
inline Eigen::Vector3d pointInHost(const Eigen::Matrix3d& R_cam_cam0, const Eigen::Vector3d& offset_cam, bool cam0,
                                   const HostBearing& bearing, double rho) {
  if (cam0) return bearing.b;
  return R_cam_cam0 * bearing.b - offset_cam * rho;
}
inline void hostJacobian(const Eigen::Matrix<double, 2, 3>& d_uv_d_p, const Eigen::Matrix3d& R_cam_cam0,
                         const Eigen::Vector3d& offset_cam, bool cam0, const HostBearing& bearing,
                         Eigen::Matrix<double, 2, 3>& d_landmark) {
  if (cam0) {
    d_landmark.leftCols<2>() = d_uv_d_p * bearing.d_b_d_s;
    d_landmark.col(2).setZero();
    return;
  }
  const Eigen::Matrix<double, 2, 3> d_uv_d_cam0 = d_uv_d_p * R_cam_cam0;
  d_landmark.leftCols<2>() = d_uv_d_cam0 * bearing.d_b_d_s;
  d_landmark.col(2) = -d_uv_d_p * offset_cam;
}
inline bool reprojectInHost(const GenericCamera<double>& camera, const Eigen::Matrix3d& R_cam_cam0,
                            const Eigen::Vector3d& offset_cam, bool cam0, const HostBearing& bearing, double rho,
                            Eigen::Vector2d& uv, Eigen::Matrix<double, 2, 3>* d_landmark = nullptr) {
  Eigen::Matrix<double, 2, 3> d_uv_d_p;
  const Eigen::Vector3d p_cam = pointInHost(R_cam_cam0, offset_cam, cam0, bearing, rho);
  if (!camera.project(p_cam, uv, d_landmark != nullptr ? &d_uv_d_p : nullptr)) return false;
  if (d_landmark != nullptr) hostJacobian(d_uv_d_p, R_cam_cam0, offset_cam, cam0, bearing, *d_landmark);
  return true;
}

// The same from the poses themselves: T_world_host, T_world_target and T_cam0_cam (every Jacobian).
inline bool reprojectLandmark(const GenericCamera<double>& camera, const SE3d& T_world_host, const SE3d& T_world_target,
                              const SE3d& T_cam0_cam, const Eigen::Vector2d& s, double rho, Eigen::Vector2d& uv,
                              ReprojectionJacobians* jacobians = nullptr) {
  const PoseMatrices host(T_world_host), target(T_world_target), cam0_cam(T_cam0_cam);
  const Eigen::Matrix3d R_cam_w = cam0_cam.R_inv * target.R_inv;
  const Eigen::Vector3d offset_cam = cam0_cam.R_inv * cam0_cam.t;
  return reprojectLandmark(camera, host.t, HostBearing(host, s, jacobians != nullptr),
                           TargetCamera{R_cam_w, target.t, offset_cam}, rho, uv, jacobians);
}

}  // namespace voca
