#pragma once
#include <Eigen/Core>
#include <array>
#include <cmath>

#include "voca/camera/camera_math.h"

namespace voca {

VOCA_CAMERA_MODEL_COPY_WARNING_OFF

// Pinhole with OpenCV's rational radial (k1..k6) and tangential (p1, p2) distortion, Basalt's
// "pinhole-radtan8". Kalibr's "radtan" is the case k3 = k4 = k5 = k6 = 0.
// Parameters fx fy cx cy k1 k2 p1 p2 k3 k4 k5 k6.
template <typename Scalar>
class PinholeRadtan8Camera {
 public:
  static constexpr int kNumParams = 12;
  static constexpr const char* kName = "pinhole-radtan8";
  static constexpr std::array<const char*, kNumParams> kParamNames{"fx", "fy", "cx", "cy", "k1", "k2",
                                                                   "p1", "p2", "k3", "k4", "k5", "k6"};
  using Vec2 = Eigen::Matrix<Scalar, 2, 1>;
  using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
  using Mat22 = Eigen::Matrix<Scalar, 2, 2>;
  using Mat23 = Eigen::Matrix<Scalar, 2, 3>;
  using Mat32 = Eigen::Matrix<Scalar, 3, 2>;
  using Params = Eigen::Matrix<Scalar, kNumParams, 1>;
  using ParamJacobian = Eigen::Matrix<Scalar, 2, kNumParams>;

  // Normalised radius (tan of the angle off the axis) searched for the end of the monotonic
  // region; beyond ~87 degrees a pinhole image is useless anyway.
  static constexpr double kMaxSearchedRadius = 20.0;

  explicit PinholeRadtan8Camera(const Params& params) : params_(params) {
    max_radius_ = Scalar(computeMaxRadius(params_.template cast<double>()));
    rational_ = params_[9] != Scalar(0) || params_[10] != Scalar(0) || params_[11] != Scalar(0);
  }
  const Params& params() const { return params_; }
  template <typename Other>
  PinholeRadtan8Camera<Other> cast() const {
    return PinholeRadtan8Camera<Other>(params_.template cast<Other>());
  }
  // Normalised radius r = |(x/z, y/z)| where r * radial(r) stops increasing (or the rational
  // denominator reaches zero); points beyond it would fold back into the image.
  Scalar maxRadius() const { return max_radius_; }

  // False for z <= 0 and for points whose normalised radius exceeds maxRadius().
  bool project(const Vec3& p_cam, Vec2& uv, Mat23* d_uv_d_p = nullptr, ParamJacobian* d_uv_d_params = nullptr) const {
    const Scalar x = p_cam[0], y = p_cam[1], z = p_cam[2];
    if (!(z > Scalar(0))) return false;
    const Scalar inv_z = Scalar(1) / z;
    const Vec2 m(x * inv_z, y * inv_z);
    if (!(m.squaredNorm() <= max_radius_ * max_radius_)) return false;
    Vec2 distorted;
    Mat22 d_dist_d_m;
    distort(m, distorted, d_uv_d_p ? &d_dist_d_m : nullptr, d_uv_d_params);
    const Scalar fx = params_[0], fy = params_[1];
    uv << fx * distorted[0] + params_[2], fy * distorted[1] + params_[3];
    if (d_uv_d_p) {
      Mat23 d_m_d_p;
      d_m_d_p << inv_z, Scalar(0), -m[0] * inv_z,  //
          Scalar(0), inv_z, -m[1] * inv_z;
      *d_uv_d_p = d_dist_d_m * d_m_d_p;
      d_uv_d_p->row(0) *= fx;
      d_uv_d_p->row(1) *= fy;
    }
    return true;
  }

  // Inverts the distortion with Newton steps (halved when they do not reduce the residual).
  // False when the iteration does not converge or lands beyond maxRadius().
  bool unproject(const Vec2& uv, Vec3& bearing, Mat32* d_bearing_d_uv = nullptr) const {
    const Scalar fx = params_[0], fy = params_[1];
    const Vec2 target((uv[0] - params_[2]) / fx, (uv[1] - params_[3]) / fy);
    Vec2 m = target;
    Vec2 distorted;
    Mat22 jacobian;
    distort(m, distorted, &jacobian, nullptr);
    Vec2 residual = distorted - target;
    const Scalar tight = camera_detail::tightTolerance<Scalar>(target.norm());
    const Scalar loose = camera_detail::looseTolerance<Scalar>(target.norm());
    for (int iteration = 0; iteration < camera_detail::kMaxUnprojectIterations; ++iteration) {
      if (residual.norm() <= tight) break;
      Mat22 inverse;
      if (!camera_detail::invert2x2<Scalar>(jacobian, inverse)) return false;
      Vec2 step = -inverse * residual;
      // Halving keeps a far-off first guess from jumping past the monotonic region. Within the
      // loose tolerance a full step that does not decrease the residual means it is at its
      // rounding floor, so halving would only cost time.
      const int max_halvings = residual.norm() > loose ? camera_detail::kMaxStepHalvings : 0;
      bool improved = false;
      for (int halving = 0; halving <= max_halvings && !improved; ++halving, step *= Scalar(0.5)) {
        const Vec2 candidate = m + step;
        Vec2 candidate_distorted;
        Mat22 candidate_jacobian;
        distort(candidate, candidate_distorted, &candidate_jacobian, nullptr);
        const Vec2 candidate_residual = candidate_distorted - target;
        if (candidate_residual.norm() < residual.norm()) {
          m = candidate;
          jacobian = candidate_jacobian;
          residual = candidate_residual;
          improved = true;
        }
      }
      if (!improved) break;
    }
    if (!(residual.norm() <= loose)) return false;
    if (!(m.squaredNorm() <= max_radius_ * max_radius_)) return false;

    const Vec3 ray(m[0], m[1], Scalar(1));
    Eigen::Matrix<Scalar, 3, 3> d_b_d_ray;
    bearing = camera_detail::normalizeWithJacobian<Scalar>(ray, d_bearing_d_uv ? &d_b_d_ray : nullptr);
    if (d_bearing_d_uv) {
      // Implicit function theorem: d m / d target = (d distorted / d m)^-1.
      Mat22 d_m_d_target;
      if (!camera_detail::invert2x2<Scalar>(jacobian, d_m_d_target)) return false;
      d_m_d_target.col(0) /= fx;
      d_m_d_target.col(1) /= fy;
      *d_bearing_d_uv = d_b_d_ray.template leftCols<2>() * d_m_d_target;
    }
    return true;
  }

 private:
  // Distorted normalised coordinates of m = (x/z, y/z), the Jacobian w.r.t. m, and (when asked) the
  // full pixel Jacobian w.r.t. the parameters.
  void distort(const Vec2& m, Vec2& distorted, Mat22* d_dist_d_m, ParamJacobian* d_uv_d_params) const {
    const Scalar k1 = params_[4], k2 = params_[5], p1 = params_[6], p2 = params_[7];
    const Scalar k3 = params_[8], k4 = params_[9], k5 = params_[10], k6 = params_[11];
    const Scalar mx = m[0], my = m[1];
    const Scalar r2 = mx * mx + my * my, r4 = r2 * r2, r6 = r4 * r2;
    const Scalar num = Scalar(1) + k1 * r2 + k2 * r4 + k3 * r6;
    // Without k4..k6 (Kalibr's radtan) the denominator is exactly 1: skipping its division gives the
    // same values bit for bit, and saves a division on every projection.
    const Scalar den = rational_ ? Scalar(1) + k4 * r2 + k5 * r4 + k6 * r6 : Scalar(1);
    const Scalar inv_den = rational_ ? Scalar(1) / den : Scalar(1);
    const Scalar radial = rational_ ? num * inv_den : num;
    const Scalar mxy = mx * my;
    distorted << mx * radial + Scalar(2) * p1 * mxy + p2 * (r2 + Scalar(2) * mx * mx),
        my * radial + Scalar(2) * p2 * mxy + p1 * (r2 + Scalar(2) * my * my);
    if (d_dist_d_m) {
      const Scalar d_num = k1 + Scalar(2) * k2 * r2 + Scalar(3) * k3 * r4;
      const Scalar d_den = k4 + Scalar(2) * k5 * r2 + Scalar(3) * k6 * r4;
      const Scalar d_radial_d_r2 = rational_ ? (d_num * den - num * d_den) * inv_den * inv_den : d_num;
      const Scalar two_r = Scalar(2) * d_radial_d_r2;
      (*d_dist_d_m)(0, 0) = radial + two_r * mx * mx + Scalar(2) * p1 * my + Scalar(6) * p2 * mx;
      (*d_dist_d_m)(0, 1) = two_r * mxy + Scalar(2) * p1 * mx + Scalar(2) * p2 * my;
      (*d_dist_d_m)(1, 0) = two_r * mxy + Scalar(2) * p2 * my + Scalar(2) * p1 * mx;
      (*d_dist_d_m)(1, 1) = radial + two_r * my * my + Scalar(2) * p2 * mx + Scalar(6) * p1 * my;
    }
    if (d_uv_d_params) {
      const Scalar fx = params_[0], fy = params_[1];
      ParamJacobian& j = *d_uv_d_params;
      j.setZero();
      j(0, 0) = distorted[0];
      j(1, 1) = distorted[1];
      j(0, 2) = Scalar(1);
      j(1, 3) = Scalar(1);
      const Scalar num_scale = inv_den;
      const Scalar den_scale = -radial * inv_den;
      const std::array<Scalar, 3> powers{r2, r4, r6};
      const std::array<int, 3> num_index{4, 5, 8};    // k1 k2 k3
      const std::array<int, 3> den_index{9, 10, 11};  // k4 k5 k6
      for (int i = 0; i < 3; ++i) {
        j(0, num_index[i]) = fx * mx * powers[i] * num_scale;
        j(1, num_index[i]) = fy * my * powers[i] * num_scale;
        j(0, den_index[i]) = fx * mx * powers[i] * den_scale;
        j(1, den_index[i]) = fy * my * powers[i] * den_scale;
      }
      j(0, 6) = fx * Scalar(2) * mxy;
      j(1, 6) = fy * (r2 + Scalar(2) * my * my);
      j(0, 7) = fx * (r2 + Scalar(2) * mx * mx);
      j(1, 7) = fy * Scalar(2) * mxy;
    }
  }

  static double computeMaxRadius(const Eigen::Matrix<double, kNumParams, 1>& p) {
    const double k1 = p[4], k2 = p[5], k3 = p[8], k4 = p[9], k5 = p[10], k6 = p[11];
    // d/dr [r * radial(r^2)] = radial + 2 r^2 radial'(r^2); the denominator must stay positive.
    const auto monotonic = [&](double r) {
      const double r2 = r * r, r4 = r2 * r2, r6 = r4 * r2;
      const double num = 1.0 + k1 * r2 + k2 * r4 + k3 * r6;
      const double den = 1.0 + k4 * r2 + k5 * r4 + k6 * r6;
      if (!(den > 0.0)) return false;
      const double d_num = k1 + 2.0 * k2 * r2 + 3.0 * k3 * r4;
      const double d_den = k4 + 2.0 * k5 * r2 + 3.0 * k6 * r4;
      return num / den + 2.0 * r2 * (d_num * den - num * d_den) / (den * den) > 0.0;
    };
    return camera_detail::firstFailure(monotonic, kMaxSearchedRadius, 4000);
  }

  Params params_;
  Scalar max_radius_ = Scalar(0);
  bool rational_ = false;  // any of k4..k6 non-zero
};

VOCA_CAMERA_MODEL_COPY_WARNING_RESTORE

}  // namespace voca
