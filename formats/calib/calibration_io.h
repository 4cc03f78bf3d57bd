#pragma once
// Calibration files: Basalt JSON, Kalibr camchain YAML, EuRoC sensor.yaml folders and KITTI
// calib.txt read into a StereoRig, and the rig written back as Basalt JSON.

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "voca/calib/calibration.h"

namespace voca {

// Loads a calibration, choosing the reader by what `path` is:
//  *.json                  Basalt (value0.T_imu_cam, value0.intrinsics, value0.resolution)
//  *.yaml / *.yml          Kalibr camchain (camN: camera_model, distortion_model, intrinsics,
//                          distortion_coeffs, resolution, T_cam_imu | T_imu_cam | T_cn_cnm1);
//                          a file named sensor.yaml loads its EuRoC mav0 folder
//  *.txt                   KITTI calib.txt (P0, P1; image size from image_0/ beside it)
//  folder                  EuRoC mav0 (camN/sensor.yaml) or the folder containing it, a KITTI
//                          sequence folder (calib.txt), or a folder with a *calib*.json
// Throws InputError naming the file and the field, e.g. "calib.json: value0.intrinsics[1].intrinsics.fx: missing".
StereoRig loadCalibration(const std::filesystem::path& path);

// One camera as a program gives it (the library API's calibration value).
struct CameraValues {
  std::string model;           // Basalt name: pinhole, pinhole-radtan8, kb4, ds, eucm
  std::vector<double> params;  // in Basalt order
  int width = 0, height = 0;
  Eigen::Matrix4d T_body_cam = Eigen::Matrix4d::Identity();
};

// A rig from values, checked as the file readers check theirs (the model and its parameters, image
// sizes, rigid poses, two cameras, a baseline). Throws InputError naming `source` and the camera.
StereoRig stereoRigFromValues(const std::vector<CameraValues>& cameras, const std::string& source);

StereoRig loadBasaltCalibration(const std::filesystem::path& json_file);
StereoRig loadKalibrCalibration(const std::filesystem::path& camchain_yaml);
StereoRig loadEurocSensorCalibration(const std::filesystem::path& mav0_folder);
StereoRig loadKittiCalibration(const std::filesystem::path& calib_txt);

// Writes Basalt JSON (T_imu_cam = T_body_cam, intrinsics, resolution) that loadCalibration reads
// back to the same rig. Throws InputError when the file cannot be written.
void saveBasaltCalibration(const StereoRig& rig, const std::filesystem::path& json_file);

// A Basalt calibration placed in a folder: the first (by name) *.json whose name contains "calib";
// nullopt when there is none or the folder cannot be read.
std::optional<std::filesystem::path> findCalibrationJson(const std::filesystem::path& folder);

}  // namespace voca
