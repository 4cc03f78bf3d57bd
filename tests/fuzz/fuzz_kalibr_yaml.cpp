// Kalibr camchain YAML (camN: camera_model, distortion_model, intrinsics, T_cam_imu, ...).
#include "tests/fuzz/fuzz_support.h"
#include "voca/calib/calibration.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = voca::fuzz::writeInput("camchain.yaml", data, size);
  voca::fuzz::expectOnlyInputErrors([&] { voca::loadCalibration(path); });
  return 0;
}
