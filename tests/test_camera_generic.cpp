// GenericCamera: run-time model selection, dispatch, casts, and the errors for bad parameters.

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "voca/camera/generic_camera.h"

namespace {

using voca::GenericCamera;
using voca::InputError;

// EuRoC cam0 (Kalibr pinhole + radtan).
const std::vector<double> kEurocIntrinsics{458.654, 457.296, 367.215, 248.375};
const std::vector<double> kEurocRadtan{-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};

std::string errorOf(std::string_view model, const std::vector<double>& params) {
  try {
    GenericCamera<double>::fromParams(model, params);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::string kalibrErrorOf(std::string_view camera_model, std::string_view distortion_model,
                          const std::vector<double>& intrinsics, const std::vector<double>& distortion) {
  try {
    voca::cameraFromKalibr(camera_model, distortion_model, intrinsics, distortion);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

}  // namespace

TEST_CASE("fromParams builds every model and dispatches to it") {
  const std::vector<std::pair<std::string, std::vector<double>>> cases{
      {"pinhole", {458.654, 457.296, 367.215, 248.375}},
      {"pinhole-radtan8", {458.654, 457.296, 367.215, 248.375, -0.28, 0.07, 2e-4, 2e-5, 0.01, 0.02, 0.003, 0.001}},
      {"kb4", {286.6, 286.5, 422.3, 395.2, -0.0068, 0.045, -0.0435, 0.0084}},
      {"ds", {349.756, 348.725, 365.894, 249.330, -0.241, 0.567}},
      {"eucm", {460.765, 459.405, 365.894, 249.335, 0.590, 1.127}},
  };
  for (const auto& model_case : cases) {
    const std::string& name = model_case.first;
    const auto& params = model_case.second;
    CAPTURE(name);
    const auto camera = GenericCamera<double>::fromParams(name, params);
    CHECK(camera.modelName() == name);
    CHECK(camera.params() == params);
    CHECK(camera.paramNames().size() == params.size());
    CHECK(std::string(camera.paramNames()[0]) == "fx");

    // The generic path gives exactly what the concrete model gives.
    const Eigen::Vector3d p(0.3, -0.2, 1.5);
    Eigen::Vector2d uv = Eigen::Vector2d::Zero(), uv_model = Eigen::Vector2d::Zero();
    Eigen::Matrix<double, 2, 3> d_uv_d_p, d_uv_d_p_model;
    REQUIRE(camera.project(p, uv, &d_uv_d_p));
    camera.visit([&](const auto& model) { REQUIRE(model.project(p, uv_model, &d_uv_d_p_model)); });
    CHECK(uv == uv_model);
    CHECK(d_uv_d_p == d_uv_d_p_model);
    Eigen::Vector3d bearing = Eigen::Vector3d::Zero();
    Eigen::Matrix<double, 3, 2> d_bearing_d_uv;
    REQUIRE(camera.unproject(uv, bearing, &d_bearing_d_uv));
    CHECK((bearing - p.normalized()).norm() < 1e-12);  // round trip to rounding

    // A float copy keeps the model and (to float precision) the parameters and projections.
    const GenericCamera<float> camera_f = camera.cast<float>();
    CHECK(camera_f.modelName() == name);
    for (size_t i = 0; i < params.size(); ++i) CHECK(camera_f.params()[i] == static_cast<float>(params[i]));
    Eigen::Vector2f uv_f = Eigen::Vector2f::Zero();
    REQUIRE(camera_f.project(p.cast<float>(), uv_f));
    CHECK((uv_f.cast<double>() - uv).norm() < 2e-3);  // float ulp at 500 px is 3e-5; a few dozen operations
  }
}

TEST_CASE("fromParams also builds float cameras") {
  const auto camera =
      GenericCamera<float>::fromParams("eucm", std::vector<double>{460.8, 459.4, 365.9, 249.3, 0.59, 1.13});
  CHECK(camera.modelName() == "eucm");
  Eigen::Vector2f uv = Eigen::Vector2f::Zero();
  REQUIRE(camera.project(Eigen::Vector3f(0.f, 0.f, 2.f), uv));
  CHECK(uv[0] == doctest::Approx(365.9f));  // the optical axis lands on the principal point
  CHECK_THROWS_AS(GenericCamera<float>::fromParams("eucm", std::vector<double>{1, 2}), InputError);
}

TEST_CASE("the default camera is a unit pinhole") {
  const GenericCamera<double> camera;
  CHECK(camera.modelName() == "pinhole");
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();
  REQUIRE(camera.project(Eigen::Vector3d(1, 2, 4), uv));
  CHECK(uv == Eigen::Vector2d(0.25, 0.5));
}

TEST_CASE("fromParams rejects bad models and parameters with a clear message") {
  const std::string unknown = errorOf("fisheye", {1, 2, 3, 4});
  CHECK(contains(unknown, "'fisheye'"));
  for (const char* name : {"pinhole", "pinhole-radtan8", "kb4", "ds", "eucm"}) CHECK(contains(unknown, name));

  const std::string count = errorOf("ds", {350, 350, 360, 240, 0.5});
  CHECK(contains(count, "'ds'"));
  CHECK(contains(count, "expected 6 parameters (fx fy cx cy xi alpha), got 5"));

  const std::string nan = errorOf("kb4", {286, 286, 422, 395, std::numeric_limits<double>::quiet_NaN(), 0, 0, 0});
  CHECK(contains(nan, "'kb4'"));
  CHECK(contains(nan, "k1 is not finite"));
  CHECK(contains(errorOf("pinhole", {400, std::numeric_limits<double>::infinity(), 320, 240}), "fy is not finite"));

  const std::string focal = errorOf("pinhole", {-400, 400, 320, 240});
  CHECK(contains(focal, "'pinhole'"));
  CHECK(contains(focal, "focal length fx = -400 must be positive"));
  CHECK(contains(errorOf("eucm", {400, 0, 320, 240, 0.5, 1}), "focal length fy = 0 must be positive"));

  CHECK(contains(errorOf("ds", {350, 350, 360, 240, -0.2, 1.5}), "alpha = 1.5 must be in [0, 1]"));
  CHECK(contains(errorOf("eucm", {350, 350, 360, 240, -0.1, 1.0}), "alpha = -0.1 must be in [0, 1]"));
  CHECK(contains(errorOf("eucm", {350, 350, 360, 240, 0.6, 0.0}), "beta = 0 must be positive"));
}

TEST_CASE("Kalibr camera and distortion models map to our models") {
  const auto radtan = voca::cameraFromKalibr("pinhole", "radtan", kEurocIntrinsics, kEurocRadtan);
  CHECK(radtan.modelName() == "pinhole-radtan8");
  const std::vector<double> expected{458.654,    457.296,        367.215, 248.375, -0.28340811, 0.07395907,
                                     0.00019359, 1.76187114e-05, 0,       0,       0,           0};
  CHECK(radtan.params() == expected);

  const std::vector<double> equidistant_coeffs{-0.0068, 0.045, -0.0435, 0.0084};
  const auto kb4 = voca::cameraFromKalibr("pinhole", "equidistant", kEurocIntrinsics, equidistant_coeffs);
  CHECK(kb4.modelName() == "kb4");
  CHECK(kb4.params()[4] == -0.0068);
  CHECK(kb4.params()[7] == 0.0084);

  const auto pinhole = voca::cameraFromKalibr("pinhole", "none", kEurocIntrinsics, {});
  CHECK(pinhole.modelName() == "pinhole");
  CHECK(pinhole.params() == kEurocIntrinsics);

  CHECK(contains(kalibrErrorOf("omni", "radtan", kEurocIntrinsics, kEurocRadtan), "camera_model 'omni'"));
  CHECK(contains(kalibrErrorOf("pinhole", "fov", kEurocIntrinsics, {0.9}), "unsupported distortion_model"));
  CHECK(contains(kalibrErrorOf("pinhole", "fov", kEurocIntrinsics, {0.9}), "'fov'"));
  CHECK(contains(kalibrErrorOf("pinhole", "radtan", kEurocIntrinsics, {0.1, 0.2}),
                 "distortion_coeffs must have 4 values (k1 k2 r1 r2), got 2"));
  CHECK(contains(kalibrErrorOf("pinhole", "radtan", {458.0, 457.0, 367.0}, kEurocRadtan),
                 "intrinsics must have 4 values (fu fv pu pv), got 3"));
  CHECK(contains(kalibrErrorOf("pinhole", "none", kEurocIntrinsics, {0.1, 0, 0, 0}), "must be empty or zero"));
  CHECK(contains(kalibrErrorOf("pinhole", "equidistant", {-458.0, 457.0, 367.0, 248.0}, equidistant_coeffs),
                 "focal length fx"));
}
