// The configuration JSON (frontend and backend sections, every key validated).
#include "formats/config/config.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = voca::fuzz::writeInput("config.json", data, size);
  voca::fuzz::expectOnlyInputErrors([&] { voca::loadConfig(path); });
  return 0;
}
