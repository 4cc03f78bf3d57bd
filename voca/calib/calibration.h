#pragma once
// Stereo rig calibration: cameras with intrinsics, image sizes and poses in a common body frame.
// The types only; formats/calib/calibration_io.h reads and writes them as files.

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

  // Throws InputError naming the source unless the rig has the two cameras stereo needs.
  void requireStereo() const;
  // Pose of cam1 in cam0 (maps cam1 points into cam0). Requires two cameras.
  SE3d T_cam0_cam1() const;
  double baselineM() const { return T_cam0_cam1().translation().norm(); }
};

}  // namespace voca
