// Shipped configurations compiled into the library and selectable by name.

#include <doctest/doctest.h>

#include <filesystem>
#include <string>

#include "formats/config/builtin_configs.h"
#include "formats/config/config.h"
#include "tests/test_support.h"

namespace fs = std::filesystem;

TEST_CASE("config: every shipped file is compiled in and names the same values as the file") {
  const fs::path configs = fs::path(VOCA_SOURCE_DIR) / "configs";
  int files = 0;
  for (const auto& entry : fs::directory_iterator(configs)) {
    const std::string stem = entry.path().stem().string();
    if (entry.path().extension() != ".json" || !stem.ends_with("_vo")) continue;
    ++files;
    const std::string name = stem.substr(0, stem.size() - 3);
    CAPTURE(name);
    const voca::VocaConfig by_name = voca::loadConfig(name);
    const voca::VocaConfig from_file = voca::loadConfig(entry.path());
    CHECK(by_name.frontend.matching_default_depth_m == from_file.frontend.matching_default_depth_m);
    CHECK(by_name.frontend.matching_guess == from_file.frontend.matching_guess);
    CHECK(by_name.frontend.grid_size_px == from_file.frontend.grid_size_px);
    CHECK(by_name.frontend.image_safe_radius_px == from_file.frontend.image_safe_radius_px);
    CHECK(by_name.backend.max_keyframes == from_file.backend.max_keyframes);
    CHECK(by_name.backend.use_lm == from_file.backend.use_lm);
  }
  CHECK(files == static_cast<int>(voca::builtinConfigs().size()));
  CHECK(files >= 3);
}

TEST_CASE("config: the KITTI setting guesses stereo matches for street depths") {
  // 2 m on KITTI's 0.54 m baseline and 707 px focal length is ~190 px of disparity, beyond what
  // the pyramid bridges; the KITTI config starts at 15 m (~25 px) and then follows the backend.
  const voca::VocaConfig kitti = voca::builtinConfig("kitti");
  CHECK(kitti.frontend.matching_default_depth_m == doctest::Approx(15.0));
  CHECK(kitti.frontend.matching_guess == voca::StereoGuess::kAverageDepth);
  CHECK(voca::builtinConfig("euroc").frontend.matching_default_depth_m == doctest::Approx(2.0));
}

TEST_CASE("config: an unknown name lists the shipped ones; a path that does not exist stays a file error") {
  const std::string unknown = voca::test::inputErrorOf([] { voca::loadConfig("eruoc"); });
  CHECK(unknown.find("unknown built-in config 'eruoc'") != std::string::npos);
  CHECK(unknown.find("euroc") != std::string::npos);
  CHECK(unknown.find("kitti") != std::string::npos);
  const std::string missing = voca::test::inputErrorOf([] { voca::loadConfig("no/such/config.json"); });
  CHECK(missing.find("no/such/config.json: cannot open") != std::string::npos);
}
