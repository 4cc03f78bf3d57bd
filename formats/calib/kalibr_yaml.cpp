// Kalibr camchain YAML and EuRoC camN/sensor.yaml (both Kalibr's camera conventions).

#include <fmt/core.h>
#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "formats/calib/calibration_io.h"
#include "formats/calib/internal.h"
#include "voca/core/error.h"

namespace voca {
namespace fs = std::filesystem;

namespace {

// A YAML node with its dotted path, so every error names the file, the field and the line.
class YamlField {
 public:
  YamlField(YAML::Node node, std::string path, const std::string& file)
      : node_(std::move(node)), path_(std::move(path)), file_(file) {}

  [[noreturn]] void fail(const std::string& what) const {
    std::string where = path_.empty() ? file_ : file_ + ": " + path_;
    if (node_.IsDefined() && node_.Mark().line >= 0) where += " (line " + std::to_string(node_.Mark().line + 1) + ")";
    throw InputError(where + ": " + what);
  }

  bool has(const std::string& key) const { return node_.IsMap() && node_[key].IsDefined(); }
  YamlField operator[](const std::string& key) const {
    if (!node_.IsMap()) fail("expected a map of fields, got " + describe());
    const YAML::Node child = node_[key];
    const std::string path = path_.empty() ? key : path_ + "." + key;
    if (!child.IsDefined()) {
      std::string where = file_ + ": " + path + ": missing";
      if (node_.Mark().line >= 0)
        where += " (in the map starting at line " + std::to_string(node_.Mark().line + 1) + ")";
      throw InputError(where);
    }
    return YamlField(child, path, file_);
  }
  // Parsed with std::from_chars: yaml-cpp's as<double> goes through a stringstream, which follows
  // the global C++ locale (a decimal comma would misread "0.5").
  double number() const {
    if (node_.IsScalar()) {
      std::string_view text = node_.Scalar();
      if (!text.empty() && text.front() == '+') text.remove_prefix(1);
      double value = 0.0;
      const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
      if (!text.empty() && ec == std::errc() && end == text.data() + text.size() && std::isfinite(value)) return value;
    }
    fail("expected a number, got " + describe());
  }
  std::string string() const {
    if (!node_.IsScalar()) fail("expected a string, got " + describe());
    return node_.Scalar();
  }
  // A list of numbers; count < 0 accepts any length.
  std::vector<double> numbers(int count = -1) const {
    if (!node_.IsSequence() || (count >= 0 && node_.size() != static_cast<size_t>(count))) {
      fail("expected a list of " + (count >= 0 ? std::to_string(count) + " " : std::string()) + "numbers, got " +
           describe());
    }
    std::vector<double> values;
    for (size_t i = 0; i < node_.size(); ++i) {
      values.push_back(YamlField(node_[i], path_ + "[" + std::to_string(i) + "]", file_).number());
    }
    return values;
  }
  // A 4x4 homogeneous matrix given as 4 rows of 4 numbers.
  Eigen::Matrix4d matrix4() const {
    if (!node_.IsSequence() || node_.size() != 4) fail("expected 4 rows of 4 numbers, got " + describe());
    Eigen::Matrix4d m;
    for (int r = 0; r < 4; ++r) {
      const std::vector<double> row = YamlField(node_[r], path_ + "[" + std::to_string(r) + "]", file_).numbers(4);
      for (int c = 0; c < 4; ++c) m(r, c) = row[static_cast<size_t>(c)];
    }
    return m;
  }
  SE3d rigid(const Eigen::Matrix4d& m) const {
    const std::string problem = calib_internal::rigidTransformProblem(m);
    if (!problem.empty()) fail(problem);
    return calib_internal::toSE3(m);
  }
  std::pair<int, int> resolution() const {
    const std::vector<double> size = numbers(2);
    for (double v : size) {
      if (!(v >= 1.0 && v <= calib_internal::kMaxImageSide && v == static_cast<int>(v))) {
        fail(fmt::format("expected [width, height] in whole pixels, 1 to {}", calib_internal::kMaxImageSide));
      }
    }
    return {static_cast<int>(size[0]), static_cast<int>(size[1])};
  }
  const std::string& path() const { return path_; }

 private:
  std::string describe() const {
    if (node_.IsScalar()) return "'" + node_.Scalar() + "'";
    if (node_.IsSequence()) return "a list of " + std::to_string(node_.size());
    if (node_.IsMap()) return "a map";
    return "nothing";
  }

  YAML::Node node_;
  std::string path_;
  const std::string& file_;
};

YAML::Node loadYaml(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open calibration");
  try {
    return YAML::Load(in);
  } catch (const YAML::Exception& e) {
    throw InputError(path.string() + ":" + std::to_string(e.mark.line + 1) + ": malformed YAML: " + e.msg);
  }
}

// Kalibr models beyond pinhole: ds and eucm store their two shape parameters first.
GenericCamera<double> kalibrCamera(const YamlField& cam) {
  const std::string model = cam["camera_model"].string();
  const std::string distortion = cam.has("distortion_model") ? cam["distortion_model"].string() : "none";
  const std::vector<double> intrinsics = cam["intrinsics"].numbers();
  const std::vector<double> coefficients =
      cam.has("distortion_coeffs") ? cam["distortion_coeffs"].numbers() : std::vector<double>();
  try {
    if ((model == "ds" || model == "eucm") && distortion == "none" && intrinsics.size() == 6) {
      const std::vector<double> params = {intrinsics[2], intrinsics[3], intrinsics[4],
                                          intrinsics[5], intrinsics[0], intrinsics[1]};
      return GenericCamera<double>::fromParams(model, params);
    }
    return cameraFromKalibr(model, distortion, intrinsics, coefficients);
  } catch (const InputError& e) {
    cam.fail(e.what());
  }
}

}  // namespace

StereoRig loadKalibrCalibration(const fs::path& camchain_yaml) {
  const std::string file = camchain_yaml.string();
  const YamlField root(loadYaml(camchain_yaml), "", file);
  StereoRig rig;
  rig.source = file;
  // cam0 decides the body frame: the IMU when it has IMU extrinsics, else cam0 itself.
  const bool imu_body = root["cam0"].has("T_cam_imu") || root["cam0"].has("T_imu_cam");
  rig.body_frame = imu_body ? "imu" : "cam0";
  for (int index = 0; root.has("cam" + std::to_string(index)); ++index) {
    const YamlField cam = root["cam" + std::to_string(index)];
    const GenericCamera<double> camera = kalibrCamera(cam);
    const auto [width, height] = cam["resolution"].resolution();
    SE3d T_body_cam;
    if (imu_body && cam.has("T_cam_imu")) {
      const YamlField t = cam["T_cam_imu"];
      T_body_cam = t.rigid(t.matrix4()).inverse();
    } else if (imu_body && cam.has("T_imu_cam")) {
      const YamlField t = cam["T_imu_cam"];
      T_body_cam = t.rigid(t.matrix4());
    } else if (index > 0) {
      if (!cam.has("T_cn_cnm1")) {
        cam["T_cn_cnm1"].fail(imu_body ? "missing (needed when T_cam_imu is absent)" : "missing");
      }
      const YamlField t = cam["T_cn_cnm1"];
      const SE3d T_cn_cnm1 = t.rigid(t.matrix4());
      T_body_cam = rig.cameras.back().T_body_cam * T_cn_cnm1.inverse();
    }
    rig.cameras.push_back({camera, width, height, T_body_cam});
  }
  if (rig.cameras.size() < calib_internal::kMinCameras) {
    root["cam1"].fail("missing (a stereo rig needs cam0 and cam1)");
  }
  return rig;
}

StereoRig loadEurocSensorCalibration(const fs::path& mav0_folder) {
  StereoRig rig;
  rig.source = mav0_folder.string();
  rig.body_frame = "euroc-body";
  for (int index = 0;; ++index) {
    const fs::path sensor = mav0_folder / ("cam" + std::to_string(index)) / "sensor.yaml";
    if (!fs::is_regular_file(sensor)) {
      if (index < calib_internal::kMinCameras) {
        throw InputError(sensor.string() + ": missing (a EuRoC stereo rig needs cam0 and cam1 sensor.yaml)");
      }
      break;
    }
    const std::string file = sensor.string();
    const YamlField root(loadYaml(sensor), "", file);
    const YamlField t_bs = root["T_BS"];
    if (t_bs.has("rows") && t_bs["rows"].number() != 4) t_bs["rows"].fail("expected 4");
    if (t_bs.has("cols") && t_bs["cols"].number() != 4) t_bs["cols"].fail("expected 4");
    const YamlField data = t_bs["data"];
    const std::vector<double> values = data.numbers(16);
    const Eigen::Matrix4d m = Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(values.data());
    const SE3d T_body_cam = data.rigid(m);
    const auto [width, height] = root["resolution"].resolution();
    // EuRoC spells Kalibr's "radtan" as "radial-tangential".
    std::string distortion = root["distortion_model"].string();
    if (distortion == "radial-tangential") distortion = "radtan";
    const std::string model = root["camera_model"].string();
    const std::vector<double> intrinsics = root["intrinsics"].numbers();
    const std::vector<double> coefficients = root["distortion_coefficients"].numbers();
    try {
      rig.cameras.push_back({cameraFromKalibr(model, distortion, intrinsics, coefficients), width, height, T_body_cam});
    } catch (const InputError& e) {
      throw InputError(file + ": " + e.what());
    }
  }
  return rig;
}

}  // namespace voca
