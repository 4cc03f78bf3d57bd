#pragma once
// Calibration files: Basalt JSON, Kalibr camchain YAML, EuRoC sensor.yaml folders and KITTI
// calib.txt read into a StereoRig, and the rig written back as Basalt JSON.

#include <filesystem>
#include <optional>

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
