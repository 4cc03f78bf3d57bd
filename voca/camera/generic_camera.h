#pragma once
// GenericCamera: one of the camera models chosen at run time from a calibration file.
// The models, one header each, have analytic Jacobians, take their parameters in the order and
// under the names of Basalt's calibration files, and are templated on the scalar: the frontend
// projects in float, the backend in double.

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "voca/camera/camera_math.h"
#include "voca/camera/double_sphere_camera.h"
#include "voca/camera/eucm_camera.h"
#include "voca/camera/kb4_camera.h"
#include "voca/camera/pinhole_camera.h"
#include "voca/camera/radtan8_camera.h"
#include "voca/core/error.h"

namespace voca {

// A camera of any supported model (Basalt names "pinhole", "pinhole-radtan8", "kb4", "ds",
// "eucm"), dispatched through std::variant so hot loops can also visit() the concrete model.
template <typename Scalar>
class GenericCamera {
 public:
  using Variant = std::variant<PinholeCamera<Scalar>, PinholeRadtan8Camera<Scalar>, KannalaBrandt4Camera<Scalar>,
                               DoubleSphereCamera<Scalar>, ExtendedUnifiedCamera<Scalar>>;
  using Vec2 = Eigen::Matrix<Scalar, 2, 1>;
  using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
  using Mat23 = Eigen::Matrix<Scalar, 2, 3>;
  using Mat32 = Eigen::Matrix<Scalar, 3, 2>;

  // Model names in the order of the variant, for messages and help texts.
  static constexpr std::array<std::string_view, 5> kModelNames{
      PinholeCamera<Scalar>::kName, PinholeRadtan8Camera<Scalar>::kName, KannalaBrandt4Camera<Scalar>::kName,
      DoubleSphereCamera<Scalar>::kName, ExtendedUnifiedCamera<Scalar>::kName};

  // A unit pinhole (fx = fy = 1, cx = cy = 0), so that structures holding a camera can be
  // default-constructed before a calibration is loaded into them.
  GenericCamera() : camera_(PinholeCamera<Scalar>(typename PinholeCamera<Scalar>::Params(1, 1, 0, 0))) {}

  // Implicit from any concrete model.
  template <typename Model>
  requires std::is_constructible_v<Variant, Model> GenericCamera(Model model) : camera_(std::move(model)) {}

  // Builds a camera from a Basalt model name and its parameters in Basalt order. Throws
  // voca::InputError naming the model and the problem: unknown model, wrong number of
  // parameters, a non-finite value, a non-positive focal length, or alpha/beta out of range.
  static GenericCamera fromParams(std::string_view model_name, std::span<const double> params) {
    std::optional<GenericCamera> camera;
    tryModel<PinholeCamera<Scalar>>(model_name, params, camera);
    tryModel<PinholeRadtan8Camera<Scalar>>(model_name, params, camera);
    tryModel<KannalaBrandt4Camera<Scalar>>(model_name, params, camera);
    tryModel<DoubleSphereCamera<Scalar>>(model_name, params, camera);
    tryModel<ExtendedUnifiedCamera<Scalar>>(model_name, params, camera);
    if (!camera) {
      std::ostringstream message;
      message << "unknown camera model '" << model_name << "' (supported: ";
      for (size_t i = 0; i < kModelNames.size(); ++i) message << (i ? ", " : "") << kModelNames[i];
      message << ")";
      throw InputError(message.str());
    }
    return *camera;
  }

  std::string_view modelName() const {
    return visit([](const auto& model) { return std::string_view(std::decay_t<decltype(model)>::kName); });
  }
  // Parameter names in the order of params() (Basalt's JSON keys).
  std::span<const char* const> paramNames() const {
    return visit(
        [](const auto& model) { return std::span<const char* const>(std::decay_t<decltype(model)>::kParamNames); });
  }
  std::vector<double> params() const {
    return visit([](const auto& model) {
      const auto p = model.params().template cast<double>().eval();
      return std::vector<double>(p.data(), p.data() + p.size());
    });
  }

  bool project(const Vec3& p_cam, Vec2& uv, Mat23* d_uv_d_p = nullptr) const {
    return visit([&](const auto& model) { return model.project(p_cam, uv, d_uv_d_p); });
  }
  bool unproject(const Vec2& uv, Vec3& bearing, Mat32* d_bearing_d_uv = nullptr) const {
    return visit([&](const auto& model) { return model.unproject(uv, bearing, d_bearing_d_uv); });
  }
  // Two points as project() projects them (the same values); models with a two-lane projection
  // (kb4 in double) take both in one register. Bit i set when point i projects; d_uv_d_p[i] is
  // written when d_uv_d_p[0] is set (then both must be).
  unsigned projectPair(const std::array<const Vec3*, 2>& p_cam, const std::array<Vec2*, 2>& uv,
                       const std::array<Mat23*, 2>& d_uv_d_p) const {
    return visit([&](const auto& model) -> unsigned {
      if constexpr (requires { model.projectPair(p_cam, uv, d_uv_d_p); }) {
        return model.projectPair(p_cam, uv, d_uv_d_p);
      } else {
        return camera_detail::projectEach(model, p_cam, uv, d_uv_d_p);
      }
    });
  }

  // Lets the models that have a faster angle computation use it (see KannalaBrandt4Camera::setFastAngle).
  void setFastAngle(bool fast) {
    std::visit(
        [fast](auto& model) {
          if constexpr (requires { model.setFastAngle(fast); }) model.setFastAngle(fast);
        },
        camera_);
  }

  template <class F>
  decltype(auto) visit(F&& f) const {
    return std::visit(std::forward<F>(f), camera_);
  }
  const Variant& variant() const { return camera_; }

  template <class Other>
  GenericCamera<Other> cast() const {
    return visit([](const auto& model) { return GenericCamera<Other>(model.template cast<Other>()); });
  }

 private:
  template <typename Model>
  static void tryModel(std::string_view model_name, std::span<const double> params,
                       std::optional<GenericCamera>& camera) {
    if (model_name != Model::kName) return;
    const auto fail = [&](const std::string& what) {
      std::ostringstream message;
      message << "camera model '" << Model::kName << "': " << what;
      throw InputError(message.str());
    };
    if (params.size() != static_cast<size_t>(Model::kNumParams)) {
      std::ostringstream what;
      what << "expected " << Model::kNumParams << " parameters (";
      for (int i = 0; i < Model::kNumParams; ++i) what << (i ? " " : "") << Model::kParamNames[i];
      what << "), got " << params.size();
      fail(what.str());
    }
    for (int i = 0; i < Model::kNumParams; ++i) {
      if (!std::isfinite(params[i])) fail(std::string("parameter ") + Model::kParamNames[i] + " is not finite");
    }
    for (int i = 0; i < 2; ++i) {
      if (!(params[i] > 0.0)) {
        std::ostringstream what;
        what << "focal length " << Model::kParamNames[i] << " = " << params[i] << " must be positive";
        fail(what.str());
      }
    }
    const std::string_view name = Model::kName;
    if (name == "ds" || name == "eucm") {
      // alpha blends two denominators; outside [0, 1] the model and its valid region are undefined.
      const double alpha = params[name == "ds" ? 5 : 4];
      if (!(alpha >= 0.0 && alpha <= 1.0)) {
        std::ostringstream what;
        what << "alpha = " << alpha << " must be in [0, 1]";
        fail(what.str());
      }
    }
    if (name == "eucm" && !(params[5] > 0.0)) {
      std::ostringstream what;
      what << "beta = " << params[5] << " must be positive";
      fail(what.str());
    }
    typename Model::Params p;
    for (int i = 0; i < Model::kNumParams; ++i) p[i] = static_cast<Scalar>(params[i]);
    camera.emplace(Model(p));
  }

  Variant camera_;
};

using GenericCameraf = GenericCamera<float>;
using GenericCamerad = GenericCamera<double>;

// Maps a Kalibr camchain entry (camera_model, distortion_model, intrinsics [fu fv pu pv],
// distortion_coeffs) to a camera: pinhole+radtan -> pinhole-radtan8 with k3..k6 = 0,
// pinhole+equidistant -> kb4, pinhole+none -> pinhole. Throws voca::InputError otherwise.
inline GenericCamera<double> cameraFromKalibr(std::string_view camera_model, std::string_view distortion_model,
                                              std::span<const double> intrinsics, std::span<const double> distortion) {
  const auto fail = [&](const std::string& what) {
    std::ostringstream message;
    message << "Kalibr camera_model '" << camera_model << "' with distortion_model '" << distortion_model
            << "': " << what;
    throw InputError(message.str());
  };
  if (camera_model != "pinhole") {
    fail("unsupported camera_model (supported: pinhole with distortion_model radtan, equidistant or none)");
  }
  if (intrinsics.size() != 4) {
    fail("intrinsics must have 4 values (fu fv pu pv), got " + std::to_string(intrinsics.size()));
  }
  std::vector<double> params(intrinsics.begin(), intrinsics.end());
  const auto expectCoefficients = [&](size_t count, const char* names) {
    if (distortion.size() != count) {
      fail("distortion_coeffs must have " + std::to_string(count) + " values (" + names + "), got " +
           std::to_string(distortion.size()));
    }
  };
  if (distortion_model == "radtan") {
    expectCoefficients(4, "k1 k2 r1 r2");
    params.insert(params.end(), distortion.begin(), distortion.end());
    params.insert(params.end(), 4, 0.0);  // k3..k6: Kalibr's radtan has no higher radial terms
    return GenericCamera<double>::fromParams(PinholeRadtan8Camera<double>::kName, params);
  }
  if (distortion_model == "equidistant") {
    expectCoefficients(4, "k1 k2 k3 k4");
    params.insert(params.end(), distortion.begin(), distortion.end());
    return GenericCamera<double>::fromParams(KannalaBrandt4Camera<double>::kName, params);
  }
  if (distortion_model == "none") {
    if (!distortion.empty() && !std::all_of(distortion.begin(), distortion.end(), [](double c) { return c == 0.0; })) {
      fail("distortion_coeffs must be empty or zero");
    }
    return GenericCamera<double>::fromParams(PinholeCamera<double>::kName, params);
  }
  fail("unsupported distortion_model (supported: radtan, equidistant, none)");
  return {};
}

}  // namespace voca
