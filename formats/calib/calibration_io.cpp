#include "formats/calib/calibration_io.h"

#include <fmt/format.h>
#include <Eigen/SVD>
#include <algorithm>
#include <optional>

#include "formats/calib/internal.h"
#include "voca/core/error.h"

namespace voca {
namespace fs = std::filesystem;

namespace calib_internal {

std::string rigidTransformProblem(const Eigen::Matrix4d& m) {
  // Files print matrices with 9-16 digits; 1e-3 accepts any of them and rejects wrong matrices.
  constexpr double kTolerance = 1e-3;
  if (!m.allFinite()) return "contains a non-finite value";
  if ((m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > kTolerance) {
    return "bottom row must be 0 0 0 1";
  }
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  if ((r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > kTolerance || r.determinant() < 0.0) {
    return "rotation block is not a rotation (orthonormal with determinant +1)";
  }
  return {};
}

SE3d toSE3(const Eigen::Matrix4d& m) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m.topLeftCorner<3, 3>(), Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d r = svd.matrixU() * svd.matrixV().transpose();
  return SE3d(SO3<double>(r), m.topRightCorner<3, 1>());
}

}  // namespace calib_internal

std::optional<fs::path> findCalibrationJson(const fs::path& folder) {
  std::vector<fs::path> found;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const fs::path& p = entry.path();
    if (entry.is_regular_file() && p.extension() == ".json" && p.filename().string().find("calib") != std::string::npos)
      found.push_back(p);
  }
  if (found.empty()) return std::nullopt;
  return *std::min_element(found.begin(), found.end());
}

namespace {

// Stereo triangulates along the baseline: a right camera at the left one's position (a copied pose,
// a translation given in the wrong unit) leaves every new point without depth, so every frame would
// be lost. Real rigs start at about a centimetre (phones); this only catches the mistake.
constexpr double kMinBaselineM = 1e-3;

StereoRig readCalibration(const fs::path& path) {
  if (!fs::exists(path)) throw InputError(path.string() + ": calibration not found");
  if (fs::is_directory(path)) {
    if (fs::is_regular_file(path / "mav0" / "cam0" / "sensor.yaml")) return loadEurocSensorCalibration(path / "mav0");
    if (fs::is_regular_file(path / "cam0" / "sensor.yaml")) return loadEurocSensorCalibration(path);
    if (fs::is_regular_file(path / "calib.txt")) return loadKittiCalibration(path / "calib.txt");
    if (const auto json = findCalibrationJson(path)) return loadBasaltCalibration(*json);
    throw InputError(path.string() +
                     ": no calibration found in this folder: looked for mav0/cam0/sensor.yaml, cam0/sensor.yaml "
                     "(EuRoC), calib.txt (KITTI) and *calib*.json (Basalt)");
  }
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (extension == ".json") return loadBasaltCalibration(path);
  if (extension == ".yaml" || extension == ".yml") {
    // A EuRoC camN/sensor.yaml describes one camera; the rig is the mav0 folder above it.
    if (path.filename() == "sensor.yaml")
      return loadEurocSensorCalibration(fs::absolute(path).parent_path().parent_path());
    return loadKalibrCalibration(path);
  }
  if (extension == ".txt") return loadKittiCalibration(path);
  throw InputError(path.string() +
                   ": unknown calibration format: expected a Basalt .json, a Kalibr camchain .yaml, a KITTI "
                   "calib.txt, or a dataset folder");
}

void requireBaseline(const StereoRig& rig) {
  const double baseline = rig.baselineM();
  if (!(baseline >= kMinBaselineM)) {
    throw InputError(fmt::format(
        "{}: cam1 is {:.3g} mm from cam0: a stereo rig needs a baseline of at least {:g} mm (are both camera "
        "poses the same, or is the translation in the wrong unit?)",
        rig.source, baseline * 1e3, kMinBaselineM * 1e3));
  }
}

}  // namespace

StereoRig loadCalibration(const fs::path& path) {
  StereoRig rig = readCalibration(path);
  requireBaseline(rig);
  return rig;
}

StereoRig stereoRigFromValues(const std::vector<CameraValues>& cameras, const std::string& source) {
  StereoRig rig;
  rig.source = source;
  rig.body_frame = "body";
  if (static_cast<int>(cameras.size()) < calib_internal::kMinCameras) {
    throw InputError(fmt::format("{}: a stereo rig needs at least {} cameras, got {}", source,
                                 calib_internal::kMinCameras, cameras.size()));
  }
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    const CameraValues& values = cameras[i];
    const std::string what = fmt::format("{}: cam{}", source, i);
    CameraCalibration camera;
    try {
      camera.camera = GenericCamera<double>::fromParams(values.model, values.params);
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: {}", what, e.what()));
    }
    if (values.width <= 0 || values.height <= 0 || values.width > calib_internal::kMaxImageSide ||
        values.height > calib_internal::kMaxImageSide) {
      throw InputError(fmt::format("{}: image size {}x{}: expected 1 to {} pixels a side", what, values.width,
                                   values.height, calib_internal::kMaxImageSide));
    }
    camera.width = values.width;
    camera.height = values.height;
    if (const std::string problem = calib_internal::rigidTransformProblem(values.T_body_cam); !problem.empty()) {
      throw InputError(fmt::format("{}: T_body_cam: {}", what, problem));
    }
    camera.T_body_cam = calib_internal::toSE3(values.T_body_cam);
    rig.cameras.push_back(camera);
  }
  requireBaseline(rig);
  return rig;
}

}  // namespace voca
