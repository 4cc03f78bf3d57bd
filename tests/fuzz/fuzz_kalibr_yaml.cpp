// Kalibr camchain YAML (camN: camera_model, distortion_model, intrinsics, T_cam_imu, ...).
#include "formats/calib/calibration_io.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = voca::fuzz::writeInput("camchain.yaml", data, size);
  voca::fuzz::expectOnlyInputErrors([&] { voca::loadCalibration(path); });
  return 0;
}
