#pragma once
// SE(3): rigid transforms T_a_b (maps points from frame b to frame a), tangent = (translation, rotation).

#include "voca/geometry/so3.h"

namespace voca {

template <typename Scalar>
class SE3 {
 public:
  using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
  using Vec6 = Eigen::Matrix<Scalar, 6, 1>;
  using Mat3 = Eigen::Matrix<Scalar, 3, 3>;
  using Mat4 = Eigen::Matrix<Scalar, 4, 4>;
  using Mat34 = Eigen::Matrix<Scalar, 3, 4>;
  using Mat6 = Eigen::Matrix<Scalar, 6, 6>;
  using Quaternion = Eigen::Quaternion<Scalar>;
  static constexpr int kDoF = 6;

  SE3() : translation_(Vec3::Zero()) {}
  SE3(const SO3<Scalar>& rotation, const Vec3& translation) : rotation_(rotation), translation_(translation) {}
  SE3(const Quaternion& q, const Vec3& translation) : rotation_(q), translation_(translation) {}
  // The rotation matrix is projected onto SO(3).
  SE3(const Mat3& rotation, const Vec3& translation) : rotation_(rotation), translation_(translation) {}
  // From a 4x4 or 3x4 homogeneous matrix; the rotation block is projected onto SO(3).
  template <typename Derived>
  explicit SE3(const Eigen::MatrixBase<Derived>& m)
      : rotation_(Mat3(m.template block<3, 3>(0, 0))), translation_(m.template block<3, 1>(0, 3)) {
    static_assert(
        Derived::ColsAtCompileTime == 4 && (Derived::RowsAtCompileTime == 3 || Derived::RowsAtCompileTime == 4),
        "SE3 from a matrix needs 3x4 or 4x4");
  }

  static SE3 identity() { return SE3(); }

  // xi = (upsilon, omega): t = J_l(omega) upsilon, R = exp(omega).
  static SE3 exp(const Vec6& xi) {
    const Vec3 omega = xi.template tail<3>();
    return SE3(SO3<Scalar>::exp(omega), SO3<Scalar>::leftJacobian(omega) * xi.template head<3>());
  }
  Vec6 log() const {
    const Vec3 omega = rotation_.log();
    Vec6 xi;
    xi.template head<3>() = SO3<Scalar>::leftJacobianInverse(omega) * translation_;
    xi.template tail<3>() = omega;
    return xi;
  }

  SE3 inverse() const {
    const SO3<Scalar> r_inv = rotation_.inverse();
    return SE3(r_inv, -(r_inv * translation_));
  }
  SE3 operator*(const SE3& other) const {
    return SE3(rotation_ * other.rotation_, translation_ + rotation_ * other.translation_);
  }
  SE3& operator*=(const SE3& other) { return *this = *this * other; }
  Vec3 operator*(const Vec3& point) const { return rotation_ * point + translation_; }

  const SO3<Scalar>& so3() const { return rotation_; }
  SO3<Scalar>& so3() { return rotation_; }
  const Vec3& translation() const { return translation_; }
  Vec3& translation() { return translation_; }
  Mat3 rotationMatrix() const { return rotation_.matrix(); }
  const Quaternion& unitQuaternion() const { return rotation_.unitQuaternion(); }

  Mat4 matrix() const {
    Mat4 m = Mat4::Identity();
    m.template block<3, 3>(0, 0) = rotation_.matrix();
    m.template block<3, 1>(0, 3) = translation_;
    return m;
  }
  Mat34 matrix3x4() const { return matrix().template topRows<3>(); }

  // Adj such that T exp(xi) T^-1 = exp(Adj xi), for xi = (upsilon, omega).
  Mat6 adjoint() const {
    const Mat3 r = rotation_.matrix();
    Mat6 adj;
    adj.template block<3, 3>(0, 0) = r;
    adj.template block<3, 3>(0, 3) = SO3<Scalar>::hat(translation_) * r;
    adj.template block<3, 3>(3, 0).setZero();
    adj.template block<3, 3>(3, 3) = r;
    return adj;
  }

  // xi = (upsilon, omega) -> [[omega^, upsilon], [0, 0]].
  static Mat4 hat(const Vec6& xi) {
    Mat4 m = Mat4::Zero();
    m.template block<3, 3>(0, 0) = SO3<Scalar>::hat(xi.template tail<3>());
    m.template block<3, 1>(0, 3) = xi.template head<3>();
    return m;
  }
  static Vec6 vee(const Mat4& m) {
    Vec6 xi;
    xi.template head<3>() = m.template block<3, 1>(0, 3);
    xi.template tail<3>() = SO3<Scalar>::vee(m.template block<3, 3>(0, 0));
    return xi;
  }

  // Left Jacobian: exp(xi + d) ~= exp(J_l(xi) d) exp(xi); [[J, Q], [0, J]] with J the SO(3) left
  // Jacobian of omega and Q Barfoot's coupling block.
  static Mat6 leftJacobian(const Vec6& xi) {
    const Vec3 omega = xi.template tail<3>();
    const Mat3 j = SO3<Scalar>::leftJacobian(omega);
    Mat6 jac;
    jac.template block<3, 3>(0, 0) = j;
    jac.template block<3, 3>(0, 3) = jacobianCoupling(xi);
    jac.template block<3, 3>(3, 0).setZero();
    jac.template block<3, 3>(3, 3) = j;
    return jac;
  }
  // Inverse of leftJacobian(xi): [[J^-1, -J^-1 Q J^-1], [0, J^-1]].
  static Mat6 leftJacobianInverse(const Vec6& xi) {
    const Mat3 j_inv = SO3<Scalar>::leftJacobianInverse(xi.template tail<3>());
    Mat6 jac;
    jac.template block<3, 3>(0, 0) = j_inv;
    jac.template block<3, 3>(0, 3) = -j_inv * jacobianCoupling(xi) * j_inv;
    jac.template block<3, 3>(3, 0).setZero();
    jac.template block<3, 3>(3, 3) = j_inv;
    return jac;
  }
  // Right Jacobian: exp(xi + d) ~= exp(xi) exp(J_r(xi) d); J_r(xi) = J_l(-xi).
  static Mat6 rightJacobian(const Vec6& xi) { return leftJacobian(-xi); }
  static Mat6 rightJacobianInverse(const Vec6& xi) { return leftJacobianInverse(-xi); }

  template <typename Other>
  SE3<Other> cast() const {
    return SE3<Other>(rotation_.template cast<Other>(), translation_.template cast<Other>());
  }

 private:
  // Q(upsilon, omega) = 1/2 V + a (WV + VW + WVW) + b (WWV + VWW - 3 WVW) + c (WVWW + WWVW)
  // with V = upsilon^, W = omega^ (Barfoot, "State Estimation for Robotics", eq. 7.86).
  static Mat3 jacobianCoupling(const Vec6& xi) {
    const Mat3 v = SO3<Scalar>::hat(xi.template head<3>());
    const Mat3 w = SO3<Scalar>::hat(xi.template tail<3>());
    const lie_detail::HalfAngle<Scalar> angle(xi.template tail<3>().squaredNorm());
    const Mat3 wv = w * v;
    const Mat3 vw = v * w;
    const Mat3 wvw = wv * w;
    const Mat3 wwv = w * wv;
    const Mat3 vww = vw * w;
    return Scalar(0.5) * v + angle.thetaMinusSinOverCube() * (wv + vw + wvw) +
           angle.se3SecondCoefficient() * (wwv + vww - Scalar(3) * wvw) +
           angle.se3ThirdCoefficient() * (wvw * w + w * wvw);
  }

  SO3<Scalar> rotation_;
  Vec3 translation_;
};

using SE3d = SE3<double>;
using SE3f = SE3<float>;

}  // namespace voca
