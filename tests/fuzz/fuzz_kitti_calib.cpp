// KITTI calib.txt (P0..P3 projection rows); the image size comes from image_0/ beside it.
#include "formats/calib/calibration_io.h"
#include "formats/image/png_io.h"
#include "tests/fuzz/fuzz_support.h"
#include "voca/core/image.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const voca::GrayImage image(37, 13);  // a KITTI-like odd size; the pixels are not read
  std::filesystem::create_directories(voca::fuzz::scratchDir() / "seq" / "image_0");
  voca::writePngGray(voca::fuzz::scratchDir() / "seq" / "image_0" / "000000.png", image.view());
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = voca::fuzz::writeInput("seq/calib.txt", data, size);
  voca::fuzz::expectOnlyInputErrors([&] { voca::loadCalibration(path); });
  return 0;
}
