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
  // From a 4x4 or 3x4 homogeneous matrix; the rotation block is projected onto SO(3).
  template <typename Derived>
  explicit SE3(const Eigen::MatrixBase<Derived>& m)
      : rotation_(Mat3(m.template block<3, 3>(0, 0))), translation_(m.template block<3, 1>(0, 3)) {
    static_assert(Derived::ColsAtCompileTime == 4 && (Derived::RowsAtCompileTime == 3 || Derived::RowsAtCompileTime == 4),
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

  template <typename Other>
  SE3<Other> cast() const {
    return SE3<Other>(rotation_.template cast<Other>(), translation_.template cast<Other>());
  }

 private:
  SO3<Scalar> rotation_;
  Vec3 translation_;
};

using SE3d = SE3<double>;
using SE3f = SE3<float>;

}  // namespace voca
