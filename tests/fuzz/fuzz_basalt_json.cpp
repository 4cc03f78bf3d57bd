// Basalt calibration JSON (value0.T_imu_cam, intrinsics, resolution).
#include "tests/fuzz/fuzz_support.h"
#include "voca/calib/calibration.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = voca::fuzz::writeInput("calib.json", data, size);
  voca::fuzz::expectOnlyInputErrors([&] { voca::loadCalibration(path); });
  return 0;
}
