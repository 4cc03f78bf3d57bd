#pragma once
// Stereo rig calibration: cameras with intrinsics, image sizes and poses in a common body frame,
// read from Basalt JSON, Kalibr camchain YAML, EuRoC sensor.yaml folders or KITTI calib.txt.

#include <filesystem>
#include <string>
#include <vector>

#include "voca/camera/generic_camera.h"
#include "voca/geometry/se3.h"

namespace voca {

// One camera of a rig: its projection model, image size and pose in the rig's body frame.
struct CameraCalibration {
  GenericCamera<double> camera;
  int width = 0;
  int height = 0;
  SE3d T_body_cam;
};

// The cameras of a calibration file (at least two; cam0 is the left/reference camera). Poses are
// in the file's body frame, which `body_frame` names: "imu" for Basalt and Kalibr camchains with
// IMU extrinsics, "euroc-body" for EuRoC sensor.yaml (T_BS), "cam0" otherwise (KITTI, camera-only Kalibr).
struct StereoRig {
  std::vector<CameraCalibration> cameras;
  std::string source;      // the file or folder it was read from
  std::string body_frame;  // see above

  // Pose of cam1 in cam0 (maps cam1 points into cam0). Requires two cameras.
  SE3d T_cam0_cam1() const;
  double baselineM() const { return T_cam0_cam1().translation().norm(); }
};

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

}  // namespace voca
