#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <unsupported/Eigen/MatrixFunctions>
#include <vector>

#include "voca/geometry/se2.h"
#include "voca/geometry/se3.h"

using voca::SE2;
using voca::SE2d;
using voca::SE2f;
using voca::SE3;
using voca::SE3d;
using voca::SE3f;
using voca::SO3;
using voca::SO3d;
using voca::SO3f;

namespace {

constexpr double kPi = std::numbers::pi;

template <typename Scalar>
constexpr double eps() {
  return std::numeric_limits<Scalar>::epsilon();
}

Eigen::Vector3d randomUnit(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  Eigen::Vector3d v(normal(rng), normal(rng), normal(rng));
  return v.normalized();
}

// Rotation angles that exercise every branch: the tiny-angle series (theta^2 < 1e-10 double,
// 1e-5 float), both sides of the series switch of the Jacobian coefficients (theta^2 = 0.1 double,
// 1 float), generic angles and angles approaching pi.
std::vector<double> testAngles(std::mt19937& rng, double closest_to_pi) {
  std::vector<double> angles = {0.0,   1e-12, 1e-9, 1e-7,  1e-5,  3e-3, 3.2e-3, 0.1,
                                0.316, 0.317, 0.5,  0.999, 1.001, 2.0,  3.0};
  std::uniform_real_distribution<double> uniform(0.0, kPi);
  for (int i = 0; i < 40; ++i) angles.push_back(uniform(rng));
  for (double gap = 1e-2; gap >= closest_to_pi; gap *= 0.1) angles.push_back(kPi - gap);
  return angles;
}

// Central differences: truncation ~h^2 |f'''| ~ 1e-10 and rounding ~eps/h ~ 2e-11 for h = 1e-5,
// so analytic Jacobians of unit-scale tangents must agree to 1e-8.
constexpr double kStep = 1e-5;
constexpr double kNumericTol = 1e-8;

template <int N, typename F>
Eigen::Matrix<double, N, N> numericJacobian(F&& f) {
  Eigen::Matrix<double, N, N> jac;
  for (int i = 0; i < N; ++i) {
    const Eigen::Matrix<double, N, 1> d = Eigen::Matrix<double, N, 1>::Unit(i) * kStep;
    jac.col(i) = (f(d) - f(-d)) / (2 * kStep);
  }
  return jac;
}

// Checks all four Jacobians of group G at tangent x against central differences.
template <typename G>
void checkJacobians(const typename G::Tangent& x, double scale) {
  using T = typename G::Tangent;
  constexpr int N = G::Group::kDoF;
  const auto x_exp = G::Group::exp(x);
  const auto jl = numericJacobian<N>([&](const T& d) { return (G::Group::exp(x + d) * x_exp.inverse()).log(); });
  const auto jr = numericJacobian<N>([&](const T& d) { return (x_exp.inverse() * G::Group::exp(x + d)).log(); });
  const auto jl_inv = numericJacobian<N>([&](const T& d) { return (G::Group::exp(d) * x_exp).log(); });
  const auto jr_inv = numericJacobian<N>([&](const T& d) { return (x_exp * G::Group::exp(d)).log(); });
  const double tol = kNumericTol * scale;
  CHECK((G::Group::leftJacobian(x) - jl).cwiseAbs().maxCoeff() < tol);
  CHECK((G::Group::rightJacobian(x) - jr).cwiseAbs().maxCoeff() < tol);
  CHECK((G::Group::leftJacobianInverse(x) - jl_inv).cwiseAbs().maxCoeff() < tol);
  CHECK((G::Group::rightJacobianInverse(x) - jr_inv).cwiseAbs().maxCoeff() < tol);
  using Mat = Eigen::Matrix<double, N, N>;
  // Product with the inverse is a handful of flops on O(scale) entries.
  CHECK((G::Group::leftJacobian(x) * G::Group::leftJacobianInverse(x) - Mat::Identity()).cwiseAbs().maxCoeff() <
        1e-13 * scale);
  CHECK((G::Group::rightJacobian(x) * G::Group::rightJacobianInverse(x) - Mat::Identity()).cwiseAbs().maxCoeff() <
        1e-13 * scale);
}

template <typename Grp>
struct Traits {
  using Group = Grp;
  using Tangent = Eigen::Matrix<double, Grp::kDoF, 1>;
};

}  // namespace

TEST_CASE_TEMPLATE("SO3 exp/log round trip over random tangents", Scalar, double, float) {
  std::mt19937 rng(7);
  // Float loses the sign of w = cos(theta/2) ~ 5e-5 only far below this gap; double keeps it to 1e-9.
  const double closest = std::is_same_v<Scalar, double> ? 1e-9 : 1e-4;
  double worst = 0;
  for (double theta : testAngles(rng, closest)) {
    const Eigen::Vector3d omega = theta * randomUnit(rng);
    const Eigen::Matrix<Scalar, 3, 1> omega_s = omega.cast<Scalar>();
    const Eigen::Vector3d back = SO3<Scalar>::exp(omega_s).log().template cast<double>();
    // Relative to |omega|: both maps are relative-accurate down to 0 (series) and the angle error
    // near pi is a few eps absolute. The rounding of omega itself to Scalar is also eps relative.
    const double rel = (back - omega).norm() / std::max(omega.norm(), 1e-300);
    worst = std::max(worst, theta == 0.0 ? (back.norm() == 0 ? 0.0 : 1.0) : rel / eps<Scalar>());
  }
  MESSAGE("SO3 worst round-trip error / eps: " << worst);
  // A few tens of roundings (trig, normalisation, atan2) -> allow 16 eps.
  CHECK(worst < 16);
}

TEST_CASE_TEMPLATE("SO3 log at and beyond pi", Scalar, double, float) {
  using Mat3 = Eigen::Matrix<Scalar, 3, 3>;
  using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
  std::mt19937 rng(11);
  // Near pi the axis sign is arbitrary, so check exp(log(R)) = R and the angle instead of log(exp(x)).
  // The rotation matrix entries are O(1): 16 eps covers the roundings of exp, log and matrix().
  const double tol = 16 * eps<Scalar>();
  for (double gap : {1e-2, 1e-5, 1e-8, 0.0, -1e-8, -1e-5, -1e-2}) {
    const Eigen::Vector3d axis = randomUnit(rng);
    const SO3<Scalar> r = SO3<Scalar>::exp((axis * (kPi - gap)).cast<Scalar>());
    const Vec3 omega = r.log();
    CHECK(double(omega.norm()) <= kPi + 4 * eps<Scalar>());
    CHECK(double(omega.norm()) == doctest::Approx(kPi - std::abs(gap)).epsilon(4 * eps<Scalar>()));
    CHECK(double((SO3<Scalar>::exp(omega).matrix() - r.matrix()).cwiseAbs().maxCoeff()) < tol);
  }
  // An exact half turn built as a matrix, R = 2 a a^T - I, must give log = +-pi a.
  for (int i = 0; i < 20; ++i) {
    const Vec3 a = randomUnit(rng).cast<Scalar>();
    const Mat3 half_turn = Scalar(2) * a * a.transpose() - Mat3::Identity();
    const Vec3 omega = SO3<Scalar>(half_turn).log();
    const double err = std::min((omega - Scalar(kPi) * a).norm(), (omega + Scalar(kPi) * a).norm());
    // Quaternion extraction from the matrix takes a square root of ~1: error ~ a few eps * pi.
    CHECK(err < 16 * eps<Scalar>());
  }
  const Vec3 x_half_turn = SO3<Scalar>(Mat3(Vec3(1, -1, -1).asDiagonal())).log();
  CHECK(double(std::abs(x_half_turn.x())) == doctest::Approx(kPi).epsilon(4 * eps<Scalar>()));
  CHECK(double(x_half_turn.template tail<2>().norm()) < 4 * eps<Scalar>());
}

TEST_CASE_TEMPLATE("SE3 exp/log round trip over random tangents", Scalar, double, float) {
  std::mt19937 rng(3);
  const double closest = std::is_same_v<Scalar, double> ? 1e-9 : 1e-4;
  std::uniform_real_distribution<double> uniform(-5.0, 5.0);
  double worst = 0;
  for (double theta : testAngles(rng, closest)) {
    for (double trans_scale : {1e-6, 1.0}) {
      Eigen::Matrix<double, 6, 1> xi;
      xi << trans_scale * Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng)), theta * randomUnit(rng);
      const Eigen::Matrix<double, 6, 1> back = SE3<Scalar>::exp(xi.cast<Scalar>()).log().template cast<double>();
      worst = std::max(worst, (back - xi).norm() / xi.norm() / eps<Scalar>());
    }
  }
  MESSAGE("SE3 worst round-trip error / (eps |xi|): " << worst);
  // The translation goes through J_l and J_l^-1 (3x3 products, ~10 roundings each) and inherits the
  // rotation's error times |upsilon|: 64 eps relative to |xi|.
  CHECK(worst < 64);
}

TEST_CASE_TEMPLATE("SE2 exp/log round trip over random tangents", Scalar, double, float) {
  std::mt19937 rng(5);
  const double closest = std::is_same_v<Scalar, double> ? 1e-9 : 1e-4;
  std::uniform_real_distribution<double> uniform(-5.0, 5.0);
  double worst = 0;
  for (double theta : testAngles(rng, closest)) {
    for (double sign : {1.0, -1.0}) {
      const Eigen::Vector3d xi(uniform(rng), uniform(rng), sign * theta);
      const Eigen::Vector3d back = SE2<Scalar>::exp(xi.cast<Scalar>()).log().template cast<double>();
      worst = std::max(worst, (back - xi).norm() / xi.norm() / eps<Scalar>());
    }
  }
  MESSAGE("SE2 worst round-trip error / (eps |xi|): " << worst);
  // Fewer operations than SE3: 2x2 products and one atan2.
  CHECK(worst < 32);
}

TEST_CASE("exp agrees with the matrix exponential of hat") {
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> uniform(-2.0, 2.0);
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector3d omega = (i == 0 ? 1e-7 : 3.0 * std::abs(uniform(rng)) / 2) * randomUnit(rng);
    Eigen::Matrix<double, 6, 1> xi;
    xi << uniform(rng), uniform(rng), uniform(rng), omega;
    const Eigen::Vector3d xi2(uniform(rng), uniform(rng), omega.x());
    // Eigen's Pade-based matrix exponential is accurate to ~1e-15 relative on these O(1) inputs.
    CHECK((SO3d::exp(omega).matrix() - Eigen::Matrix3d(SO3d::hat(omega).exp())).norm() < 1e-13);
    CHECK((SE3d::exp(xi).matrix() - Eigen::Matrix4d(SE3d::hat(xi).exp())).norm() < 1e-13);
    CHECK((SE2d::exp(xi2).matrix() - Eigen::Matrix3d(SE2d::hat(xi2).exp())).norm() < 1e-13);
    CHECK((SO3d::vee(SO3d::hat(omega)) - omega).norm() == 0);
    CHECK((SE3d::vee(SE3d::hat(xi)) - xi).norm() == 0);
    CHECK((SE2d::vee(SE2d::hat(xi2)) - xi2).norm() == 0);
  }
}

TEST_CASE("analytic Jacobians match central differences") {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> uniform(-2.0, 2.0);
  // Stay 0.05 below pi so the +-h steps never cross log's branch cut.
  for (double theta : {0.0, 1e-9, 1e-6, 1e-3, 0.2, 0.316, 0.317, 0.8, 1.0, 1.5, 2.5, kPi - 0.05}) {
    const Eigen::Vector3d omega = theta * randomUnit(rng);
    CAPTURE(theta);
    checkJacobians<Traits<SO3d>>(omega, 1.0);
    Eigen::Matrix<double, 6, 1> xi;
    xi << uniform(rng), uniform(rng), uniform(rng), omega;
    // SE3/SE2 entries scale with |upsilon| <= 3.5.
    checkJacobians<Traits<SE3d>>(xi, 4.0);
    checkJacobians<Traits<SE2d>>(Eigen::Vector3d(uniform(rng), uniform(rng), theta), 4.0);
    checkJacobians<Traits<SE2d>>(Eigen::Vector3d(uniform(rng), uniform(rng), -theta), 4.0);
  }
}

TEST_CASE("float Jacobians agree with double ones across the series switch points") {
  std::mt19937 rng(19);
  std::uniform_real_distribution<double> uniform(-2.0, 2.0);
  double worst = 0;
  for (double theta : {0.0, 1e-6, 3.1e-3, 3.2e-3, 0.3, 0.99, 1.01, 2.0, 3.0, kPi - 1e-3}) {
    const Eigen::Vector3d omega = theta * randomUnit(rng);
    Eigen::Matrix<double, 6, 1> xi;
    xi << uniform(rng), uniform(rng), uniform(rng), omega;
    const Eigen::Vector3d xi2(uniform(rng), uniform(rng), -theta);
    const Eigen::Vector3f omega_f = omega.cast<float>();
    const Eigen::Matrix<float, 6, 1> xi_f = xi.cast<float>();
    const Eigen::Vector3f xi2_f = xi2.cast<float>();
    auto diff = [](const auto& a, const auto& b) { return (a.template cast<double>() - b).cwiseAbs().maxCoeff(); };
    for (double d : {diff(SO3f::leftJacobian(omega_f), SO3d::leftJacobian(omega)),
                     diff(SO3f::leftJacobianInverse(omega_f), SO3d::leftJacobianInverse(omega)),
                     diff(SE3f::leftJacobian(xi_f), SE3d::leftJacobian(xi)),
                     diff(SE3f::leftJacobianInverse(xi_f), SE3d::leftJacobianInverse(xi)),
                     diff(SE2f::leftJacobian(xi2_f), SE2d::leftJacobian(xi2)),
                     diff(SE2f::leftJacobianInverse(xi2_f), SE2d::leftJacobianInverse(xi2))}) {
      worst = std::max(worst, d / eps<float>());
    }
  }
  MESSAGE("float vs double Jacobians, worst entry error / float eps: " << worst);
  // Entries are O(|upsilon|) <= 3.5 and each is a few products of series/closed-form coefficients;
  // the closed forms' cancellation is bounded by the switch points (eps/theta^2 <= eps there).
  CHECK(worst < 64);
}

TEST_CASE("adjoint: T exp(x) T^-1 = exp(Adj x)") {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> uniform(-3.0, 3.0);
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector3d omega = uniform(rng) * randomUnit(rng);
    Eigen::Matrix<double, 6, 1> xi, xi_t;
    xi << uniform(rng), uniform(rng), uniform(rng), 0.5 * uniform(rng) * randomUnit(rng);
    xi_t << uniform(rng), uniform(rng), uniform(rng), omega;
    const SO3d r = SO3d::exp(omega);
    const SE3d t = SE3d::exp(xi_t);
    const SE2d t2(uniform(rng), Eigen::Vector2d(uniform(rng), uniform(rng)));
    const Eigen::Vector3d x2(uniform(rng), uniform(rng), 0.5 * uniform(rng));
    const Eigen::Vector3d w = xi.tail<3>();
    // Matrices with O(10) entries after a few products: 1e-13 is ~500 eps.
    CHECK(((r * SO3d::exp(w) * r.inverse()).matrix() - SO3d::exp(r.adjoint() * w).matrix()).norm() < 1e-13);
    CHECK(((t * SE3d::exp(xi) * t.inverse()).matrix() - SE3d::exp(t.adjoint() * xi).matrix()).norm() < 1e-13);
    CHECK(((t2 * SE2d::exp(x2) * t2.inverse()).matrix() - SE2d::exp(t2.adjoint() * x2).matrix()).norm() < 1e-13);
  }
}

TEST_CASE_TEMPLATE("quaternion and matrix conversions round trip", Scalar, double, float) {
  using Mat3 = Eigen::Matrix<Scalar, 3, 3>;
  using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  // O(1) entries through normalisation / SVD: 16 eps.
  const Scalar tol = Scalar(16 * eps<Scalar>());
  for (int i = 0; i < 30; ++i) {
    const SO3<Scalar> r = SO3<Scalar>::exp((3.0 * uniform(rng) * randomUnit(rng)).cast<Scalar>());
    CHECK((SO3<Scalar>(r.unitQuaternion()).matrix() - r.matrix()).norm() < tol);
    CHECK((SO3<Scalar>(r.matrix()).matrix() - r.matrix()).norm() < tol);
    const Eigen::Quaternion<Scalar> q_eigen(r.matrix());
    CHECK(std::abs(std::abs(q_eigen.dot(r.unitQuaternion())) - Scalar(1)) < tol);
    // A noisy matrix is projected onto the nearest rotation: orthonormal, det +1, and no farther
    // (Frobenius) from the input than the rotation that was perturbed.
    Mat3 noisy = r.matrix();
    for (int k = 0; k < 9; ++k) noisy(k) += Scalar(1e-2 * uniform(rng));
    const Mat3 projected = SO3<Scalar>(noisy).matrix();
    CHECK((projected.transpose() * projected - Mat3::Identity()).norm() < tol);
    CHECK(std::abs(projected.determinant() - Scalar(1)) < tol);
    CHECK((projected - noisy).norm() <= (r.matrix() - noisy).norm() + tol);
    CHECK((projected - r.matrix()).norm() < Scalar(0.05));

    const SE3<Scalar> t(r, Vec3(uniform(rng), uniform(rng), uniform(rng)) * Scalar(10));
    // Translations up to ~17 m: 32 eps relative.
    const Scalar tol_t = Scalar(32 * eps<Scalar>() * 17);
    CHECK((SE3<Scalar>(t.matrix()).matrix() - t.matrix()).norm() < tol_t);
    CHECK((SE3<Scalar>(t.matrix3x4()).matrix() - t.matrix()).norm() < tol_t);
    CHECK((SE3<Scalar>(t.rotationMatrix(), t.translation()).matrix() - t.matrix()).norm() < tol_t);
    CHECK((SE3<Scalar>(t.unitQuaternion(), t.translation()).matrix() - t.matrix()).norm() < tol_t);

    const SE2<Scalar> p(Scalar(3 * uniform(rng)), Eigen::Matrix<Scalar, 2, 1>(uniform(rng), uniform(rng)));
    CHECK((SE2<Scalar>(p.matrix()).matrix() - p.matrix()).norm() < tol);
    CHECK((SE2<Scalar>(p.matrix2x3()).matrix() - p.matrix()).norm() < tol);
  }
}

TEST_CASE("SE2 from angle and translation acts on points") {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> uniform(-3.0, 3.0);
  for (int i = 0; i < 20; ++i) {
    const double theta = uniform(rng);
    const Eigen::Vector2d t(uniform(rng), uniform(rng)), p(uniform(rng), uniform(rng));
    const SE2d a(theta, t);
    const Eigen::Matrix2d rot = Eigen::Rotation2Dd(theta).toRotationMatrix();
    CHECK((a * p - (rot * p + t)).norm() < 1e-14);
    CHECK(a.angle() == doctest::Approx(theta).epsilon(1e-15));
    CHECK(a.log().z() == doctest::Approx(theta).epsilon(1e-15));
    const SE2f af(float(theta), t.cast<float>());
    // Float: O(3) coordinates, a few roundings -> 8 float eps * 10.
    CHECK(((af * p.cast<float>()).cast<double>() - (rot * p + t)).norm() < 1e-5);
  }
}

TEST_CASE_TEMPLATE("composition is associative and inverse cancels", Scalar, double, float) {
  using Vec2 = Eigen::Matrix<Scalar, 2, 1>;
  using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
  using Vec6 = Eigen::Matrix<Scalar, 6, 1>;
  std::mt19937 rng(37);
  std::uniform_real_distribution<Scalar> uniform(-3, 3);
  auto rand3 = [&] { return Vec3(uniform(rng), uniform(rng), uniform(rng)); };
  auto rand6 = [&] {
    Vec6 v;
    for (int k = 0; k < 6; ++k) v(k) = uniform(rng);
    return v;
  };
  // Coordinates up to ~10 after three compositions: 64 eps * 10 absolute.
  const Scalar tol = Scalar(640 * eps<Scalar>());
  for (int i = 0; i < 30; ++i) {
    const SO3<Scalar> ra = SO3<Scalar>::exp(rand3()), rb = SO3<Scalar>::exp(rand3()), rc = SO3<Scalar>::exp(rand3());
    CHECK((((ra * rb) * rc).matrix() - (ra * (rb * rc)).matrix()).norm() < tol);
    CHECK(((ra * ra.inverse()).matrix() - Eigen::Matrix<Scalar, 3, 3>::Identity()).norm() < tol);
    CHECK(((ra * rb).matrix() - ra.matrix() * rb.matrix()).norm() < tol);

    const SE3<Scalar> a = SE3<Scalar>::exp(rand6()), b = SE3<Scalar>::exp(rand6()), c = SE3<Scalar>::exp(rand6());
    const Vec3 p = rand3();
    CHECK((((a * b) * c).matrix() - (a * (b * c)).matrix()).norm() < tol);
    CHECK(((a * a.inverse()).matrix() - Eigen::Matrix<Scalar, 4, 4>::Identity()).norm() < tol);
    CHECK(((a * b).matrix() - a.matrix() * b.matrix()).norm() < tol);
    CHECK(((a * b) * p - a * (b * p)).norm() < tol);
    CHECK((a.inverse() * (a * p) - p).norm() < tol);

    const SE2<Scalar> d = SE2<Scalar>::exp(rand3()), e = SE2<Scalar>::exp(rand3()), f = SE2<Scalar>::exp(rand3());
    const Vec2 q(uniform(rng), uniform(rng));
    CHECK((((d * e) * f).matrix() - (d * (e * f)).matrix()).norm() < tol);
    CHECK(((d * d.inverse()).matrix() - Eigen::Matrix<Scalar, 3, 3>::Identity()).norm() < tol);
    CHECK(((d * e).matrix() - d.matrix() * e.matrix()).norm() < tol);
    CHECK(((d * e) * q - d * (e * q)).norm() < tol);
  }
  // A long chain stays on the group: the rotation parts remain unit length.
  SE2<Scalar> chain;
  SO3<Scalar> chain3;
  for (int i = 0; i < 10000; ++i) {
    chain = chain * SE2<Scalar>::exp(rand3() * Scalar(0.1));
    chain3 = chain3 * SO3<Scalar>::exp(rand3() * Scalar(0.1));
  }
  CHECK(std::abs(chain.unitComplex().norm() - Scalar(1)) < Scalar(4 * eps<Scalar>()));
  CHECK(std::abs(chain3.unitQuaternion().norm() - Scalar(1)) < Scalar(4 * eps<Scalar>()));
}

TEST_CASE("cast between precisions") {
  Eigen::Matrix<double, 6, 1> xi;
  xi << 1.0, -2.0, 0.5, 0.3, -1.2, 2.0;
  const SE3d t = SE3d::exp(xi);
  // One float rounding of O(2) values: 1e-6.
  CHECK((t.cast<float>().cast<double>().matrix() - t.matrix()).norm() < 1e-6);
  CHECK((t.so3().cast<float>().cast<double>().matrix() - t.rotationMatrix()).norm() < 1e-6);
  const SE2d p(2.5, Eigen::Vector2d(1.0, -3.0));
  CHECK((p.cast<float>().cast<double>().matrix() - p.matrix()).norm() < 1e-6);
}
