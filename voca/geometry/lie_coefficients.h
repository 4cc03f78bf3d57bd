#pragma once
// Scalar coefficients of the SO(3)/SE(3)/SE(2) exponential maps and Jacobians, evaluated without
// cancellation near zero angle and without poles near pi.

#include <cmath>

namespace voca::lie_detail {

// Below this squared angle a two-term series is exact to the scalar's precision (truncation is
// O(theta^4) relative), used where the closed form would divide by zero.
template <typename Scalar>
constexpr Scalar tinyAngleSquared() {
  return sizeof(Scalar) >= sizeof(double) ? Scalar(1e-10) : Scalar(1e-5);
}

// Below this squared angle the five-term series below are used. The closed forms they replace
// lose about eps / theta^2 (relative) to cancellation; the series truncation at the switch is
// ~1e-15 relative in double (theta^2 < 0.1) and ~1e-10 in float (theta^2 < 1).
template <typename Scalar>
constexpr Scalar seriesAngleSquared() {
  return sizeof(Scalar) >= sizeof(double) ? Scalar(0.1) : Scalar(1);
}

// c0 + c1 x + c2 x^2 + c3 x^3 + c4 x^4 by Horner's rule.
template <typename Scalar>
Scalar poly4(Scalar x, double c0, double c1, double c2, double c3, double c4) {
  return Scalar(c0) + x * (Scalar(c1) + x * (Scalar(c2) + x * (Scalar(c3) + x * Scalar(c4))));
}

// sin(theta/2) and cos(theta/2) once; every other coefficient follows without cancellation.
template <typename Scalar>
struct HalfAngle {
  Scalar theta;
  Scalar theta_sq;
  Scalar sin_half;
  Scalar cos_half;

  explicit HalfAngle(Scalar theta_sq_in) : theta_sq(theta_sq_in) {
    using std::cos;
    using std::sin;
    using std::sqrt;
    theta = sqrt(theta_sq);
    sin_half = sin(theta / Scalar(2));
    cos_half = cos(theta / Scalar(2));
  }
  Scalar sinTheta() const { return Scalar(2) * sin_half * cos_half; }
  Scalar cosTheta() const { return cos_half * cos_half - sin_half * sin_half; }
  // 1 - cos(theta), accurate for small theta where the direct difference cancels.
  Scalar oneMinusCos() const { return Scalar(2) * sin_half * sin_half; }

  // sin(theta) / theta.
  Scalar sinc() const {
    if (theta_sq < tinyAngleSquared<Scalar>()) return Scalar(1) - theta_sq / Scalar(6);
    return sinTheta() / theta;
  }
  // (1 - cos(theta)) / theta^2.
  Scalar oneMinusCosOverSq() const {
    if (theta_sq < tinyAngleSquared<Scalar>()) return Scalar(0.5) - theta_sq / Scalar(24);
    return oneMinusCos() / theta_sq;
  }
  // (theta - sin(theta)) / theta^3 = sum (-1)^k theta^2k / (2k+3)!.
  Scalar thetaMinusSinOverCube() const {
    if (theta_sq < seriesAngleSquared<Scalar>()) {
      return poly4(theta_sq, 1.0 / 6, -1.0 / 120, 1.0 / 5040, -1.0 / 362880, 1.0 / 39916800);
    }
    return (theta - sinTheta()) / (theta_sq * theta);
  }
  // (1 - (theta/2) cot(theta/2)) / theta^2, the coefficient of hat^2 in the inverse Jacobian of
  // SO(3); its Taylor series has radius 2 pi, so it is well behaved at pi.
  Scalar inverseJacobianCoefficient() const {
    if (theta_sq < seriesAngleSquared<Scalar>()) {
      return poly4(theta_sq, 1.0 / 12, 1.0 / 720, 1.0 / 30240, 1.0 / 1209600, 1.0 / 47900160);
    }
    return (Scalar(1) - Scalar(0.5) * theta * cos_half / sin_half) / theta_sq;
  }
  // (theta/2) cot(theta/2), the diagonal of the inverse of SE(2)'s V matrix.
  Scalar halfThetaCotHalfTheta() const { return Scalar(1) - theta_sq * inverseJacobianCoefficient(); }
  // (cos(theta) - 1 + theta^2/2) / theta^4 = sum_{k>=2} (-1)^k theta^(2k-4) / (2k)!.
  Scalar se3SecondCoefficient() const {
    if (theta_sq < seriesAngleSquared<Scalar>()) {
      return poly4(theta_sq, 1.0 / 24, -1.0 / 720, 1.0 / 40320, -1.0 / 3628800, 1.0 / 479001600);
    }
    return (theta_sq / Scalar(2) - oneMinusCos()) / (theta_sq * theta_sq);
  }
  // (2 theta - 3 sin(theta) + theta cos(theta)) / (2 theta^5)
  //   = sum_{k>=2} (-1)^k (k-1) theta^(2k-4) / (2k+1)!.
  Scalar se3ThirdCoefficient() const {
    if (theta_sq < seriesAngleSquared<Scalar>()) {
      return poly4(theta_sq, 1.0 / 120, -2.0 / 5040, 3.0 / 362880, -4.0 / 39916800, 5.0 / 6227020800.0);
    }
    return (Scalar(2) * theta - Scalar(3) * sinTheta() + theta * cosTheta()) /
           (Scalar(2) * theta_sq * theta_sq * theta);
  }
};

}  // namespace voca::lie_detail
