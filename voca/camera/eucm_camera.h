#pragma once
#include <Eigen/Core>
#include <array>
#include <cmath>

#include "voca/camera/camera_math.h"

namespace voca {

// Extended unified camera model. d = sqrt(beta (x^2 + y^2) + z^2),
// u = fx x / (alpha d + (1 - alpha) z) + cx. Parameters fx fy cx cy alpha beta.
// Formulas and valid region after Usenko, Demmel, Cremers, "The Double Sphere Camera Model", 3DV 2018.
template <typename Scalar>
class ExtendedUnifiedCamera {
 public:
  static constexpr int kNumParams = 6;
  static constexpr const char* kName = "eucm";
  static constexpr std::array<const char*, kNumParams> kParamNames{"fx", "fy", "cx", "cy", "alpha", "beta"};
  using Vec2 = Eigen::Matrix<Scalar, 2, 1>;
  using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
  using Mat23 = Eigen::Matrix<Scalar, 2, 3>;
  using Mat32 = Eigen::Matrix<Scalar, 3, 2>;
  using Params = Eigen::Matrix<Scalar, kNumParams, 1>;
  using ParamJacobian = Eigen::Matrix<Scalar, 2, kNumParams>;

  explicit ExtendedUnifiedCamera(const Params& params) : params_(params) {
    const Scalar alpha = params_[4];
    w_ = camera_detail::validRegionWeight(alpha);
  }
  const Params& params() const { return params_; }
  template <typename Other>
  ExtendedUnifiedCamera<Other> cast() const {
    return ExtendedUnifiedCamera<Other>(params_.template cast<Other>());
  }

  // False outside the valid region z > -w d (w: camera_detail::validRegionWeight).
  bool project(const Vec3& p_cam, Vec2& uv, Mat23* d_uv_d_p = nullptr, ParamJacobian* d_uv_d_params = nullptr) const {
    const Scalar fx = params_[0], fy = params_[1], cx = params_[2], cy = params_[3];
    const Scalar alpha = params_[4], beta = params_[5];
    const Scalar x = p_cam[0], y = p_cam[1], z = p_cam[2];
    const Scalar r2 = x * x + y * y;
    const Scalar d = std::sqrt(beta * r2 + z * z);
    if (!(z > -w_ * d)) return false;
    const Scalar den = alpha * d + (Scalar(1) - alpha) * z;
    if (!(den > Scalar(0))) return false;
    const Scalar inv_den = Scalar(1) / den;
    const Scalar mx = x * inv_den, my = y * inv_den;
    uv << fx * mx + cx, fy * my + cy;
    if (d_uv_d_p) {
      const Vec3 d_den_d_p = Vec3(alpha * beta * x / d, alpha * beta * y / d, alpha * z / d + Scalar(1) - alpha);
      camera_detail::projectionOverDenominatorJacobian(fx, fy, mx, my, inv_den, d_den_d_p, *d_uv_d_p);
    }
    if (d_uv_d_params) {
      const Scalar d_den_d_alpha = d - z;
      const Scalar d_den_d_beta = alpha * r2 / (Scalar(2) * d);
      camera_detail::projectionOverDenominatorParamJacobian(fx, fy, mx, my, inv_den, d_den_d_alpha, d_den_d_beta,
                                                            *d_uv_d_params);
    }
    return true;
  }

  // Closed form; false outside the unprojection domain r^2 < 1/(beta (2 alpha - 1)) (alpha > 0.5).
  bool unproject(const Vec2& uv, Vec3& bearing, Mat32* d_bearing_d_uv = nullptr) const {
    const Scalar fx = params_[0], fy = params_[1];
    const Scalar alpha = params_[4], beta = params_[5];
    const Scalar mx = (uv[0] - params_[2]) / fx, my = (uv[1] - params_[3]) / fy;
    const Scalar r2 = mx * mx + my * my;
    const Scalar s2 = Scalar(1) - (Scalar(2) * alpha - Scalar(1)) * beta * r2;
    if (!(s2 > Scalar(0))) return false;
    const Scalar s = std::sqrt(s2);
    const Scalar q = alpha * s + Scalar(1) - alpha;
    const Scalar n = Scalar(1) - beta * alpha * alpha * r2;
    const Scalar mz = n / q;
    Eigen::Matrix<Scalar, 3, 3> d_b_d_ray;
    bearing = camera_detail::normalizeWithJacobian<Scalar>(Vec3(mx, my, mz), d_bearing_d_uv ? &d_b_d_ray : nullptr);
    if (d_bearing_d_uv) {
      const Scalar d_q_d_r2 = -alpha * (Scalar(2) * alpha - Scalar(1)) * beta / (Scalar(2) * s);
      const Scalar d_mz_d_r2 = (-beta * alpha * alpha * q - n * d_q_d_r2) / (q * q);
      Mat32 d_ray_d_m = Mat32::Zero();
      d_ray_d_m(0, 0) = Scalar(1);
      d_ray_d_m(1, 1) = Scalar(1);
      d_ray_d_m(2, 0) = d_mz_d_r2 * Scalar(2) * mx;
      d_ray_d_m(2, 1) = d_mz_d_r2 * Scalar(2) * my;
      d_ray_d_m.col(0) /= fx;
      d_ray_d_m.col(1) /= fy;
      *d_bearing_d_uv = d_b_d_ray * d_ray_d_m;
    }
    return true;
  }

 private:
  Params params_;
  Scalar w_;
};

}  // namespace voca
