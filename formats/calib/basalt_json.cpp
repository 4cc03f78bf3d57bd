// Basalt's calibration JSON (cereal layout): value0.{T_imu_cam, intrinsics, resolution}.

#include <fmt/core.h>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "formats/calib/calibration_io.h"
#include "formats/calib/internal.h"
#include "voca/core/error.h"

namespace voca {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const char* typeName(const json& j) {
  switch (j.type()) {
    case json::value_t::null:
      return "null";
    case json::value_t::object:
      return "an object";
    case json::value_t::array:
      return "an array";
    case json::value_t::string:
      return "a string";
    case json::value_t::boolean:
      return "a boolean";
    case json::value_t::number_integer:
    case json::value_t::number_unsigned:
      return "an integer";
    case json::value_t::number_float:
      return "a number";
    default:
      return "an unsupported value";
  }
}

// A JSON value with its dotted path, so every error names the file and the field.
class JsonField {
 public:
  JsonField(const json& value, std::string path, const std::string& file)
      : value_(value), path_(std::move(path)), file_(file) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw InputError((path_.empty() ? file_ : file_ + ": " + path_) + ": " + what);
  }

  JsonField operator[](const char* key) const {
    if (!value_.is_object()) fail(std::string("expected an object, got ") + typeName(value_));
    const auto it = value_.find(key);
    const std::string path = path_.empty() ? key : path_ + "." + key;
    if (it == value_.end()) JsonField(value_, path, file_).fail("missing");
    return JsonField(*it, path, file_);
  }
  JsonField at(size_t index) const {
    if (index >= size()) fail("missing element " + std::to_string(index));
    return JsonField(value_[index], path_ + "[" + std::to_string(index) + "]", file_);
  }
  size_t size() const {
    if (!value_.is_array()) fail(std::string("expected an array, got ") + typeName(value_));
    return value_.size();
  }
  double number() const {
    if (!value_.is_number()) fail(std::string("expected a number, got ") + typeName(value_));
    return value_.get<double>();
  }
  // An image width or height in whole pixels.
  int imageSide() const {
    if (!value_.is_number_integer() || value_.get<int64_t>() <= 0 ||
        value_.get<int64_t>() > calib_internal::kMaxImageSide) {
      fail(fmt::format("expected an image size in pixels, 1 to {}, got {}", calib_internal::kMaxImageSide,
                       value_.is_number() ? value_.dump() : std::string(typeName(value_))));
    }
    return static_cast<int>(value_.get<int64_t>());
  }
  std::string string() const {
    if (!value_.is_string()) fail(std::string("expected a string, got ") + typeName(value_));
    return value_.get<std::string>();
  }
  const json& value() const { return value_; }
  const std::string& path() const { return path_; }

 private:
  const json& value_;
  std::string path_;
  const std::string& file_;
};

// The Basalt parameter names of a camera type, or empty for an unknown type.
std::span<const char* const> paramNamesOf(std::string_view type) {
  std::span<const char* const> names;
  const auto check = [&](auto tag) {
    using Model = typename decltype(tag)::type;
    if (type == Model::kName) names = std::span<const char* const>(Model::kParamNames);
  };
  check(std::type_identity<PinholeCamera<double>>());
  check(std::type_identity<PinholeRadtan8Camera<double>>());
  check(std::type_identity<KannalaBrandt4Camera<double>>());
  check(std::type_identity<DoubleSphereCamera<double>>());
  check(std::type_identity<ExtendedUnifiedCamera<double>>());
  return names;
}

GenericCamera<double> readCamera(const JsonField& entry) {
  const JsonField type_field = entry["camera_type"];
  const std::string type = type_field.string();
  const std::span<const char* const> names = paramNamesOf(type);
  if (names.empty()) {
    std::string supported;
    for (const std::string_view name : GenericCamera<double>::kModelNames) {
      if (!supported.empty()) supported += ", ";
      supported += name;
    }
    type_field.fail("unknown camera type '" + type + "' (supported: " + supported + ")");
  }
  const JsonField intrinsics = entry["intrinsics"];
  std::vector<double> params;
  for (const char* name : names) params.push_back(intrinsics[name].number());
  // Unknown keys are usually typos of a parameter that then silently took no effect.
  for (const auto& item : intrinsics.value().items()) {
    // A named reference, not a structured binding: lambdas capture bindings only from C++20 on
    // and Clang (clang-tidy, other compilers) rejects it.
    const std::string& key = item.key();
    const bool known = std::find_if(names.begin(), names.end(), [&](const char* n) { return key == n; }) != names.end();
    // Basalt may store radtan8's valid radius; our model derives it from the coefficients.
    if (!known && !(type == PinholeRadtan8Camera<double>::kName && key == "rpmax")) {
      std::string expected;
      for (const char* n : names) {
        if (!expected.empty()) expected += ' ';
        expected += n;
      }
      intrinsics[key.c_str()].fail("unknown parameter for camera type " + type + " (expected " + expected + ")");
    }
  }
  try {
    return GenericCamera<double>::fromParams(type, params);
  } catch (const InputError& e) {
    intrinsics.fail(e.what());
  }
}

SE3d readPose(const JsonField& pose) {
  Eigen::Vector3d p(pose["px"].number(), pose["py"].number(), pose["pz"].number());
  Eigen::Quaterniond q(pose["qw"].number(), pose["qx"].number(), pose["qy"].number(), pose["qz"].number());
  // Files store unit quaternions to ~16 digits; a norm off by more than 1e-3 is a wrong value, not rounding.
  if (!(std::abs(q.norm() - 1.0) < 1e-3)) {
    std::ostringstream what;
    what << "quaternion (qx qy qz qw) has norm " << q.norm() << ", expected 1";
    pose.fail(what.str());
  }
  if (!p.allFinite()) pose.fail("position is not finite");
  return SE3d(q, p);
}

}  // namespace

StereoRig loadBasaltCalibration(const fs::path& json_file) {
  const std::string file = json_file.string();
  std::ifstream in(json_file);
  if (!in) throw InputError(file + ": cannot open calibration");
  json root;
  try {
    root = json::parse(in);
  } catch (const json::exception& e) {
    throw InputError(file + ": malformed JSON: " + e.what());
  }
  const JsonField value0 = JsonField(root, "", file)["value0"];
  const JsonField poses = value0["T_imu_cam"];
  const JsonField intrinsics = value0["intrinsics"];
  const JsonField resolution = value0["resolution"];
  const size_t count = intrinsics.size();
  if (count < calib_internal::kMinCameras) {
    intrinsics.fail("a stereo rig needs at least 2 cameras, got " + std::to_string(count));
  }
  if (poses.size() != count) {
    poses.fail("has " + std::to_string(poses.size()) + " entries but value0.intrinsics has " + std::to_string(count));
  }
  if (resolution.size() != count) {
    resolution.fail("has " + std::to_string(resolution.size()) + " entries but value0.intrinsics has " +
                    std::to_string(count));
  }
  StereoRig rig;
  rig.source = file;
  rig.body_frame = "imu";
  for (size_t i = 0; i < count; ++i) {
    const JsonField size = resolution.at(i);
    if (size.size() != 2) size.fail("expected [width, height]");
    rig.cameras.push_back(
        {readCamera(intrinsics.at(i)), size.at(0).imageSide(), size.at(1).imageSide(), readPose(poses.at(i))});
  }
  return rig;
}

void saveBasaltCalibration(const StereoRig& rig, const fs::path& json_file) {
  json poses = json::array(), intrinsics = json::array(), resolution = json::array();
  for (const CameraCalibration& cam : rig.cameras) {
    const Eigen::Quaterniond& q = cam.T_body_cam.unitQuaternion();
    const Eigen::Vector3d& p = cam.T_body_cam.translation();
    poses.push_back(
        {{"px", p.x()}, {"py", p.y()}, {"pz", p.z()}, {"qx", q.x()}, {"qy", q.y()}, {"qz", q.z()}, {"qw", q.w()}});
    json params = json::object();
    const std::vector<double> values = cam.camera.params();
    const std::span<const char* const> names = cam.camera.paramNames();
    for (size_t k = 0; k < values.size(); ++k) params[names[k]] = values[k];
    intrinsics.push_back({{"camera_type", std::string(cam.camera.modelName())}, {"intrinsics", params}});
    resolution.push_back({cam.width, cam.height});
  }
  // nlohmann orders object keys alphabetically; Basalt reads by name, so the order does not matter.
  const json root = {{"value0", {{"T_imu_cam", poses}, {"intrinsics", intrinsics}, {"resolution", resolution}}}};
  std::ofstream out(json_file);
  if (!out) throw InputError(json_file.string() + ": cannot open for writing");
  // dump() prints doubles with 17 significant digits, so they read back bit-exactly.
  out << root.dump(4) << '\n';
  out.close();
  if (!out) throw InputError(json_file.string() + ": write failed");
}

}  // namespace voca
