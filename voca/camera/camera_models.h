#pragma once
// Camera projection models with analytic Jacobians: pinhole, pinhole-radtan8, kb4, ds and eucm.
//
// Parameter orders and names follow Basalt's calibration files. Formulas for kb4, ds and eucm
// (and their valid regions) follow Usenko, Demmel, Cremers, "The Double Sphere Camera Model",
// 3DV 2018; pinhole-radtan8 is OpenCV's rational radial + tangential model.
// Every model is templated on the scalar: the frontend projects in float, the backend in double.

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <type_traits>

namespace voca {

namespace camera_detail {

// Unit vector along q and the Jacobian of q -> q/|q|, which is (I - b b^T)/|q|.
template <typename Scalar>
inline Eigen::Matrix<Scalar, 3, 1> normalizeWithJacobian(const Eigen::Matrix<Scalar, 3, 1>& q,
                                                         Eigen::Matrix<Scalar, 3, 3>* d_b_d_q) {
  const Scalar norm = q.norm();
  const Eigen::Matrix<Scalar, 3, 1> b = q / norm;
  if (d_b_d_q) *d_b_d_q = (Eigen::Matrix<Scalar, 3, 3>::Identity() - b * b.transpose()) / norm;
  return b;
}

// Inverse of a 2x2 matrix; false when it is singular (kept local to avoid pulling in Eigen/LU).
template <typename Scalar>
inline bool invert2x2(const Eigen::Matrix<Scalar, 2, 2>& a, Eigen::Matrix<Scalar, 2, 2>& inverse) {
  const Scalar det = a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0);
  if (!(std::abs(det) > std::numeric_limits<Scalar>::min())) return false;
  inverse << a(1, 1) / det, -a(0, 1) / det, -a(1, 0) / det, a(0, 0) / det;
  return true;
}

// Newton-type unprojection stops after this many iterations; realistic calibrations converge in
// fewer than 6 (quadratic convergence from the distorted point as the first guess).
inline constexpr int kMaxUnprojectIterations = 20;

// Newton iterations run until the residual is at the rounding level of evaluating the model
// (kTight) or stops decreasing; the result is accepted when the residual is below kLoose. Stopping
// at the loose bound instead would leave errors of ~1e-5 rad in float.
template <typename Scalar>
inline Scalar tightTolerance(Scalar magnitude) {
  return Scalar(2) * std::numeric_limits<Scalar>::epsilon() * (Scalar(1) + magnitude);
}
template <typename Scalar>
inline Scalar looseTolerance(Scalar magnitude) {
  return Scalar(32) * std::numeric_limits<Scalar>::epsilon() * (Scalar(1) + magnitude);
}

// Step halvings tried when a Newton step does not reduce the residual.
inline constexpr int kMaxStepHalvings = 8;

// Largest x in (0, x_end] such that ok(t) holds for every t in (0, x]. Scans with a fixed step and
// then bisects the first failing interval. Used once at construction to find where a distortion
// function stops being monotonic.
template <typename Predicate>
inline double firstFailure(Predicate ok, double x_end, int steps) {
  const double step = x_end / steps;
  double good = 0.0;
  for (int i = 1; i <= steps; ++i) {
    const double x = step * i;
    if (!ok(x)) {
      double bad = x;
      for (int j = 0; j < 60; ++j) {
        const double mid = 0.5 * (good + bad);
        (ok(mid) ? good : bad) = mid;
      }
      return good;
    }
    good = x;
  }
  return x_end;
}

// Two doubles in one register (SSE2 on x86-64, NEON on AArch64): +, -, *, / and comparisons act lane
// by lane, each lane correctly rounded like the scalar operation, so a computation written once for
// double and once for Double2 with the same operations gives the same bits in every lane. A
// comparison gives a Mask2 lane of all ones or zeros.
using Double2 = double __attribute__((vector_size(16)));
using Mask2 = std::int64_t __attribute__((vector_size(16)));

inline Double2 select(Mask2 mask, Double2 if_set, Double2 if_clear) {
  return std::bit_cast<Double2>((std::bit_cast<Mask2>(if_set) & mask) | (std::bit_cast<Mask2>(if_clear) & ~mask));
}
inline Double2 abs(Double2 x) {
  return std::bit_cast<Double2>(std::bit_cast<Mask2>(x) & ~std::bit_cast<Mask2>(Double2{-0.0, -0.0}));
}
inline Double2 sqrt(Double2 x) { return Double2{std::sqrt(x[0]), std::sqrt(x[1])}; }

inline constexpr double kTan3Pi8 = 2.41421356237309504880;            // tan(3 pi / 8)
inline constexpr double kAtanMoreBits = 6.123233995736765886130e-17;  // pi/2 - double(pi/2)

// atan(t) for |t| <= tan(pi/8) plus base + extra: Cephes' rational approximation (S. L. Moshier),
// for double or Double2 alike.
template <typename T>
inline T atanReduced(T t, T base, T extra) {
  const T z = t * t;
  const T p = (((-8.750608600031904122785e-1 * z - 1.615753718733365076637e1) * z - 7.500855792314704667340e1) * z -
               1.228866684490136173410e2) *
                  z -
              6.485021904942025371773e1;
  const T q = ((((z + 2.485846490142306297962e1) * z + 1.650270098316988542046e2) * z + 4.328810604912902668951e2) * z +
               4.853903996359136964868e2) *
                  z +
              1.945506571482613964425e2;
  return base + ((t * (z * p / q) + t) + extra);
}

// atan2(y, x) for y >= 0 (an angle in [0, pi]) with Cephes' rational approximation of atan
// (the arguments reduced to |t| <= tan(pi/8) through pi/4 and pi/2), about three times as fast as
// the C library's correctly rounded one and within a few units in the last place of it
// (tests/test_camera.cpp). Only one division beyond the rational: x/y ratios are formed directly.
inline double atan2NonNegative(double y, double x) {
  const double ax = std::abs(x);
  // x = y = 0 gives 0 or pi, as std::atan2(+0, +-0).
  if (!(ax > 0.0) && !(y > 0.0)) return std::signbit(x) ? std::numbers::pi : 0.0;
  double angle;
  if (y > kTan3Pi8 * ax) {  // beyond 3 pi / 8: pi/2 - atan(|x| / y)
    angle = atanReduced(-ax / y, std::numbers::pi / 2, kAtanMoreBits);
  } else if (y <= 0.66 * ax) {
    angle = atanReduced(y / ax, 0.0, 0.0);
  } else {  // pi/4 + atan((y - |x|) / (y + |x|))
    angle = atanReduced((y - ax) / (y + ax), std::numbers::pi / 4, 0.5 * kAtanMoreBits);
  }
  // x < 0: the mirror image, pi - atan2(y, |x|).
  return x < 0.0 ? std::numbers::pi - angle : angle;
}

// The same in both lanes of a Double2 with y > 0 (the caller handles y = 0): every lane takes the
// operations of its own branch above (one division of the chosen numerator and denominator).
inline Double2 atan2NonNegative(Double2 y, Double2 x) {
  const Double2 ax = abs(x);
  const Mask2 steep = y > kTan3Pi8 * ax;
  const Mask2 flat = ~steep & (y <= 0.66 * ax);
  const Mask2 middle = ~steep & ~flat;
  const Double2 numerator = select(steep, -ax, select(flat, y, y - ax));
  const Double2 denominator = select(steep, y, select(flat, ax, y + ax));
  const Double2 zero{0.0, 0.0};
  const Double2 base = select(steep, zero + std::numbers::pi / 2, select(middle, zero + std::numbers::pi / 4, zero));
  const Double2 extra = select(steep, zero + kAtanMoreBits, select(middle, zero + 0.5 * kAtanMoreBits, zero));
  const Double2 angle = atanReduced(numerator / denominator, base, extra);
  return select(x < zero, std::numbers::pi - angle, angle);
}

// Two points through model.project() one at a time, as a two-lane projectPair() returns them: bit i
// set when point i projects; Jacobians when d_uv_d_p[0] is set.
template <typename Model, typename Vec3, typename Vec2, typename Mat23>
inline unsigned projectEach(const Model& model, const std::array<const Vec3*, 2>& p_cam, const std::array<Vec2*, 2>& uv,
                            const std::array<Mat23*, 2>& d_uv_d_p) {
  unsigned projected = 0;
  for (std::size_t i = 0; i < 2; ++i) {
    if (model.project(*p_cam[i], *uv[i], d_uv_d_p[0] != nullptr ? d_uv_d_p[i] : nullptr)) projected |= 1u << i;
  }
  return projected;
}

}  // namespace camera_detail

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

// GCC 12 reports -Wmaybe-uninitialized on the implicit copy of these models when they sit in a
// std::variant holding another alternative (it copies the union's bytes). Every member has an
// initialiser, so the report is a false positive; it is silenced for these class bodies only.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

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

// Kannala-Brandt fisheye with four coefficients (Kalibr "equidistant"):
// u = fx d(theta) x/r + cx with r = |(x, y)|, theta = atan2(r, z),
// d(theta) = theta + k1 theta^3 + k2 theta^5 + k3 theta^7 + k4 theta^9. Parameters fx fy cx cy k1 k2 k3 k4.
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

#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

// Double sphere model. d1 = |p|, d2 = |(x, y, xi d1 + z)|,
// u = fx x / (alpha d2 + (1 - alpha)(xi d1 + z)) + cx. Parameters fx fy cx cy xi alpha.
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
    const Scalar w1 = alpha <= Scalar(0.5) ? alpha / (Scalar(1) - alpha) : (Scalar(1) - alpha) / alpha;
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
      d_uv_d_p->row(0) = -fx * mx * inv_den * d_den_d_p.transpose();
      d_uv_d_p->row(1) = -fy * my * inv_den * d_den_d_p.transpose();
      (*d_uv_d_p)(0, 0) += fx * inv_den;
      (*d_uv_d_p)(1, 1) += fy * inv_den;
    }
    if (d_uv_d_params) {
      ParamJacobian& j = *d_uv_d_params;
      j.setZero();
      j(0, 0) = mx;
      j(1, 1) = my;
      j(0, 2) = Scalar(1);
      j(1, 3) = Scalar(1);
      const Scalar d_den_d_xi = alpha * k * d1 / d2 + (Scalar(1) - alpha) * d1;
      const Scalar d_den_d_alpha = d2 - k;
      j(0, 4) = -fx * mx * inv_den * d_den_d_xi;
      j(1, 4) = -fy * my * inv_den * d_den_d_xi;
      j(0, 5) = -fx * mx * inv_den * d_den_d_alpha;
      j(1, 5) = -fy * my * inv_den * d_den_d_alpha;
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

// Extended unified camera model. d = sqrt(beta (x^2 + y^2) + z^2),
// u = fx x / (alpha d + (1 - alpha) z) + cx. Parameters fx fy cx cy alpha beta.
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
    w_ = alpha <= Scalar(0.5) ? alpha / (Scalar(1) - alpha) : (Scalar(1) - alpha) / alpha;
  }
  const Params& params() const { return params_; }
  template <typename Other>
  ExtendedUnifiedCamera<Other> cast() const {
    return ExtendedUnifiedCamera<Other>(params_.template cast<Other>());
  }

  // False outside the valid region z > -w d, w = alpha/(1-alpha) for alpha <= 0.5 (the
  // denominator stays positive), (1-alpha)/alpha above (the projection stays injective).
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
      d_uv_d_p->row(0) = -fx * mx * inv_den * d_den_d_p.transpose();
      d_uv_d_p->row(1) = -fy * my * inv_den * d_den_d_p.transpose();
      (*d_uv_d_p)(0, 0) += fx * inv_den;
      (*d_uv_d_p)(1, 1) += fy * inv_den;
    }
    if (d_uv_d_params) {
      ParamJacobian& j = *d_uv_d_params;
      j.setZero();
      j(0, 0) = mx;
      j(1, 1) = my;
      j(0, 2) = Scalar(1);
      j(1, 3) = Scalar(1);
      const Scalar d_den_d_alpha = d - z;
      const Scalar d_den_d_beta = alpha * r2 / (Scalar(2) * d);
      j(0, 4) = -fx * mx * inv_den * d_den_d_alpha;
      j(1, 4) = -fy * my * inv_den * d_den_d_alpha;
      j(0, 5) = -fx * mx * inv_den * d_den_d_beta;
      j(1, 5) = -fy * my * inv_den * d_den_d_beta;
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
