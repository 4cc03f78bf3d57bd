// EuRoC mav0/camN/sensor.yaml (T_BS, intrinsics, distortion, resolution). The input holds cam0's
// file, then a "--8<--" line and cam1's (or one file used for both).
#include "formats/calib/calibration_io.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto [cam0, cam1] = voca::fuzz::splitInput({reinterpret_cast<const char*>(data), size});
  voca::fuzz::writeInput("mav0/cam0/sensor.yaml", cam0);
  voca::fuzz::writeInput("mav0/cam1/sensor.yaml", cam1);
  voca::fuzz::expectOnlyInputErrors([&] { voca::loadCalibration(voca::fuzz::scratchDir() / "mav0"); });
  return 0;
}
