#pragma once
// SO(3): 3-D rotations stored as unit quaternions, with the exponential map and its Jacobians.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>

#include "voca/geometry/lie_coefficients.h"

namespace voca {

template <typename Scalar>
class SO3 {
 public:
  using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
  using Mat3 = Eigen::Matrix<Scalar, 3, 3>;
  using Quaternion = Eigen::Quaternion<Scalar>;
  static constexpr int kDoF = 3;

  SO3() : q_(Quaternion::Identity()) {}
  // The quaternion is normalised; callers may pass one that is only approximately unit.
  explicit SO3(const Quaternion& q) : q_(q.normalized()) {}
  // Projects a matrix onto the nearest rotation (Frobenius norm), so rotations read from text files
  // with few digits or accumulated in float come back exactly orthonormal.
  explicit SO3(const Mat3& rotation) : q_(Quaternion(nearestRotation(rotation)).normalized()) {}

  static SO3 identity() { return SO3(); }
  static SO3 fromQuaternion(const Quaternion& q) { return SO3(q); }
  static SO3 fromMatrix(const Mat3& rotation) { return SO3(rotation); }

  // Nearest rotation matrix to m: U diag(1, 1, det(U V^T)) V^T from the SVD m = U S V^T.
  static Mat3 nearestRotation(const Mat3& m) {
    const Eigen::JacobiSVD<Mat3> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Mat3 u = svd.matrixU();
    const Mat3& v = svd.matrixV();
    if ((u * v.transpose()).determinant() < Scalar(0)) u.col(2) = -u.col(2);
    return u * v.transpose();
  }

  static SO3 exp(const Vec3& omega) {
    const Scalar theta_sq = omega.squaredNorm();
    Scalar real, imag_factor;
    if (theta_sq < lie_detail::tinyAngleSquared<Scalar>()) {
      // Taylor expansion of cos(theta/2) and sin(theta/2)/theta to keep full precision near 0.
      real = Scalar(1) - theta_sq / Scalar(8);
      imag_factor = Scalar(0.5) - theta_sq / Scalar(48);
    } else {
      const Scalar theta = std::sqrt(theta_sq);
      real = std::cos(theta / Scalar(2));
      imag_factor = std::sin(theta / Scalar(2)) / theta;
    }
    SO3 result;
    result.q_ = Quaternion(real, imag_factor * omega.x(), imag_factor * omega.y(), imag_factor * omega.z());
    result.q_.normalize();
    return result;
  }

  // Rotation vector with angle in [0, pi].
  Vec3 log() const {
    Quaternion q = q_;
    if (q.w() < Scalar(0)) q.coeffs() = -q.coeffs();  // same rotation, angle <= pi
    const Vec3 imag = q.vec();
    const Scalar n = imag.norm();
    const Scalar w = q.w();
    if (n < std::sqrt(lie_detail::tinyAngleSquared<Scalar>())) {
      // theta ~ 2 n / w; the series keeps log(exp(x)) = x to machine precision for small x.
      return (Scalar(2) / w - Scalar(2) * n * n / (Scalar(3) * w * w * w)) * imag;
    }
    const Scalar two_atan = Scalar(2) * std::atan2(n, w);
    return (two_atan / n) * imag;
  }

  SO3 inverse() const {
    SO3 result;
    result.q_ = q_.conjugate();
    return result;
  }
  SO3 operator*(const SO3& other) const {
    SO3 result;
    result.q_ = (q_ * other.q_).normalized();
    return result;
  }
  SO3& operator*=(const SO3& other) { return *this = *this * other; }
  Vec3 operator*(const Vec3& point) const { return q_ * point; }

  Mat3 matrix() const { return q_.toRotationMatrix(); }
  const Quaternion& unitQuaternion() const { return q_; }
  void setQuaternion(const Quaternion& q) { q_ = q.normalized(); }
  // Rotation angle in [0, pi].
  Scalar angle() const {
    using std::abs;
    using std::atan2;
    return Scalar(2) * atan2(q_.vec().norm(), abs(q_.w()));
  }
  // The adjoint of SO(3) is the rotation matrix itself: R exp(w) R^T = exp(R w).
  Mat3 adjoint() const { return matrix(); }

  template <typename Other>
  SO3<Other> cast() const {
    return SO3<Other>(q_.template cast<Other>());
  }

  static Mat3 hat(const Vec3& v) {
    Mat3 m;
    m << Scalar(0), -v.z(), v.y(), v.z(), Scalar(0), -v.x(), -v.y(), v.x(), Scalar(0);
    return m;
  }
  // Reads the skew-symmetric part, so a slightly non-skew input gives the nearest vector.
  static Vec3 vee(const Mat3& m) { return Scalar(0.5) * Vec3(m(2, 1) - m(1, 2), m(0, 2) - m(2, 0), m(1, 0) - m(0, 1)); }

  // Left Jacobian: exp(w + dw) ~= exp(J_l(w) dw) exp(w).
  static Mat3 leftJacobian(const Vec3& omega) {
    const lie_detail::HalfAngle<Scalar> a(omega.squaredNorm());
    const Mat3 w_hat = hat(omega);
    return Mat3::Identity() + a.oneMinusCosOverSq() * w_hat + a.thetaMinusSinOverCube() * w_hat * w_hat;
  }
  // Inverse of leftJacobian(omega); singular only at |omega| = 2 pi, beyond the range of log().
  static Mat3 leftJacobianInverse(const Vec3& omega) {
    const lie_detail::HalfAngle<Scalar> a(omega.squaredNorm());
    const Mat3 w_hat = hat(omega);
    return Mat3::Identity() - Scalar(0.5) * w_hat + a.inverseJacobianCoefficient() * w_hat * w_hat;
  }
  // Right Jacobian: exp(w + dw) ~= exp(w) exp(J_r(w) dw); J_r(w) = J_l(-w).
  static Mat3 rightJacobian(const Vec3& omega) { return leftJacobian(-omega); }
  static Mat3 rightJacobianInverse(const Vec3& omega) { return leftJacobianInverse(-omega); }

 private:
  Quaternion q_;
};

using SO3d = SO3<double>;
using SO3f = SO3<float>;

}  // namespace voca
