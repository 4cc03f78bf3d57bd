// EuRoC / TUM-VI mav0/camN/data.csv ("<timestamp ns>,<file name>") through openDataset. The input
// holds cam0's file, then a "--8<--" line and cam1's (or one file used for both).
#include "formats/dataset/dataset.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto [cam0, cam1] = voca::fuzz::splitInput({reinterpret_cast<const char*>(data), size});
  voca::fuzz::writeInput("mav0/cam0/data.csv", cam0);
  voca::fuzz::writeInput("mav0/cam1/data.csv", cam1);
  voca::fuzz::expectOnlyInputErrors([&] { voca::openDataset(voca::fuzz::scratchDir()); });
  return 0;
}
