// Basalt calibration JSON (value0.T_imu_cam, intrinsics, resolution).
#include "formats/calib/calibration_io.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = voca::fuzz::writeInput("calib.json", data, size);
  voca::fuzz::expectOnlyInputErrors([&] { voca::loadCalibration(path); });
  return 0;
}
