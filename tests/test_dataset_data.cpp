// Dataset readers on the real excerpts in ../shared/data (skipped when it is absent).

#include <string>

#include "formats/dataset/dataset.h"
#include "formats/image/png_io.h"
#include "tests/test_support.h"

TEST_CASE("EuRoC V1_01 micro: 95 stereo frames, the 4 cam1 rows without images warned") {
  const auto root = voca::test::sharedData("euroc_v101_micro");
  if (!root) return;
  for (const auto& path : {*root, *root / "mav0"}) {
    const voca::Dataset dataset = voca::openDataset(path);
    CHECK(dataset.layout == voca::DatasetLayout::kEuroc);
    // SOURCE.txt: 95 PNG pairs with identical names; cam1/data.csv lists 99 rows.
    REQUIRE(dataset.frames.size() == 95);
    CHECK(dataset.frames.front().t_ns == 1403715273262142976);
    CHECK(dataset.frames.back().t_ns == 1403715277962142976);
    REQUIRE(dataset.warnings.size() == 1);
    CHECK(dataset.warnings[0].find("cam1/data.csv: 4 of 99 rows have no image file") != std::string::npos);
    CHECK(dataset.warnings[0].find("data/1403715278012143104.png") != std::string::npos);
    // The ground-truth csv is not part of the excerpt (SOURCE.txt), so none is reported.
    CHECK_FALSE(dataset.ground_truth.has_value());
    REQUIRE(dataset.calibration.has_value());
    CHECK(dataset.calibration->filename() == "mav0");
    for (const auto& frame : dataset.frames) CHECK(frame.left.filename() == frame.right.filename());
  }
  const voca::GrayImage image = voca::readPngGray(voca::openDataset(*root).frames[10].right);
  CHECK(image.width() == 752);
  CHECK(image.height() == 480);
}

TEST_CASE("KITTI 06 first 51 frames with ground truth") {
  const auto root = voca::test::sharedData("kitti06_first51/sequences/06");
  if (!root) return;
  const voca::Dataset dataset = voca::openDataset(*root);
  CHECK(dataset.layout == voca::DatasetLayout::kKitti);
  REQUIRE(dataset.frames.size() == 51);
  CHECK(dataset.warnings.empty());
  CHECK(dataset.frames[50].t_ns == 5000000000);  // times.txt is nominal 10 Hz
  REQUIRE(dataset.ground_truth.has_value());
  CHECK(std::filesystem::equivalent(*dataset.ground_truth, *root / "../../poses/06.txt"));
  REQUIRE(dataset.calibration.has_value());
  CHECK(dataset.calibration->filename() == "calib.txt");
  const voca::GrayImage image = voca::readPngGray(dataset.frames[0].left);
  CHECK(image.width() == 1226);
  CHECK(image.height() == 370);
}
