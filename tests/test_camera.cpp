// Camera models: round trips over whole images, analytic vs numerical Jacobians, float vs double,
// valid regions and hand-derived projections.

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>

#include "voca/camera/fast_atan2.h"
#include "voca/camera/generic_camera.h"

namespace {

using voca::DoubleSphereCamera;
using voca::ExtendedUnifiedCamera;
using voca::KannalaBrandt4Camera;
using voca::PinholeCamera;
using voca::PinholeRadtan8Camera;

// Real calibrations (facts copied from the dataset calibration files named beside each).
struct ImageSize {
  int width;
  int height;
};
constexpr ImageSize kEurocSize{752, 480};
constexpr ImageSize kT265Size{848, 800};
constexpr ImageSize kTumvi512Size{512, 512};

// EuRoC cam0, Kalibr pinhole + radtan (k1 k2 p1 p2), as pinhole-radtan8 with k3..k6 = 0.
Eigen::Matrix<double, 12, 1> eurocRadtan() {
  Eigen::Matrix<double, 12, 1> p;
  p << 458.654, 457.296, 367.215, 248.375, -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05, 0, 0, 0, 0;
  return p;
}
// A full rational model (every coefficient non-zero) on the EuRoC image, to exercise k3..k6.
Eigen::Matrix<double, 12, 1> syntheticRational() {
  Eigen::Matrix<double, 12, 1> p;
  p << 458.654, 457.296, 367.215, 248.375, 0.4, -0.05, 0.0012, -0.0008, 0.01, 0.7, -0.02, 0.004;
  return p;
}
Eigen::Matrix<double, 4, 1> eurocPinhole() { return Eigen::Vector4d(458.654, 457.296, 367.215, 248.375); }
// euroc_ds_calib.json cam0.
Eigen::Matrix<double, 6, 1> eurocDs() {
  Eigen::Matrix<double, 6, 1> p;
  p << 349.7560023050409, 348.72454229977037, 365.89440762590149, 249.32995565708704, -0.2409573942178872,
      0.566996899163044;
  return p;
}
// tumvi_512_ds_calib.json cam0 (195 degree fisheye).
Eigen::Matrix<double, 6, 1> tumviDs() {
  Eigen::Matrix<double, 6, 1> p;
  p << 158.28600034966977, 158.2743455478755, 254.96116578191653, 256.8894394501779, -0.17213086034353243,
      0.5931177593944744;
  return p;
}
// euroc_eucm_calib.json cam0.
Eigen::Matrix<double, 6, 1> eurocEucm() {
  Eigen::Matrix<double, 6, 1> p;
  p << 460.76484651566468, 459.4051018049483, 365.8937161309615, 249.33499869752445, 0.5903365915227143,
      1.127468196965374;
  return p;
}
// t265_kb4_calib.json cam0.
Eigen::Matrix<double, 8, 1> t265Kb4() {
  Eigen::Matrix<double, 8, 1> p;
  p << 286.60144163375528, 286.4617087423328, 422.2765876951761, 395.2246466040553, -0.006762412326815424,
      0.045170283325720008, -0.043515167278210638, 0.008374959821591333;
  return p;
}

// Unprojects every 8th pixel of the image and projects the bearing (at two depths) back.
// Returns the fraction of pixels that unprojected.
template <class Model>
double checkGridRoundTrip(const Model& camera, ImageSize size) {
  int total = 0, valid = 0;
  double worst_px = 0.0, worst_norm = 0.0;
  for (int v = 0; v < size.height; v += 8) {
    for (int u = 0; u < size.width; u += 8) {
      ++total;
      const Eigen::Vector2d uv(u, v);
      Eigen::Vector3d bearing = Eigen::Vector3d::Zero();
      if (!camera.unproject(uv, bearing)) continue;
      ++valid;
      worst_norm = std::max(worst_norm, std::abs(bearing.norm() - 1.0));
      for (const double depth : {0.5, 7.0}) {
        Eigen::Vector2d back = Eigen::Vector2d::Zero();
        REQUIRE(camera.project(depth * bearing, back));
        worst_px = std::max(worst_px, (back - uv).norm());
      }
    }
  }
  // Double precision: the closed forms are exact to rounding and the iterative inverses stop at
  // a residual of a few 1e-15 in normalised units, i.e. far below 1e-6 px.
  CHECK(worst_px < 1e-6);
  CHECK(worst_norm < 1e-12);
  return static_cast<double>(valid) / total;
}

// Projects random bearings covering the model's field of view and unprojects them again.
template <class Model>
void checkBearingRoundTrip(const Model& camera, double max_angle_rad) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(0.0, max_angle_rad), azimuth(-std::numbers::pi, std::numbers::pi);
  int projected = 0;
  for (int i = 0; i < 500; ++i) {
    const double a = angle(rng), b = azimuth(rng);
    const Eigen::Vector3d bearing(std::sin(a) * std::cos(b), std::sin(a) * std::sin(b), std::cos(a));
    Eigen::Vector2d uv = Eigen::Vector2d::Zero();
    if (!camera.project(3.0 * bearing, uv)) continue;
    ++projected;
    Eigen::Vector3d back = Eigen::Vector3d::Zero();
    REQUIRE(camera.unproject(uv, back));
    CHECK((back - bearing).norm() < 1e-9);  // same argument as the grid round trip
  }
  CHECK(projected == 500);  // max_angle_rad is chosen inside each model's valid region
}

// Central differences; the step is small against the curvature of the models (truncation error
// ~h^2) and large against rounding (eps/h ~ 1e-10 relative).
template <int Rows, int Cols, class F>
Eigen::Matrix<double, Rows, Cols> numericalJacobian(F f, const Eigen::Matrix<double, Cols, 1>& x,
                                                    const Eigen::Matrix<double, Cols, 1>& steps) {
  Eigen::Matrix<double, Rows, Cols> j;
  for (int i = 0; i < Cols; ++i) {
    Eigen::Matrix<double, Cols, 1> plus = x, minus = x;
    plus[i] += steps[i];
    minus[i] -= steps[i];
    j.col(i) = (f(plus) - f(minus)) / (2.0 * steps[i]);
  }
  return j;
}

template <class A, class B>
double relativeError(const A& analytic, const B& numeric) {
  return (analytic - numeric).cwiseAbs().maxCoeff() / std::max(1e-3, numeric.cwiseAbs().maxCoeff());
}

// Compares all three analytic Jacobians with numerical ones at points spread over the image.
template <class Model>
void checkJacobians(const Model& camera, ImageSize size) {
  using Params = typename Model::Params;
  constexpr int kN = Model::kNumParams;
  // Relative error bound: the numerical Jacobian is accurate to ~1e-8 relative with these steps;
  // a wrong analytic term is off by O(1).
  constexpr double kTolerance = 1e-6;
  int checked = 0;
  for (int iv = 0; iv <= 4; ++iv) {
    for (int iu = 0; iu <= 6; ++iu) {
      const Eigen::Vector2d uv(0.5 + iu * (size.width - 1.0) / 6.0, 0.5 + iv * (size.height - 1.0) / 4.0);
      Eigen::Vector3d bearing = Eigen::Vector3d::Zero();
      Eigen::Matrix<double, 3, 2> d_bearing_d_uv;
      if (!camera.unproject(uv, bearing, &d_bearing_d_uv)) continue;
      ++checked;
      const auto unproject = [&](const Eigen::Vector2d& q) {
        Eigen::Vector3d b = Eigen::Vector3d::Zero();
        REQUIRE(camera.unproject(q, b));
        return b;
      };
      const Eigen::Matrix<double, 3, 2> num_unproject =
          numericalJacobian<3, 2>(unproject, uv, Eigen::Vector2d::Constant(1e-3));
      CHECK(relativeError(d_bearing_d_uv, num_unproject) < kTolerance);

      const Eigen::Vector3d p = 2.5 * bearing;
      Eigen::Vector2d projected = Eigen::Vector2d::Zero();
      Eigen::Matrix<double, 2, 3> d_uv_d_p;
      // NaN until project() writes them: an entry it leaves unset fails allFinite() (and GCC for
      // 32-bit ARM no longer warns that the matrices may be used uninitialized).
      d_uv_d_p.setConstant(std::numeric_limits<double>::quiet_NaN());
      Eigen::Matrix<double, 2, kN> d_uv_d_params =
          Eigen::Matrix<double, 2, kN>::Constant(std::numeric_limits<double>::quiet_NaN());
      REQUIRE(camera.project(p, projected, &d_uv_d_p, &d_uv_d_params));
      CHECK(d_uv_d_p.allFinite());
      CHECK(d_uv_d_params.allFinite());
      const auto projectPoint = [&](const Eigen::Vector3d& q) {
        Eigen::Vector2d r = Eigen::Vector2d::Zero();
        REQUIRE(camera.project(q, r));
        return r;
      };
      CHECK(relativeError(d_uv_d_p, numericalJacobian<2, 3>(projectPoint, p, Eigen::Vector3d::Constant(1e-6))) <
            kTolerance);
      const auto projectWithParams = [&](const Params& params) {
        Eigen::Vector2d r = Eigen::Vector2d::Zero();
        REQUIRE(Model(params).project(p, r));
        return r;
      };
      const Params steps = (camera.params().cwiseAbs().array().max(1.0) * 1e-6).matrix();
      CHECK(relativeError(d_uv_d_params, numericalJacobian<2, kN>(projectWithParams, camera.params(), steps)) <
            kTolerance);
    }
  }
  CHECK(checked >= 30);  // of 35 samples; only fisheye corners outside the valid region may drop
}

// Float against double for the same pixels: float keeps ~7 significant digits, pixel coordinates
// are below 1000 (ulp 6e-5 px) and each model chains a few dozen operations.
template <class Model>
void checkFloatMatchesDouble(const Model& camera, ImageSize size) {
  const auto camera_f = camera.template cast<float>();
  int compared = 0;
  for (int v = 4; v < size.height; v += 24) {
    for (int u = 4; u < size.width; u += 24) {
      Eigen::Vector3d bearing = Eigen::Vector3d::Zero();
      if (!camera.unproject(Eigen::Vector2d(u, v), bearing)) continue;
      Eigen::Vector3f bearing_f = Eigen::Vector3f::Zero();
      REQUIRE(camera_f.unproject(Eigen::Vector2f(u, v), bearing_f));
      CHECK((bearing_f.cast<double>() - bearing).norm() < 2e-6);  // ~2e-3 px at f = 460
      const Eigen::Vector3d p = 4.0 * bearing;
      Eigen::Vector2d uv = Eigen::Vector2d::Zero();
      Eigen::Vector2f uv_f = Eigen::Vector2f::Zero();
      REQUIRE(camera.project(p, uv));
      REQUIRE(camera_f.project(p.cast<float>(), uv_f));
      CHECK((uv_f.cast<double>() - uv).norm() < 2e-3);
      ++compared;
    }
  }
  CHECK(compared > 100);
}

}  // namespace

TEST_CASE("round trips over the whole image") {
  SUBCASE("pinhole") { CHECK(checkGridRoundTrip(PinholeCamera<double>(eurocPinhole()), kEurocSize) == 1.0); }
  SUBCASE("radtan EuRoC") { CHECK(checkGridRoundTrip(PinholeRadtan8Camera<double>(eurocRadtan()), kEurocSize) == 1.0); }
  SUBCASE("radtan8 rational") {
    CHECK(checkGridRoundTrip(PinholeRadtan8Camera<double>(syntheticRational()), kEurocSize) == 1.0);
  }
  SUBCASE("ds EuRoC") { CHECK(checkGridRoundTrip(DoubleSphereCamera<double>(eurocDs()), kEurocSize) == 1.0); }
  SUBCASE("ds TUM-VI") { CHECK(checkGridRoundTrip(DoubleSphereCamera<double>(tumviDs()), kTumvi512Size) == 1.0); }
  SUBCASE("eucm EuRoC") { CHECK(checkGridRoundTrip(ExtendedUnifiedCamera<double>(eurocEucm()), kEurocSize) == 1.0); }
  SUBCASE("kb4 T265") { CHECK(checkGridRoundTrip(KannalaBrandt4Camera<double>(t265Kb4()), kT265Size) == 1.0); }
}

TEST_CASE("bearing -> pixel -> bearing round trips") {
  checkBearingRoundTrip(PinholeCamera<double>(eurocPinhole()), 1.3);
  checkBearingRoundTrip(PinholeRadtan8Camera<double>(eurocRadtan()), 0.9);
  checkBearingRoundTrip(DoubleSphereCamera<double>(eurocDs()), 2.0);  // valid to acos(-w2) = 2.25 rad
  checkBearingRoundTrip(DoubleSphereCamera<double>(tumviDs()), 2.0);
  checkBearingRoundTrip(ExtendedUnifiedCamera<double>(eurocEucm()), 2.0);
  checkBearingRoundTrip(KannalaBrandt4Camera<double>(t265Kb4()), 2.5);
}

TEST_CASE("analytic Jacobians match central differences") {
  SUBCASE("pinhole") { checkJacobians(PinholeCamera<double>(eurocPinhole()), kEurocSize); }
  SUBCASE("radtan EuRoC") { checkJacobians(PinholeRadtan8Camera<double>(eurocRadtan()), kEurocSize); }
  SUBCASE("radtan8 rational") { checkJacobians(PinholeRadtan8Camera<double>(syntheticRational()), kEurocSize); }
  SUBCASE("ds EuRoC") { checkJacobians(DoubleSphereCamera<double>(eurocDs()), kEurocSize); }
  SUBCASE("ds TUM-VI") { checkJacobians(DoubleSphereCamera<double>(tumviDs()), kTumvi512Size); }
  SUBCASE("eucm EuRoC") { checkJacobians(ExtendedUnifiedCamera<double>(eurocEucm()), kEurocSize); }
  SUBCASE("kb4 T265") { checkJacobians(KannalaBrandt4Camera<double>(t265Kb4()), kT265Size); }
  SUBCASE("kb4 on the optical axis") {
    // The axis uses a first-order branch; its Jacobians must agree with the general formula nearby.
    const KannalaBrandt4Camera<double> camera(t265Kb4());
    const Eigen::Vector3d p(0, 0, 2);
    Eigen::Vector2d uv = Eigen::Vector2d::Zero();
    Eigen::Matrix<double, 2, 3> d_uv_d_p;
    REQUIRE(camera.project(p, uv, &d_uv_d_p));
    const auto projectPoint = [&](const Eigen::Vector3d& q) {
      Eigen::Vector2d r = Eigen::Vector2d::Zero();
      REQUIRE(camera.project(q, r));
      return r;
    };
    CHECK(relativeError(d_uv_d_p, numericalJacobian<2, 3>(projectPoint, p, Eigen::Vector3d::Constant(1e-6))) < 1e-6);
    Eigen::Vector3d bearing = Eigen::Vector3d::Zero();
    Eigen::Matrix<double, 3, 2> d_bearing_d_uv;
    REQUIRE(camera.unproject(uv, bearing, &d_bearing_d_uv));
    CHECK((bearing - Eigen::Vector3d::UnitZ()).norm() < 1e-15);
    const auto unproject = [&](const Eigen::Vector2d& q) {
      Eigen::Vector3d b = Eigen::Vector3d::Zero();
      REQUIRE(camera.unproject(q, b));
      return b;
    };
    CHECK(relativeError(d_bearing_d_uv, numericalJacobian<3, 2>(unproject, uv, Eigen::Vector2d::Constant(1e-3))) <
          1e-6);
  }
}

TEST_CASE("float agrees with double") {
  checkFloatMatchesDouble(PinholeCamera<double>(eurocPinhole()), kEurocSize);
  checkFloatMatchesDouble(PinholeRadtan8Camera<double>(eurocRadtan()), kEurocSize);
  checkFloatMatchesDouble(PinholeRadtan8Camera<double>(syntheticRational()), kEurocSize);
  checkFloatMatchesDouble(DoubleSphereCamera<double>(eurocDs()), kEurocSize);
  checkFloatMatchesDouble(DoubleSphereCamera<double>(tumviDs()), kTumvi512Size);
  checkFloatMatchesDouble(ExtendedUnifiedCamera<double>(eurocEucm()), kEurocSize);
  checkFloatMatchesDouble(KannalaBrandt4Camera<double>(t265Kb4()), kT265Size);
}

TEST_CASE("points behind the camera or outside the field of view are rejected") {
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();
  Eigen::Vector3d bearing = Eigen::Vector3d::Zero();
  const Eigen::Vector3d behind(0.1, -0.2, -1.0);
  CHECK_FALSE(PinholeCamera<double>(eurocPinhole()).project(behind, uv));
  CHECK_FALSE(PinholeCamera<double>(eurocPinhole()).project(Eigen::Vector3d(1, 1, 0), uv));
  CHECK_FALSE(PinholeRadtan8Camera<double>(eurocRadtan()).project(behind, uv));
  CHECK_FALSE(DoubleSphereCamera<double>(eurocDs()).project(behind, uv));
  CHECK_FALSE(ExtendedUnifiedCamera<double>(eurocEucm()).project(behind, uv));
  // The camera centre itself has no direction.
  CHECK_FALSE(PinholeCamera<double>(eurocPinhole()).project(Eigen::Vector3d::Zero(), uv));
  CHECK_FALSE(PinholeRadtan8Camera<double>(eurocRadtan()).project(Eigen::Vector3d::Zero(), uv));
  CHECK_FALSE(KannalaBrandt4Camera<double>(t265Kb4()).project(Eigen::Vector3d::Zero(), uv));
  CHECK_FALSE(DoubleSphereCamera<double>(eurocDs()).project(Eigen::Vector3d::Zero(), uv));
  CHECK_FALSE(ExtendedUnifiedCamera<double>(eurocEucm()).project(Eigen::Vector3d::Zero(), uv));

  SUBCASE("radtan stops where r * radial(r) stops increasing") {
    // k1 = -0.5 only: d/dr [r (1 - r^2/2)] = 1 - 1.5 r^2 vanishes at r = sqrt(2/3).
    Eigen::Matrix<double, 12, 1> p = eurocRadtan();
    p.tail<8>().setZero();
    p[4] = -0.5;
    const PinholeRadtan8Camera<double> camera(p);
    CHECK(camera.maxRadius() == doctest::Approx(std::sqrt(2.0 / 3.0)).epsilon(1e-12));
    CHECK(camera.project(Eigen::Vector3d(0.8, 0.0, 1.0), uv));
    CHECK_FALSE(camera.project(Eigen::Vector3d(0.0, 0.83, 1.0), uv));
    CHECK_FALSE(camera.project(Eigen::Vector3d(3.0, 2.0, 1.0), uv));  // would fold back into the image
    // The largest distorted radius is sqrt(2/3) * (1 - 1/3) = 0.5443; beyond it there is no solution.
    CHECK(camera.unproject(Eigen::Vector2d(p[2] + 0.54 * p[0], p[3]), bearing));
    CHECK_FALSE(camera.unproject(Eigen::Vector2d(p[2] + 0.56 * p[0], p[3]), bearing));
    // The realistic EuRoC coefficients stay monotonic over the searched range.
    CHECK(PinholeRadtan8Camera<double>(eurocRadtan()).maxRadius() == PinholeRadtan8Camera<double>::kMaxSearchedRadius);
  }

  SUBCASE("kb4 stops where d(theta) stops increasing, also behind the camera") {
    // k1 = -0.1 only: d'(theta) = 1 - 0.3 theta^2 vanishes at theta = sqrt(1/0.3) = 1.8257 rad (105 deg).
    Eigen::Matrix<double, 8, 1> p = t265Kb4();
    p.tail<4>() << -0.1, 0, 0, 0;
    const KannalaBrandt4Camera<double> camera(p);
    const double limit = std::sqrt(1.0 / 0.3);
    CHECK(camera.maxTheta() == doctest::Approx(limit).epsilon(1e-12));
    for (const double delta : {-0.01, 0.01}) {
      const double theta = limit + delta;
      const Eigen::Vector3d point(std::sin(theta), 0.0, std::cos(theta));  // z < 0: behind the camera
      CHECK(camera.project(point, uv) == (delta < 0));
    }
    const double d_max = limit - 0.1 * limit * limit * limit;
    CHECK(camera.unproject(Eigen::Vector2d(p[2], p[3] + 0.999 * d_max * p[1]), bearing));
    CHECK_FALSE(camera.unproject(Eigen::Vector2d(p[2], p[3] + 1.001 * d_max * p[1]), bearing));
    // The T265 calibration is monotonic up to pi, so kb4 sees nearly all around; the exact back
    // direction has no defined pixel.
    const KannalaBrandt4Camera<double> t265(t265Kb4());
    CHECK(t265.maxTheta() == doctest::Approx(std::numbers::pi));
    CHECK(t265.project(Eigen::Vector3d(0.3, 0.1, -1.0), uv));
    CHECK_FALSE(t265.project(Eigen::Vector3d(0.0, 0.0, -1.0), uv));
  }

  SUBCASE("ds and eucm valid regions against the unprojection domains") {
    // eucm (alpha > 0.5) stops being injective exactly where z = -w d, and that edge projects onto
    // r^2 = 1/(beta (2 alpha - 1)), the unprojection domain's edge: two conditions written
    // independently in project() and unproject(). For ds the paper's w2 bound is slightly
    // conservative (EuRoC cam0: 129.0 deg against a fold at 130.8 deg), so its edge lies just
    // inside r^2 = 1/(2 alpha - 1) and sits at the hand-computed acos(-w2).
    const DoubleSphereCamera<double> ds(eurocDs());
    const ExtendedUnifiedCamera<double> eucm(eurocEucm());
    const auto edge = [&](const auto& camera, double azimuth, double& r2) {
      // Bisect the largest projectable angle along one azimuth.
      const auto point = [&](double angle) {
        return Eigen::Vector3d(std::sin(angle) * std::cos(azimuth), std::sin(angle) * std::sin(azimuth),
                               std::cos(angle));
      };
      double inside = 0.0, outside = std::numbers::pi;
      Eigen::Vector2d q = Eigen::Vector2d::Zero();
      for (int i = 0; i < 60; ++i) {
        const double mid = 0.5 * (inside + outside);
        (camera.project(point(mid), q) ? inside : outside) = mid;
      }
      REQUIRE(camera.project(point(inside), q));
      const auto& params = camera.params();
      r2 = std::pow((q[0] - params[2]) / params[0], 2) + std::pow((q[1] - params[3]) / params[1], 2);
      return inside;
    };
    // w1 = (1 - alpha)/alpha, w2 = (w1 + xi)/sqrt(2 w1 xi + xi^2 + 1) for the EuRoC ds values.
    const double alpha = eurocDs()[5], xi = eurocDs()[4];
    const double w1 = (1.0 - alpha) / alpha;
    const double w2 = (w1 + xi) / std::sqrt(2.0 * w1 * xi + xi * xi + 1.0);
    for (const double azimuth : {0.0, 1.0, 2.5}) {
      double r2 = 0.0;
      CHECK(edge(ds, azimuth, r2) == doctest::Approx(std::acos(-w2)).epsilon(1e-12));
      CHECK(r2 < 1.0 / (2.0 * alpha - 1.0));
      CHECK(r2 > 0.99 / (2.0 * alpha - 1.0));
      const double eucm_edge = edge(eucm, azimuth, r2);
      CHECK(eucm_edge > std::numbers::pi / 2);  // sees behind the camera
      // 1e-6: r^2 is stationary at the fold, so the bisected angle error enters only squared.
      CHECK(r2 == doctest::Approx(1.0 / (eurocEucm()[5] * (2.0 * eurocEucm()[4] - 1.0))).epsilon(1e-6));
    }
    // Pixels beyond those radii have no bearing.
    const auto ds_params = eurocDs();
    const double ds_r = std::sqrt(1.0 / (2.0 * ds_params[5] - 1.0));
    CHECK(ds.unproject(Eigen::Vector2d(ds_params[2] + 0.99 * ds_r * ds_params[0], ds_params[3]), bearing));
    CHECK_FALSE(ds.unproject(Eigen::Vector2d(ds_params[2] + 1.01 * ds_r * ds_params[0], ds_params[3]), bearing));
    const auto eucm_params = eurocEucm();
    const double eucm_r = std::sqrt(1.0 / (eucm_params[5] * (2.0 * eucm_params[4] - 1.0)));
    CHECK(eucm.unproject(Eigen::Vector2d(eucm_params[2], eucm_params[3] + 0.99 * eucm_r * eucm_params[1]), bearing));
    CHECK_FALSE(
        eucm.unproject(Eigen::Vector2d(eucm_params[2], eucm_params[3] + 1.01 * eucm_r * eucm_params[1]), bearing));
  }
}

TEST_CASE("hand-derived projections") {
  // Tolerances: these are a handful of exact floating-point operations, so 1e-9 px is rounding.
  const Eigen::Vector4d f(400.0, 300.0, 320.0, 240.0);
  const Eigen::Vector3d p(1.0, 2.0, 4.0);
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();

  // Pinhole: (400 * 1/4 + 320, 300 * 2/4 + 240).
  REQUIRE(PinholeCamera<double>(f).project(p, uv));
  CHECK(uv[0] == 420.0);
  CHECK(uv[1] == 390.0);
  Eigen::Vector3d bearing = Eigen::Vector3d::Zero();
  REQUIRE(PinholeCamera<double>(f).unproject(uv, bearing));
  CHECK((bearing - p / std::sqrt(21.0)).norm() < 1e-15);

  Eigen::Matrix<double, 6, 1> ds_params, eucm_params;
  // ds with xi = 0, alpha = 0 and eucm with alpha = 0 are the pinhole.
  ds_params << f, 0.0, 0.0;
  eucm_params << f, 0.0, 1.0;
  REQUIRE(DoubleSphereCamera<double>(ds_params).project(p, uv));
  CHECK((uv - Eigen::Vector2d(420.0, 390.0)).norm() < 1e-9);
  REQUIRE(ExtendedUnifiedCamera<double>(eucm_params).project(p, uv));
  CHECK((uv - Eigen::Vector2d(420.0, 390.0)).norm() < 1e-9);
  // Both are then limited to z > 0 like the pinhole.
  CHECK_FALSE(DoubleSphereCamera<double>(ds_params).project(Eigen::Vector3d(1, 0, -0.01), uv));
  CHECK_FALSE(ExtendedUnifiedCamera<double>(eucm_params).project(Eigen::Vector3d(1, 0, -0.01), uv));

  // ds with xi = 0, alpha = 0.5 and eucm with alpha = 0.5, beta = 1 are both the unified model with
  // xi = 1: (1, 0, 1) -> x / (0.5 |p| + 0.5 z) = 2 / (sqrt(2) + 1) = 2 (sqrt(2) - 1).
  ds_params << f, 0.0, 0.5;
  eucm_params << f, 0.5, 1.0;
  const double expected_u = 320.0 + 400.0 * 2.0 * (std::sqrt(2.0) - 1.0);
  REQUIRE(DoubleSphereCamera<double>(ds_params).project(Eigen::Vector3d(1, 0, 1), uv));
  CHECK(uv[0] == doctest::Approx(expected_u).epsilon(1e-14));
  CHECK(uv[1] == 240.0);
  REQUIRE(ExtendedUnifiedCamera<double>(eucm_params).project(Eigen::Vector3d(1, 0, 1), uv));
  CHECK(uv[0] == doctest::Approx(expected_u).epsilon(1e-14));
  // ds with xi = 1, alpha = 0: x / (|p| + z) = 1 / (sqrt(2) + 1).
  ds_params << f, 1.0, 0.0;
  REQUIRE(DoubleSphereCamera<double>(ds_params).project(Eigen::Vector3d(1, 0, 1), uv));
  CHECK(uv[0] == doctest::Approx(320.0 + 400.0 * (std::sqrt(2.0) - 1.0)).epsilon(1e-14));

  // kb4 with k = 0 is the equidistant fisheye r = f theta, also behind the camera.
  Eigen::Matrix<double, 8, 1> kb_params;
  kb_params << f, 0.0, 0.0, 0.0, 0.0;
  const KannalaBrandt4Camera<double> equidistant(kb_params);
  REQUIRE(equidistant.project(Eigen::Vector3d(2, 0, 2), uv));
  CHECK(uv[0] == doctest::Approx(320.0 + 400.0 * std::numbers::pi / 4).epsilon(1e-14));
  CHECK(uv[1] == 240.0);
  REQUIRE(equidistant.project(Eigen::Vector3d(0, 1, -1), uv));
  CHECK(uv[0] == 320.0);
  CHECK(uv[1] == doctest::Approx(240.0 + 300.0 * 3 * std::numbers::pi / 4).epsilon(1e-14));

  // radtan at x' = 0.1, y' = 0.2 (r^2 = 0.05), k1 = -0.3, k2 = 0.1, p1 = 0.001, p2 = -0.002:
  // radial = 1 - 0.015 + 0.00025 = 0.98525,
  // x'' = 0.098525 + 2 * 0.001 * 0.02 - 0.002 * (0.05 + 0.02) = 0.098425,
  // y'' = 0.19705 + 2 * (-0.002) * 0.02 + 0.001 * (0.05 + 0.08) = 0.1971.
  Eigen::Matrix<double, 12, 1> rt_params;
  rt_params << f, -0.3, 0.1, 0.001, -0.002, 0.0, 0.0, 0.0, 0.0;
  REQUIRE(PinholeRadtan8Camera<double>(rt_params).project(Eigen::Vector3d(0.2, 0.4, 2.0), uv));
  CHECK(uv[0] == doctest::Approx(320.0 + 400.0 * 0.098425).epsilon(1e-14));
  CHECK(uv[1] == doctest::Approx(240.0 + 300.0 * 0.1971).epsilon(1e-14));
  // The rational denominator: k4 = 1 divides the radial factor by 1 + r^2 = 1.05.
  rt_params << f, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0;
  REQUIRE(PinholeRadtan8Camera<double>(rt_params).project(Eigen::Vector3d(0.2, 0.4, 2.0), uv));
  CHECK(uv[0] == doctest::Approx(320.0 + 400.0 * 0.1 / 1.05).epsilon(1e-14));
}

TEST_CASE("atan2NonNegative agrees with std::atan2 to a few units in the last place over [0, pi]") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(0.0, std::numbers::pi);
  std::uniform_real_distribution<double> log_scale(-6.0, 6.0);
  double worst_ulps = 0.0;
  for (int trial = 0; trial < 200000; ++trial) {
    const double a = angle(rng), scale = std::pow(10.0, log_scale(rng));
    const double y = std::abs(scale * std::sin(a)), x = scale * std::cos(a);
    const double expected = std::atan2(y, x);
    const double got = voca::camera_detail::atan2NonNegative(y, x);
    const double ulp = std::nextafter(expected, 4.0) - expected;
    worst_ulps = std::max(worst_ulps, std::abs(got - expected) / ulp);
  }
  // Cephes' rational is good to about 1e-16 relative on its reduced range; the reductions by pi/4,
  // pi/2 and pi - angle add at most a rounding each, so 4 units in the last place bound it.
  CHECK(worst_ulps <= 4.0);
  // The axes, the branch boundaries of the reduction and the origin.
  for (const auto& [y, x] : {std::pair{0.0, 1.0},
                             {1.0, 0.0},
                             {0.0, -1.0},
                             {1.0, -0.0},
                             {0.66, 1.0},
                             {2.41421356237309504880, 1.0},
                             {1.0, 1.0},
                             {0.0, 0.0}}) {
    CHECK(std::abs(voca::camera_detail::atan2NonNegative(y, x) - std::atan2(y, x)) <=
          4e-16 * std::max(1.0, std::atan2(y, x)));
  }
}

TEST_CASE("kb4's two-lane projection gives project()'s values bit for bit, lane by lane") {
  // WindowOptimizer's residual passes project two points per register (projectPair); every
  // decision and trajectory depends on those values being project()'s own. Points of every kind:
  // ordinary ones in front, near and on the axis (project()'s pinhole branch), behind the camera,
  // beyond the largest angle, and not finite; paired in every combination by drawing both lanes.
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> kind(0, 7);
  const auto draw = [&]() -> Eigen::Vector3d {
    switch (kind(rng)) {
      case 0:
        return {1e-10 * u(rng), 1e-10 * u(rng), 0.5 + u(rng)};  // within the axis test
      case 1:
        return {0.0, 0.0, u(rng)};
      case 2:
        return {u(rng), u(rng), -2.0 - u(rng)};  // far behind: beyond the largest angle
      case 3:
        return {std::numeric_limits<double>::quiet_NaN(), u(rng), 1.0};
      case 4:
        return {u(rng), u(rng), 0.0};
      default:
        return {u(rng), u(rng), u(rng)};
    }
  };
  for (const bool fast : {true, false}) {
    KannalaBrandt4Camera<double> camera(t265Kb4());
    camera.setFastAngle(fast);
    int both = 0;
    for (int trial = 0; trial < 20000; ++trial) {
      const std::array<Eigen::Vector3d, 2> p{draw(), draw()};
      const bool jacobians = trial % 2 == 0;
      std::array<Eigen::Vector2d, 2> uv_pair, uv_one;
      std::array<Eigen::Matrix<double, 2, 3>, 2> J_pair, J_one;
      for (std::size_t i = 0; i < 2; ++i) {
        uv_pair[i].setConstant(7.0);
        J_pair[i].setConstant(7.0);
      }
      const unsigned projected =
          camera.projectPair({&p[0], &p[1]}, {&uv_pair[0], &uv_pair[1]},
                             {jacobians ? &J_pair[0] : nullptr, jacobians ? &J_pair[1] : nullptr});
      for (std::size_t i = 0; i < 2; ++i) {
        const bool ok = camera.project(p[i], uv_one[i], jacobians ? &J_one[i] : nullptr);
        REQUIRE(((projected >> i) & 1u) == static_cast<unsigned>(ok));
        if (!ok) {
          // Nothing is written for a point that does not project.
          CHECK((uv_pair[i].array() == 7.0).all());
          continue;
        }
        // Bit for bit (memcmp also tells -0 from +0).
        CHECK(std::memcmp(uv_pair[i].data(), uv_one[i].data(), sizeof(double) * 2) == 0);
        if (jacobians) CHECK(std::memcmp(J_pair[i].data(), J_one[i].data(), sizeof(double) * 6) == 0);
        if (!jacobians) CHECK((J_pair[i].array() == 7.0).all());
      }
      both += projected == 3u;
    }
    CHECK(both > 5000);
  }
  // Models without a two-lane projection take project() twice through GenericCamera.
  const voca::GenericCamera<double> pinhole =
      voca::GenericCamera<double>::fromParams("pinhole", std::vector<double>{400.0, 300.0, 320.0, 240.0});
  const std::array<Eigen::Vector3d, 2> p{Eigen::Vector3d(0.1, -0.2, 1.0), Eigen::Vector3d(0.3, 0.1, -1.0)};
  std::array<Eigen::Vector2d, 2> uv;
  std::array<Eigen::Matrix<double, 2, 3>, 2> J;
  REQUIRE(pinhole.projectPair({&p[0], &p[1]}, {&uv[0], &uv[1]}, {&J[0], &J[1]}) == 1u);
  Eigen::Vector2d uv_one;
  Eigen::Matrix<double, 2, 3> J_one;
  REQUIRE(pinhole.project(p[0], uv_one, &J_one));
  CHECK(uv[0] == uv_one);
  CHECK(J[0] == J_one);
}

TEST_CASE("kb4 with the fast angle projects as with std::atan2") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  KannalaBrandt4Camera<double> exact(t265Kb4()), fast(t265Kb4());
  fast.setFastAngle(true);
  int projected = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    Eigen::Vector2d uv_exact, uv_fast;
    Eigen::Matrix<double, 2, 3> J_exact, J_fast;
    const bool ok = exact.project(p, uv_exact, &J_exact);
    REQUIRE(fast.project(p, uv_fast, &J_fast) == ok);
    if (!ok) continue;
    ++projected;
    // A few ulps in theta move the pixel by ~1e-13 px at these focal lengths.
    CHECK((uv_fast - uv_exact).norm() <= 1e-10);
    CHECK((J_fast - J_exact).norm() <= 1e-9 * std::max(1.0, J_exact.norm()));
  }
  CHECK(projected > 10000);
}
