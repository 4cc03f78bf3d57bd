#pragma once
// The math the camera models share: bearings from rays, 2x2 inversion, the Newton tolerances of
// unprojection, the search for the end of a monotonic distortion, and the scalar fallback of the
// two-point projection.

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

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

// The weight w of the valid regions of ds and eucm: alpha/(1-alpha) for alpha <= 0.5 (the denominator
// stays positive), (1-alpha)/alpha above (the projection stays injective). eucm projects for
// z > -w d; ds derives its bound w2 from it.
template <typename Scalar>
inline Scalar validRegionWeight(Scalar alpha) {
  return alpha <= Scalar(0.5) ? alpha / (Scalar(1) - alpha) : (Scalar(1) - alpha) / alpha;
}

// ds and eucm project as u = fx x / den + cx, v = fy y / den + cy with mx = x / den, my = y / den;
// only den(p) differs. Their Jacobians by the point, from den's gradient d_den_d_p:
template <typename Scalar>
inline void projectionOverDenominatorJacobian(Scalar fx, Scalar fy, Scalar mx, Scalar my, Scalar inv_den,
                                              const Eigen::Matrix<Scalar, 3, 1>& d_den_d_p,
                                              Eigen::Matrix<Scalar, 2, 3>& d_uv_d_p) {
  d_uv_d_p.row(0) = -fx * mx * inv_den * d_den_d_p.transpose();
  d_uv_d_p.row(1) = -fy * my * inv_den * d_den_d_p.transpose();
  d_uv_d_p(0, 0) += fx * inv_den;
  d_uv_d_p(1, 1) += fy * inv_den;
}

// ... and by the parameters fx fy cx cy p4 p5, from den's derivatives by the two model parameters.
template <typename Scalar>
inline void projectionOverDenominatorParamJacobian(Scalar fx, Scalar fy, Scalar mx, Scalar my, Scalar inv_den,
                                                   Scalar d_den_d_p4, Scalar d_den_d_p5,
                                                   Eigen::Matrix<Scalar, 2, 6>& j) {
  j.setZero();
  j(0, 0) = mx;
  j(1, 1) = my;
  j(0, 2) = Scalar(1);
  j(1, 3) = Scalar(1);
  j(0, 4) = -fx * mx * inv_den * d_den_d_p4;
  j(1, 4) = -fy * my * inv_den * d_den_d_p4;
  j(0, 5) = -fx * mx * inv_den * d_den_d_p5;
  j(1, 5) = -fy * my * inv_den * d_den_d_p5;
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

}  // namespace voca

// GCC 12 reports -Wmaybe-uninitialized on the implicit copy of a camera model when it sits in a
// std::variant holding another alternative (it copies the union's bytes). Every member has an
// initialiser, so the report is a false positive; it is silenced for the class bodies between
// these two.
#if defined(__GNUC__) && !defined(__clang__)
#define VOCA_CAMERA_MODEL_COPY_WARNING_OFF \
  _Pragma("GCC diagnostic push") _Pragma("GCC diagnostic ignored \"-Wmaybe-uninitialized\"")
#define VOCA_CAMERA_MODEL_COPY_WARNING_RESTORE _Pragma("GCC diagnostic pop")
#else
#define VOCA_CAMERA_MODEL_COPY_WARNING_OFF
#define VOCA_CAMERA_MODEL_COPY_WARNING_RESTORE
#endif
