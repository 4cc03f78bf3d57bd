#pragma once
// SE(2): planar rigid transforms (e.g. image-patch warps), tangent = (tx, ty, theta).

#include <Eigen/Core>
#include <cmath>

#include "voca/geometry/lie_coefficients.h"

namespace voca {

template <typename Scalar>
class SE2 {
 public:
  using Vec2 = Eigen::Matrix<Scalar, 2, 1>;
  using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
  using Mat2 = Eigen::Matrix<Scalar, 2, 2>;
  using Mat3 = Eigen::Matrix<Scalar, 3, 3>;
  using Mat23 = Eigen::Matrix<Scalar, 2, 3>;
  static constexpr int kDoF = 3;

  SE2() : cos_sin_(Scalar(1), Scalar(0)), translation_(Vec2::Zero()) {}
  SE2(Scalar theta, const Vec2& translation) : translation_(translation) {
    using std::cos;
    using std::sin;
    cos_sin_ = Vec2(cos(theta), sin(theta));
  }
  // The rotation matrix is projected onto SO(2): (r00 + r11, r10 - r01) normalised is the nearest
  // rotation in the Frobenius norm.
  SE2(const Mat2& rotation, const Vec2& translation)
      : cos_sin_(rotation(0, 0) + rotation(1, 1), rotation(1, 0) - rotation(0, 1)), translation_(translation) {
    cos_sin_.normalize();
  }
  // From a 3x3 homogeneous or 2x3 matrix.
  template <typename Derived>
  explicit SE2(const Eigen::MatrixBase<Derived>& m)
      : SE2(Mat2(m.template block<2, 2>(0, 0)), Vec2(m.template block<2, 1>(0, 2))) {
    static_assert(
        Derived::ColsAtCompileTime == 3 && (Derived::RowsAtCompileTime == 2 || Derived::RowsAtCompileTime == 3),
        "SE2 from a matrix needs 2x3 or 3x3");
  }

  static SE2 identity() { return SE2(); }

  // xi = (upsilon, theta): t = V(theta) upsilon with V = [[A, -B], [B, A]], A = sin/theta,
  // B = (1 - cos)/theta. One sin/cos pair of the half angle gives everything.
  static SE2 exp(const Vec3& xi) {
    const lie_detail::HalfAngle<Scalar> a(xi.z() * xi.z());
    const Scalar sinc = a.sinc();
    const Scalar b = xi.z() * a.oneMinusCosOverSq();
    SE2 result;
    result.cos_sin_ = Vec2(a.cosTheta(), Scalar(2) * a.sin_half * (xi.z() < Scalar(0) ? -a.cos_half : a.cos_half));
    result.translation_ = Vec2(sinc * xi.x() - b * xi.y(), b * xi.x() + sinc * xi.y());
    return result;
  }
  // Tangent with theta in [-pi, pi]; upsilon = V^-1 t with V^-1 = [[h, theta/2], [-theta/2, h]],
  // h = (theta/2) cot(theta/2).
  Vec3 log() const {
    const Scalar theta = angle();
    const Scalar c = cos_sin_.x();
    const Scalar s = cos_sin_.y();
    Scalar h;
    if (theta * theta < lie_detail::tinyAngleSquared<Scalar>()) {
      h = Scalar(1) - theta * theta / Scalar(12);
    } else if (c >= Scalar(0)) {
      // cot(theta/2) = (1 + cos) / sin: both well conditioned while cos >= 0.
      h = Scalar(0.5) * theta * (Scalar(1) + c) / s;
    } else {
      // cot(theta/2) = sin / (1 - cos), with 1 - cos >= 1 here.
      h = Scalar(0.5) * theta * s / (Scalar(1) - c);
    }
    const Scalar half = Scalar(0.5) * theta;
    return Vec3(h * translation_.x() + half * translation_.y(), -half * translation_.x() + h * translation_.y(), theta);
  }

  SE2 inverse() const {
    SE2 result;
    result.cos_sin_ = Vec2(cos_sin_.x(), -cos_sin_.y());
    result.translation_ = -result.rotate(translation_);
    return result;
  }
  SE2 operator*(const SE2& other) const {
    SE2 result;
    const Scalar c = cos_sin_.x() * other.cos_sin_.x() - cos_sin_.y() * other.cos_sin_.y();
    const Scalar s = cos_sin_.y() * other.cos_sin_.x() + cos_sin_.x() * other.cos_sin_.y();
    // One Newton step towards unit length keeps long products on the circle without a sqrt.
    const Scalar scale = (Scalar(3) - (c * c + s * s)) / Scalar(2);
    result.cos_sin_ = Vec2(c * scale, s * scale);
    result.translation_ = translation_ + rotate(other.translation_);
    return result;
  }
  SE2& operator*=(const SE2& other) { return *this = *this * other; }
  Vec2 operator*(const Vec2& point) const { return rotate(point) + translation_; }

  // Rotation angle in [-pi, pi].
  Scalar angle() const {
    using std::atan2;
    return atan2(cos_sin_.y(), cos_sin_.x());
  }
  // (cos theta, sin theta).
  const Vec2& unitComplex() const { return cos_sin_; }
  const Vec2& translation() const { return translation_; }
  Vec2& translation() { return translation_; }
  Mat2 rotationMatrix() const {
    Mat2 r;
    r << cos_sin_.x(), -cos_sin_.y(), cos_sin_.y(), cos_sin_.x();
    return r;
  }
  Mat3 matrix() const {
    Mat3 m = Mat3::Identity();
    m.template block<2, 2>(0, 0) = rotationMatrix();
    m.template block<2, 1>(0, 2) = translation_;
    return m;
  }
  Mat23 matrix2x3() const { return matrix().template topRows<2>(); }

  // Adj such that T exp(xi) T^-1 = exp(Adj xi): [[R, (ty, -tx)], [0, 1]].
  Mat3 adjoint() const {
    Mat3 adj = Mat3::Identity();
    adj.template block<2, 2>(0, 0) = rotationMatrix();
    adj(0, 2) = translation_.y();
    adj(1, 2) = -translation_.x();
    return adj;
  }

  // xi = (tx, ty, theta) -> [[0, -theta, tx], [theta, 0, ty], [0, 0, 0]].
  static Mat3 hat(const Vec3& xi) {
    Mat3 m;
    m << Scalar(0), -xi.z(), xi.x(), xi.z(), Scalar(0), xi.y(), Scalar(0), Scalar(0), Scalar(0);
    return m;
  }
  // Reads the skew-symmetric part of the rotation block.
  static Vec3 vee(const Mat3& m) { return Vec3(m(0, 2), m(1, 2), Scalar(0.5) * (m(1, 0) - m(0, 1))); }

  // Left Jacobian: exp(xi + d) ~= exp(J_l(xi) d) exp(xi); [[V, w], [0, 1]] with
  // w = (x c + y b, -x b + y c), b = (1 - cos)/theta^2, c = (theta - sin)/theta^2.
  static Mat3 leftJacobian(const Vec3& xi) {
    const lie_detail::HalfAngle<Scalar> a(xi.z() * xi.z());
    const Scalar sinc = a.sinc();
    const Scalar b = a.oneMinusCosOverSq();
    const Scalar c = xi.z() * a.thetaMinusSinOverCube();
    const Scalar bt = xi.z() * b;
    Mat3 jac;
    jac << sinc, -bt, xi.x() * c + xi.y() * b,  //
        bt, sinc, -xi.x() * b + xi.y() * c,     //
        Scalar(0), Scalar(0), Scalar(1);
    return jac;
  }
  // Inverse of leftJacobian(xi): [[V^-1, -V^-1 w], [0, 1]].
  static Mat3 leftJacobianInverse(const Vec3& xi) {
    const lie_detail::HalfAngle<Scalar> a(xi.z() * xi.z());
    const Scalar h = a.halfThetaCotHalfTheta();
    const Scalar half = Scalar(0.5) * xi.z();
    const Scalar b = a.oneMinusCosOverSq();
    const Scalar c = xi.z() * a.thetaMinusSinOverCube();
    const Vec2 w(xi.x() * c + xi.y() * b, -xi.x() * b + xi.y() * c);
    Mat2 v_inv;
    v_inv << h, half, -half, h;
    Mat3 jac = Mat3::Identity();
    jac.template block<2, 2>(0, 0) = v_inv;
    jac.template block<2, 1>(0, 2) = -v_inv * w;
    return jac;
  }
  // Right Jacobian: exp(xi + d) ~= exp(xi) exp(J_r(xi) d); J_r(xi) = J_l(-xi).
  static Mat3 rightJacobian(const Vec3& xi) { return leftJacobian(-xi); }
  static Mat3 rightJacobianInverse(const Vec3& xi) { return leftJacobianInverse(-xi); }

  template <typename Other>
  SE2<Other> cast() const {
    return SE2<Other>(rotationMatrix().template cast<Other>(), translation_.template cast<Other>());
  }

 private:
  Vec2 rotate(const Vec2& p) const {
    return Vec2(cos_sin_.x() * p.x() - cos_sin_.y() * p.y(), cos_sin_.y() * p.x() + cos_sin_.x() * p.y());
  }

  Vec2 cos_sin_;
  Vec2 translation_;
};

using SE2d = SE2<double>;
using SE2f = SE2<float>;

}  // namespace voca
