#pragma once
#include <Eigen/Core>
#include <array>

#include "voca/camera/camera_math.h"

namespace voca {

// Ideal pinhole: u = fx x/z + cx, v = fy y/z + cy. Parameters fx fy cx cy.
template <typename Scalar>
class PinholeCamera {
 public:
  static constexpr int kNumParams = 4;
  static constexpr const char* kName = "pinhole";
  static constexpr std::array<const char*, kNumParams> kParamNames{"fx", "fy", "cx", "cy"};
  using Vec2 = Eigen::Matrix<Scalar, 2, 1>;
  using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
  using Mat23 = Eigen::Matrix<Scalar, 2, 3>;
  using Mat32 = Eigen::Matrix<Scalar, 3, 2>;
  using Params = Eigen::Matrix<Scalar, kNumParams, 1>;
  using ParamJacobian = Eigen::Matrix<Scalar, 2, kNumParams>;

  explicit PinholeCamera(const Params& params) : params_(params) {}
  const Params& params() const { return params_; }
  template <typename Other>
  PinholeCamera<Other> cast() const {
    return PinholeCamera<Other>(params_.template cast<Other>());
  }

  // False for points on or behind the image plane (z <= 0).
  bool project(const Vec3& p_cam, Vec2& uv, Mat23* d_uv_d_p = nullptr, ParamJacobian* d_uv_d_params = nullptr) const {
    const Scalar fx = params_[0], fy = params_[1], cx = params_[2], cy = params_[3];
    const Scalar x = p_cam[0], y = p_cam[1], z = p_cam[2];
    if (!(z > Scalar(0))) return false;
    const Scalar inv_z = Scalar(1) / z;
    const Scalar mx = x * inv_z, my = y * inv_z;
    uv << fx * mx + cx, fy * my + cy;
    if (d_uv_d_p) {
      *d_uv_d_p << fx * inv_z, Scalar(0), -fx * mx * inv_z,  //
          Scalar(0), fy * inv_z, -fy * my * inv_z;
    }
    if (d_uv_d_params) {
      *d_uv_d_params << mx, Scalar(0), Scalar(1), Scalar(0),  //
          Scalar(0), my, Scalar(0), Scalar(1);
    }
    return true;
  }

  // Every pixel has a bearing.
  bool unproject(const Vec2& uv, Vec3& bearing, Mat32* d_bearing_d_uv = nullptr) const {
    const Scalar fx = params_[0], fy = params_[1], cx = params_[2], cy = params_[3];
    const Vec3 m((uv[0] - cx) / fx, (uv[1] - cy) / fy, Scalar(1));
    Eigen::Matrix<Scalar, 3, 3> d_b_d_m;
    bearing = camera_detail::normalizeWithJacobian<Scalar>(m, d_bearing_d_uv ? &d_b_d_m : nullptr);
    if (d_bearing_d_uv) {
      d_bearing_d_uv->col(0) = d_b_d_m.col(0) / fx;
      d_bearing_d_uv->col(1) = d_b_d_m.col(1) / fy;
    }
    return true;
  }

 private:
  Params params_;
};

}  // namespace voca
