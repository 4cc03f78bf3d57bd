#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <type_traits>

#include "voca/camera/camera_math.h"
#include "voca/camera/double2.h"
#include "voca/camera/fast_atan2.h"
#include "voca/camera/pinhole_camera.h"

namespace voca {

VOCA_CAMERA_MODEL_COPY_WARNING_OFF

// Kannala-Brandt fisheye with four coefficients (Kalibr "equidistant"):
// u = fx d(theta) x/r + cx with r = |(x, y)|, theta = atan2(r, z),
// d(theta) = theta + k1 theta^3 + k2 theta^5 + k3 theta^7 + k4 theta^9. Parameters fx fy cx cy k1 k2 k3 k4.
// Formulas and valid region after Usenko, Demmel, Cremers, "The Double Sphere Camera Model", 3DV 2018.
template <typename Scalar>
class KannalaBrandt4Camera {
 public:
  static constexpr int kNumParams = 8;
  static constexpr const char* kName = "kb4";
  static constexpr std::array<const char*, kNumParams> kParamNames{"fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"};
  using Vec2 = Eigen::Matrix<Scalar, 2, 1>;
  using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
  using Mat23 = Eigen::Matrix<Scalar, 2, 3>;
  using Mat32 = Eigen::Matrix<Scalar, 3, 2>;
  using Params = Eigen::Matrix<Scalar, kNumParams, 1>;
  using ParamJacobian = Eigen::Matrix<Scalar, 2, kNumParams>;

  explicit KannalaBrandt4Camera(const Params& params) : params_(params) {
    const Eigen::Matrix<double, kNumParams, 1> p = params_.template cast<double>();
    const auto monotonic = [&](double theta) {
      const double t2 = theta * theta;
      return 1.0 + t2 * (3.0 * p[4] + t2 * (5.0 * p[5] + t2 * (7.0 * p[6] + t2 * 9.0 * p[7]))) > 0.0;
    };
    const double max_theta = camera_detail::firstFailure(monotonic, std::numbers::pi, 3200);
    max_theta_ = Scalar(max_theta);
    max_distorted_ = distortion(max_theta_);
  }
  const Params& params() const { return params_; }
  template <typename Other>
  KannalaBrandt4Camera<Other> cast() const {
    return KannalaBrandt4Camera<Other>(params_.template cast<Other>());
  }
  // Angle off the optical axis (radians, at most pi) up to which d(theta) increases; points at
  // larger angles would fold back into the image.
  Scalar maxTheta() const { return max_theta_; }
  // Projections in double take the angle off the axis from camera_detail::atan2NonNegative instead
  // of std::atan2 (a few units in the last place apart, about three times as fast): what the backend
  // asks for, which projects ~50k points per frame. Off by default, so other users keep their values.
  void setFastAngle(bool fast) { fast_angle_ = fast; }

  // Works behind the camera (z <= 0) as long as the angle stays within maxTheta().
  bool project(const Vec3& p_cam, Vec2& uv, Mat23* d_uv_d_p = nullptr, ParamJacobian* d_uv_d_params = nullptr) const {
    const Scalar x = p_cam[0], y = p_cam[1], z = p_cam[2];
    const Scalar r2 = x * x + y * y;
    const Scalar r = std::sqrt(r2);
    // Near the axis d(theta)/r = 1/z up to O((r/z)^2), which is below rounding here.
    // "<=" also sends the origin (r = z = 0) here, where it is rejected.
    if (r <= std::sqrt(std::numeric_limits<Scalar>::epsilon()) * std::abs(z)) {
      if (!(z > Scalar(0))) return false;
      typename PinholeCamera<Scalar>::ParamJacobian d_uv_d_pinhole;
      PinholeCamera<Scalar>(params_.template head<4>()).project(p_cam, uv, d_uv_d_p, &d_uv_d_pinhole);
      if (d_uv_d_params) {
        // On the axis the coefficients k1..k4 have no first-order effect.
        d_uv_d_params->setZero();
        d_uv_d_params->template leftCols<4>() = d_uv_d_pinhole;
      }
      return true;
    }
    Scalar theta;
    if constexpr (std::is_same_v<Scalar, double>) {
      theta = fast_angle_ ? camera_detail::atan2NonNegative(r, z) : std::atan2(r, z);
    } else {
      theta = std::atan2(r, z);
    }
    if (!(theta <= max_theta_)) return false;
    const Scalar inv_r = Scalar(1) / r;
    Scalar d_uv_d_p_entries[6];
    offAxis(x, y, z, r2, r, inv_r, theta, uv[0], uv[1], d_uv_d_p != nullptr ? d_uv_d_p_entries : nullptr);
    if (d_uv_d_p) *d_uv_d_p = Eigen::Map<const Mat23>(d_uv_d_p_entries);
    if (d_uv_d_params) {
      const Scalar fx = params_[0], fy = params_[1];
      const Scalar t2 = theta * theta;
      const Scalar s = distortion(theta) * inv_r;
      ParamJacobian& j = *d_uv_d_params;
      j.setZero();
      j(0, 0) = s * x;
      j(1, 1) = s * y;
      j(0, 2) = Scalar(1);
      j(1, 3) = Scalar(1);
      Scalar theta_power = theta * t2;
      for (int i = 4; i < 8; ++i) {
        j(0, i) = fx * x * inv_r * theta_power;
        j(1, i) = fy * y * inv_r * theta_power;
        theta_power *= t2;
      }
    }
    return true;
  }

  // Two points at once, each lane of a register taking exactly project()'s operations with the fast
  // angle (setFastAngle(true); the same values bit for bit): the backend's residual passes spend
  // most of their time in this chain of divisions, and two independent chains in one register run
  // about as fast as one. Returns bit i set when point i projects; uv[i] and d_uv_d_p[i] (when
  // d_uv_d_p[0] is set) are written only then. Double only; points near the axis take project().
  unsigned projectPair(const std::array<const Vec3*, 2>& p_cam, const std::array<Vec2*, 2>& uv,
                       const std::array<Mat23*, 2>& d_uv_d_p) const requires std::is_same_v<Scalar, double> {
    using camera_detail::Double2;
    const Double2 x{(*p_cam[0])[0], (*p_cam[1])[0]}, y{(*p_cam[0])[1], (*p_cam[1])[1]},
        z{(*p_cam[0])[2], (*p_cam[1])[2]};
    const Double2 r2 = x * x + y * y;
    const Double2 r = camera_detail::sqrt(r2);
    const bool jacobians = d_uv_d_p[0] != nullptr;
    // project()'s axis test, negated so that a NaN also goes the scalar way.
    const camera_detail::Mask2 off_axis = r > std::sqrt(std::numeric_limits<double>::epsilon()) * camera_detail::abs(z);
    if (!fast_angle_ || !(off_axis[0] && off_axis[1])) return camera_detail::projectEach(*this, p_cam, uv, d_uv_d_p);
    const Double2 theta = camera_detail::atan2NonNegative(r, z);
    const camera_detail::Mask2 within = theta <= max_theta_ + Double2{0.0, 0.0};
    const Double2 inv_r = 1.0 / r;
    Double2 u, v, entries[6];
    offAxis(x, y, z, r2, r, inv_r, theta, u, v, jacobians ? entries : nullptr);
    unsigned projected = 0;
    for (int i = 0; i < 2; ++i) {
      if (!within[i]) continue;
      projected |= 1u << i;
      const auto lane = static_cast<std::size_t>(i);
      *uv[lane] << u[i], v[i];
      if (jacobians) {
        Mat23& J = *d_uv_d_p[lane];
        for (int k = 0; k < 6; ++k) J.data()[k] = entries[k][i];
      }
    }
    return projected;
  }

  // Solves d(theta) = |m| for theta with Newton's method on [0, maxTheta()]. False for pixels
  // beyond the image of maxTheta() or when the iteration does not converge.
  bool unproject(const Vec2& uv, Vec3& bearing, Mat32* d_bearing_d_uv = nullptr) const {
    const Scalar fx = params_[0], fy = params_[1];
    const Scalar mx = (uv[0] - params_[2]) / fx, my = (uv[1] - params_[3]) / fy;
    const Scalar ru = std::sqrt(mx * mx + my * my);
    if (ru < std::sqrt(std::numeric_limits<Scalar>::epsilon())) {
      // d(theta) = theta + O(theta^3): the pinhole bearing is exact to rounding here.
      return PinholeCamera<Scalar>(params_.template head<4>()).unproject(uv, bearing, d_bearing_d_uv);
    }
    const Scalar loose = camera_detail::looseTolerance<Scalar>(ru);
    if (!(ru <= max_distorted_ + loose)) return false;
    Scalar theta = std::min(ru, max_theta_);
    Scalar residual = distortion(theta) - ru;
    const Scalar tight = camera_detail::tightTolerance<Scalar>(ru);
    for (int iteration = 0; iteration < camera_detail::kMaxUnprojectIterations; ++iteration) {
      if (std::abs(residual) <= tight) break;
      const Scalar slope = distortionDerivative(theta);
      if (!(slope > Scalar(0))) break;
      Scalar step = -residual / slope;
      const int max_halvings = std::abs(residual) > loose ? camera_detail::kMaxStepHalvings : 0;  // as in radtan8
      bool improved = false;
      for (int halving = 0; halving <= max_halvings && !improved; ++halving, step *= Scalar(0.5)) {
        const Scalar candidate = std::clamp(theta + step, Scalar(0), max_theta_);
        const Scalar candidate_residual = distortion(candidate) - ru;
        if (std::abs(candidate_residual) < std::abs(residual)) {
          theta = candidate;
          residual = candidate_residual;
          improved = true;
        }
      }
      if (!improved) break;
    }
    if (!(std::abs(residual) <= loose)) return false;
    const Scalar d_prime = distortionDerivative(theta);
    const Scalar sin_theta = std::sin(theta), cos_theta = std::cos(theta);
    const Scalar g = sin_theta / ru;
    bearing << g * mx, g * my, cos_theta;
    if (d_bearing_d_uv) {
      // theta(ru) has derivative 1/d'(theta); g = sin(theta)/ru.
      const Scalar d_theta_d_ru = Scalar(1) / d_prime;
      const Scalar d_g_d_ru = (cos_theta * d_theta_d_ru * ru - sin_theta) / (ru * ru);
      const Eigen::Matrix<Scalar, 1, 2> d_ru_d_m(mx / ru, my / ru);
      Mat32 d_b_d_m;
      d_b_d_m.template topRows<2>() = Vec2(mx, my) * (d_g_d_ru * d_ru_d_m);
      d_b_d_m(0, 0) += g;
      d_b_d_m(1, 1) += g;
      d_b_d_m.row(2) = -sin_theta * d_theta_d_ru * d_ru_d_m;
      d_b_d_m.col(0) /= fx;
      d_b_d_m.col(1) /= fy;
      *d_bearing_d_uv = d_b_d_m;
    }
    return true;
  }

 private:
  // d(theta) and d'(theta), for Scalar or (in double) camera_detail::Double2 lanes.
  template <typename T>
  T distortion(T theta) const {
    const T t2 = theta * theta;
    return theta * (Scalar(1) + t2 * (params_[4] + t2 * (params_[5] + t2 * (params_[6] + t2 * params_[7]))));
  }
  template <typename T>
  T distortionDerivative(T theta) const {
    const T t2 = theta * theta;
    return Scalar(1) +
           t2 * (Scalar(3) * params_[4] +
                 t2 * (Scalar(5) * params_[5] + t2 * (Scalar(7) * params_[6] + t2 * Scalar(9) * params_[7])));
  }

  // The pixel of a point off the axis at angle theta (within maxTheta()) and, when d_uv_d_p is set,
  // its Jacobian by the point (column-major 2x3), for one point (T = Scalar) or two (Double2).
  template <typename T>
  void offAxis(T x, T y, T z, T r2, T r, T inv_r, T theta, T& u, T& v, T* d_uv_d_p) const {
    const Scalar fx = params_[0], fy = params_[1], cx = params_[2], cy = params_[3];
    const T s = distortion(theta) * inv_r;
    u = fx * s * x + cx;
    v = fy * s * y + cy;
    if (d_uv_d_p == nullptr) return;
    const T d_prime = distortionDerivative(theta);
    const T rho2 = r2 + z * z;
    const T d_theta_d_r = z / rho2;
    const T d_theta_d_z = -r / rho2;
    // s = d(theta(r, z)) / r: ds/dr and ds/dz, then r = |(x, y)| gives dr/dx = x/r.
    const T d_s_d_r = (d_prime * d_theta_d_r - s) * inv_r;
    const T d_s_d_z = d_prime * d_theta_d_z * inv_r;
    const T d_s_d_x = d_s_d_r * x * inv_r, d_s_d_y = d_s_d_r * y * inv_r;
    const T fx_x = fx * x, fy_y = fy * y;
    d_uv_d_p[0] = fx_x * d_s_d_x + fx * s;
    d_uv_d_p[1] = fy_y * d_s_d_x;
    d_uv_d_p[2] = fx_x * d_s_d_y;
    d_uv_d_p[3] = fy_y * d_s_d_y + fy * s;
    d_uv_d_p[4] = fx_x * d_s_d_z;
    d_uv_d_p[5] = fy_y * d_s_d_z;
  }

  Params params_;
  Scalar max_theta_ = Scalar(0);
  Scalar max_distorted_ = Scalar(0);
  bool fast_angle_ = false;
};

VOCA_CAMERA_MODEL_COPY_WARNING_RESTORE

}  // namespace voca
