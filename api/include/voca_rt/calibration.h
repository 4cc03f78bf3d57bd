#pragma once
// A calibrated stereo rig as a value: what a calibration file holds, for programs that know their
// cameras without one (a headset runtime with factory calibration) and to inspect a loaded file.

#include <array>
#include <string>
#include <vector>

#include "voca_rt/export.h"

namespace voca_rt {

struct CameraModel {
  // The projection model and its parameters in Basalt's names and order:
  //   "pinhole"          fx fy cx cy
  //   "pinhole-radtan8"  fx fy cx cy k1 k2 p1 p2 k3 k4 k5 k6   (Kalibr's radtan: k3..k6 zero)
  //   "kb4"              fx fy cx cy k1 k2 k3 k4               (Kalibr's equidistant)
  //   "ds"               fx fy cx cy xi alpha                  (double sphere)
  //   "eucm"             fx fy cx cy alpha beta                (extended unified)
  std::string type;
  std::vector<double> intrinsics;
  int width = 0, height = 0;  // the image size the intrinsics belong to
  // The camera's pose in the rig's body frame (maps camera points into the body frame), row-major 4x4.
  // Estimated poses are of the body frame, so they compare with ground truth given in it.
  std::array<double, 16> T_body_cam{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
};

struct Calibration {
  std::vector<CameraModel> cameras;  // cam0 (left, the reference), cam1 (right)

  // Reads a Basalt calibration JSON, a Kalibr camchain YAML, a EuRoC sensor.yaml (or its mav0
  // folder) or a KITTI calib.txt. Throws voca_rt::Error naming the file and field.
  VOCA_RT_API static Calibration load(const std::string& path);
};

}  // namespace voca_rt
