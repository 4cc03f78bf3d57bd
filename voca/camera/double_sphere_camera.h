#pragma once
#include <Eigen/Core>
#include <array>
#include <cmath>

#include "voca/camera/camera_math.h"

namespace voca {

// Double sphere model. d1 = |p|, d2 = |(x, y, xi d1 + z)|,
// u = fx x / (alpha d2 + (1 - alpha)(xi d1 + z)) + cx. Parameters fx fy cx cy xi alpha.
// Formulas and valid region after Usenko, Demmel, Cremers, "The Double Sphere Camera Model", 3DV 2018.
template <typename Scalar>
class DoubleSphereCamera {
 public:
  static constexpr int kNumParams = 6;
  static constexpr const char* kName = "ds";
  static constexpr std::array<const char*, kNumParams> kParamNames{"fx", "fy", "cx", "cy", "xi", "alpha"};
  using Vec2 = Eigen::Matrix<Scalar, 2, 1>;
  using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
  using Mat23 = Eigen::Matrix<Scalar, 2, 3>;
  using Mat32 = Eigen::Matrix<Scalar, 3, 2>;
  using Params = Eigen::Matrix<Scalar, kNumParams, 1>;
  using ParamJacobian = Eigen::Matrix<Scalar, 2, kNumParams>;

  explicit DoubleSphereCamera(const Params& params) : params_(params) {
    const Scalar xi = params_[4], alpha = params_[5];
    const Scalar w1 = camera_detail::validRegionWeight(alpha);
    const Scalar w2_den = Scalar(2) * w1 * xi + xi * xi + Scalar(1);
    // w2_den = (w1 + xi)^2 + 1 - w1^2 >= 0 since w1 <= 1; it is zero only for alpha = 0.5, xi = -1.
    w2_ = w2_den > Scalar(0) ? (w1 + xi) / std::sqrt(w2_den) : Scalar(1);
  }
  const Params& params() const { return params_; }
  template <typename Other>
  DoubleSphereCamera<Other> cast() const {
    return DoubleSphereCamera<Other>(params_.template cast<Other>());
  }

  // False outside the valid region z > -w2 d1 (paper, eq. for Omega of the double sphere model).
  bool project(const Vec3& p_cam, Vec2& uv, Mat23* d_uv_d_p = nullptr, ParamJacobian* d_uv_d_params = nullptr) const {
    const Scalar fx = params_[0], fy = params_[1], cx = params_[2], cy = params_[3];
    const Scalar xi = params_[4], alpha = params_[5];
    const Scalar x = p_cam[0], y = p_cam[1], z = p_cam[2];
    const Scalar r2 = x * x + y * y;
    const Scalar d1 = std::sqrt(r2 + z * z);
    if (!(z > -w2_ * d1)) return false;
    const Scalar k = xi * d1 + z;
    const Scalar d2 = std::sqrt(r2 + k * k);
    const Scalar den = alpha * d2 + (Scalar(1) - alpha) * k;
    if (!(den > Scalar(0))) return false;
    const Scalar inv_den = Scalar(1) / den;
    const Scalar mx = x * inv_den, my = y * inv_den;
    uv << fx * mx + cx, fy * my + cy;
    if (d_uv_d_p) {
      const Vec3 d_d1_d_p = p_cam / d1;
      Vec3 d_k_d_p = xi * d_d1_d_p;
      d_k_d_p[2] += Scalar(1);
      const Vec3 d_d2_d_p = (Vec3(x, y, Scalar(0)) + k * d_k_d_p) / d2;
      const Vec3 d_den_d_p = alpha * d_d2_d_p + (Scalar(1) - alpha) * d_k_d_p;
      camera_detail::projectionOverDenominatorJacobian(fx, fy, mx, my, inv_den, d_den_d_p, *d_uv_d_p);
    }
    if (d_uv_d_params) {
      const Scalar d_den_d_xi = alpha * k * d1 / d2 + (Scalar(1) - alpha) * d1;
      const Scalar d_den_d_alpha = d2 - k;
      camera_detail::projectionOverDenominatorParamJacobian(fx, fy, mx, my, inv_den, d_den_d_xi, d_den_d_alpha,
                                                            *d_uv_d_params);
    }
    return true;
  }

  // Closed form; false outside the unprojection domain r^2 < 1/(2 alpha - 1) (alpha > 0.5).
  bool unproject(const Vec2& uv, Vec3& bearing, Mat32* d_bearing_d_uv = nullptr) const {
    const Scalar fx = params_[0], fy = params_[1];
    const Scalar xi = params_[4], alpha = params_[5];
    const Scalar mx = (uv[0] - params_[2]) / fx, my = (uv[1] - params_[3]) / fy;
    const Scalar r2 = mx * mx + my * my;
    const Scalar s2 = Scalar(1) - (Scalar(2) * alpha - Scalar(1)) * r2;
    if (!(s2 > Scalar(0))) return false;
    const Scalar s = std::sqrt(s2);
    const Scalar q = alpha * s + Scalar(1) - alpha;
    const Scalar n = Scalar(1) - alpha * alpha * r2;
    const Scalar mz = n / q;
    const Scalar t2 = mz * mz + (Scalar(1) - xi * xi) * r2;
    if (!(t2 >= Scalar(0))) return false;
    const Scalar t = std::sqrt(t2);
    const Scalar num = mz * xi + t;
    const Scalar dd = mz * mz + r2;
    const Scalar f = num / dd;
    bearing << f * mx, f * my, f * mz - xi;
    if (d_bearing_d_uv) {
      if (!(t > Scalar(0))) return false;
      const Scalar d_q_d_r2 = -alpha * (Scalar(2) * alpha - Scalar(1)) / (Scalar(2) * s);
      const Scalar d_mz_d_r2 = (-alpha * alpha * q - n * d_q_d_r2) / (q * q);
      const Scalar d_t_d_r2 = (Scalar(2) * mz * d_mz_d_r2 + Scalar(1) - xi * xi) / (Scalar(2) * t);
      const Scalar d_num_d_r2 = xi * d_mz_d_r2 + d_t_d_r2;
      const Scalar d_dd_d_r2 = Scalar(2) * mz * d_mz_d_r2 + Scalar(1);
      const Scalar d_f_d_r2 = (d_num_d_r2 * dd - num * d_dd_d_r2) / (dd * dd);
      const Eigen::Matrix<Scalar, 1, 2> d_r2_d_m(Scalar(2) * mx, Scalar(2) * my);
      Mat32 d_b_d_m = Vec3(mx, my, mz) * (d_f_d_r2 * d_r2_d_m);
      d_b_d_m(0, 0) += f;
      d_b_d_m(1, 1) += f;
      d_b_d_m.row(2) += f * d_mz_d_r2 * d_r2_d_m;
      d_b_d_m.col(0) /= fx;
      d_b_d_m.col(1) /= fy;
      *d_bearing_d_uv = d_b_d_m;
    }
    return true;
  }

 private:
  Params params_;
  Scalar w2_;
};

}  // namespace voca
