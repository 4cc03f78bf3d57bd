// Dataset readers on synthetic folders written to scratch space, and the EuRoC writer.

#include <array>
#include <fstream>
#include <optional>
#include <string>

#include <fmt/core.h>

#include "formats/dataset/dataset.h"
#include "formats/image/png_io.h"
#include "tests/test_support.h"
#include "voca/core/error.h"

namespace {

namespace fs = std::filesystem;
using voca::Dataset;
using voca::DatasetLayout;

using voca::test::expectError;
using voca::test::writeText;

std::string errorOf(const fs::path& path) {
  return voca::test::inputErrorOf([&] { voca::openDataset(path); });
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

voca::GrayImage pattern(int seed) {
  voca::GrayImage image(16, 12);
  for (int y = 0; y < 12; ++y) {
    for (int x = 0; x < 16; ++x) image(x, y) = static_cast<std::uint8_t>(seed * 31 + x * 3 + y * 5);
  }
  return image;
}

// Writes frames t = 1000, 2000, ... with images distinguishable per camera and frame.
void writeEuroc(const fs::path& root, int frames) {
  voca::EurocWriter writer(root);
  for (int i = 0; i < frames; ++i) {
    const voca::GrayImage left = pattern(2 * i), right = pattern(2 * i + 1);
    const std::array<voca::GrayView, 2> views = {left.view(), right.view()};
    writer.addFrame(1000 * (i + 1), views);
  }
  writer.finish();
  CHECK(writer.frameCount() == frames);
}

}  // namespace

TEST_CASE("EurocWriter output is re-read by openDataset") {
  voca::test::ScratchDir dir("dataset-writer");
  writeEuroc(dir.path(), 5);
  for (const fs::path& root : {dir.path(), dir / "mav0"}) {
    const Dataset dataset = voca::openDataset(root);
    CHECK(dataset.layout == DatasetLayout::kEuroc);
    CHECK(dataset.warnings.empty());
    CHECK_FALSE(dataset.ground_truth.has_value());
    REQUIRE(dataset.frames.size() == 5);
    for (int i = 0; i < 5; ++i) {
      const voca::StereoFrameRef& frame = dataset.frames[static_cast<size_t>(i)];
      CHECK(frame.t_ns == 1000 * (i + 1));
      const voca::GrayImage left = voca::readPngGray(frame.left), right = voca::readPngGray(frame.right);
      CHECK(left(3, 4) == pattern(2 * i)(3, 4));
      CHECK(right(3, 4) == pattern(2 * i + 1)(3, 4));
    }
  }
  // A calibration is found beside the dataset: a Basalt json by name, else nothing (no sensor.yaml here).
  CHECK_FALSE(voca::openDataset(dir.path()).calibration.has_value());
  writeText(dir / "my_calib.json", "{}");
  REQUIRE(voca::openDataset(dir.path()).calibration.has_value());
  CHECK(voca::openDataset(dir.path()).calibration->filename() == "my_calib.json");
  CHECK(voca::openDataset(dir / "mav0").calibration->filename() == "my_calib.json");
}

TEST_CASE("EurocWriter over an earlier sequence replaces it: its images do not stay beside the new ones") {
  voca::test::ScratchDir dir("dataset-writer-over");
  writeEuroc(dir.path(), 5);
  writeText(dir / "mav0" / "cam0" / "data" / "notes.txt", "kept");  // not an image the writer owns
  writeEuroc(dir.path(), 2);
  for (const char* camera : {"cam0", "cam1"}) {
    int images = 0;
    for (const fs::directory_entry& entry : fs::directory_iterator(dir / "mav0" / camera / "data")) {
      images += entry.path().extension() == ".png" ? 1 : 0;
    }
    CHECK(images == 2);
  }
  CHECK(fs::exists(dir / "mav0" / "cam0" / "data" / "notes.txt"));
  CHECK(voca::openDataset(dir.path()).frames.size() == 2);
}

TEST_CASE("EurocWriter rejects wrong image counts and timestamps going back") {
  voca::test::ScratchDir dir("dataset-writer-bad");
  voca::EurocWriter writer(dir.path());
  const voca::GrayImage image = pattern(0);
  const std::array<voca::GrayView, 1> one = {image.view()};
  CHECK_THROWS_AS(writer.addFrame(10, one), voca::InputError);
  const std::array<voca::GrayView, 2> two = {image.view(), image.view()};
  writer.addFrame(10, two);
  CHECK_THROWS_AS(writer.addFrame(10, two), voca::InputError);
  CHECK(writer.frameCount() == 1);
}

TEST_CASE("EuRoC rows without images and unpaired timestamps are skipped with warnings") {
  voca::test::ScratchDir dir("dataset-missing");
  writeEuroc(dir.path(), 6);
  fs::remove(dir / "mav0/cam1/data/3000.png");
  fs::remove(dir / "mav0/cam0/data/5000.png");
  // A right row whose timestamp has no left partner.
  const voca::GrayImage image = pattern(9);
  voca::writePngGray(dir / "mav0/cam1/data/6500.png", image.view());
  std::ofstream(dir / "mav0/cam1/data.csv", std::ios::app) << "6500,6500.png\n";

  const Dataset dataset = voca::openDataset(dir.path());
  REQUIRE(dataset.frames.size() == 4);
  CHECK(dataset.frames[2].t_ns == 4000);
  CHECK(dataset.frames[3].t_ns == 6000);
  REQUIRE(dataset.warnings.size() == 4);
  CHECK(
      contains(dataset.warnings[0], "cam0/data.csv: 1 of 6 rows have no image file and were skipped (data/5000.png)"));
  CHECK(
      contains(dataset.warnings[1], "cam1/data.csv: 1 of 7 rows have no image file and were skipped (data/3000.png)"));
  expectError(dataset.warnings[2], "1 cam0 images have no cam1 image");
  // cam1's 5000 lost its partner (the left image is gone) and 6500 never had one.
  expectError(dataset.warnings[3],
              "2 cam1 images have no cam0 image with the same timestamp and were skipped (t_ns 5000, 6500)");
}

TEST_CASE("malformed EuRoC csv lines are errors naming file and line") {
  voca::test::ScratchDir dir("dataset-csv");
  writeEuroc(dir.path(), 3);
  const fs::path csv = dir / "mav0/cam0/data.csv";
  SUBCASE("not a number") {
    writeText(csv, "#timestamp [ns],filename\n1000,1000.png\nabc,2000.png\n");
    const std::string error = errorOf(dir.path());
    expectError(error, "cam0/data.csv:3: expected '<timestamp ns>,<image file name>', got 'abc,2000.png'");
  }
  SUBCASE("no file name") {
    writeText(csv, "#timestamp [ns],filename\n\n1000,1000.png\n2000\n");
    expectError(errorOf(dir.path()), "cam0/data.csv:4: expected");
  }
  SUBCASE("timestamps going back") {
    writeText(csv, "1000,1000.png\n3000,3000.png\n2000,2000.png\n");
    expectError(errorOf(dir.path()), "cam0/data.csv:3: timestamp 2000 is not after the previous row's 3000");
  }
  SUBCASE("cam1 csv missing") {
    fs::remove(dir / "mav0/cam1/data.csv");
    expectError(errorOf(dir.path()), "cam1/data.csv: missing");
  }
  SUBCASE("no image pairs at all") {
    fs::remove_all(dir / "mav0/cam1/data");
    expectError(errorOf(dir.path()), "no stereo frame");
  }
}

TEST_CASE("missing folders and unknown layouts are explained") {
  voca::test::ScratchDir dir("dataset-unknown");
  expectError(errorOf(dir / "nope"), "nope: dataset folder not found");
  writeText(dir / "file.txt", "x");
  expectError(errorOf(dir / "file.txt"), "not a folder");
  fs::create_directories(dir / "empty");
  const std::string error = errorOf(dir / "empty");
  expectError(error, "unknown dataset layout");
  expectError(error, "mav0/cam0/data.csv");
  expectError(error, "image_0/");
}

TEST_CASE("KITTI sequence folder with ground truth two levels up") {
  voca::test::ScratchDir dir("dataset-kitti");
  const fs::path seq = dir / "sequences" / "03";
  fs::create_directories(seq / "image_0");
  fs::create_directories(seq / "image_1");
  const voca::GrayImage image = pattern(1);
  for (int i = 0; i < 4; ++i) {
    char name[16];
    std::snprintf(name, sizeof(name), "%06d.png", i);
    voca::writePngGray(seq / "image_0" / name, image.view());
    if (i != 2) voca::writePngGray(seq / "image_1" / name, image.view());
  }
  writeText(seq / "times.txt", "0.000000e+00\n1.000000e-01\n2.0e-01\n0.3\n");
  writeText(seq / "calib.txt", "P0: 1 0 0 0 0 1 0 0 0 0 1 0\n");
  writeText(dir / "poses" / "03.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n");

  // Given with a trailing separator, the sequence name still comes out right.
  const Dataset dataset = voca::openDataset(seq.string() + "/");
  CHECK(dataset.layout == DatasetLayout::kKitti);
  REQUIRE(dataset.frames.size() == 3);
  CHECK(dataset.frames[0].t_ns == 0);
  CHECK(dataset.frames[1].t_ns == 100000000);
  CHECK(dataset.frames[2].t_ns == 300000000);
  CHECK(dataset.frames[2].left.filename() == "000003.png");
  CHECK(dataset.frames[2].right.parent_path().filename() == "image_1");
  REQUIRE(dataset.warnings.size() == 1);
  expectError(dataset.warnings[0], "1 of 4 frames lack an image and were skipped (image_1/000002.png)");
  REQUIRE(dataset.ground_truth.has_value());
  CHECK(fs::equivalent(*dataset.ground_truth, dir / "poses" / "03.txt"));
  REQUIRE(dataset.calibration.has_value());
  CHECK(dataset.calibration->filename() == "calib.txt");

  writeText(seq / "times.txt", "0.0\n0.1\nten\n");
  expectError(errorOf(seq), "times.txt:3: expected a time in seconds, got 'ten'");
  // Beyond int64 nanoseconds: refused rather than converted with undefined behaviour.
  writeText(seq / "times.txt", "0.0\n0.1\n1e300\n");
  expectError(errorOf(seq), "times.txt:3: expected a time in seconds, got '1e300'");
  fs::remove_all(seq / "image_1");
  expectError(errorOf(seq), "image_1: missing");
}

TEST_CASE("loadGroundTruth: a KITTI sequence's poses take its times.txt, a file given instead wins") {
  voca::test::ScratchDir dir("dataset-kitti-gt");
  const fs::path seq = dir / "sequences" / "00";
  for (const char* folder : {"image_0", "image_1"}) {
    fs::create_directories(seq / folder);
    for (int i = 0; i < 3; ++i) voca::writePngGray(seq / folder / fmt::format("{:06d}.png", i), pattern(1).view());
  }
  writeText(seq / "times.txt", "0.0\n0.5\n1.0\n");
  writeText(seq / "calib.txt", "P0: 1 0 0 0 0 1 0 0 0 0 1 0\n");
  writeText(dir / "poses" / "00.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n1 0 0 2 0 1 0 0 0 0 1 0\n");
  const Dataset dataset = voca::openDataset(seq);
  const std::optional<voca::Trajectory> own = voca::loadGroundTruth(dataset);
  REQUIRE(own.has_value());
  REQUIRE(own->poses.size() == 3);
  CHECK(own->poses[1].t_ns == 500000000);
  CHECK(own->poses[2].T_world_body.translation().x() == doctest::Approx(2.0));

  // A KITTI file given instead also takes the sequence's times; a TUM file keeps its own stamps.
  writeText(dir / "other.txt", "1 0 0 5 0 1 0 0 0 0 1 0\n1 0 0 6 0 1 0 0 0 0 1 0\n1 0 0 7 0 1 0 0 0 0 1 0\n");
  const std::optional<voca::Trajectory> kitti = voca::loadGroundTruth(dataset, dir / "other.txt");
  REQUIRE(kitti.has_value());
  CHECK(kitti->poses[2].t_ns == 1000000000);
  CHECK(kitti->poses[0].T_world_body.translation().x() == doctest::Approx(5.0));
  writeText(dir / "tum.txt", "2.0 0 0 0 0 0 0 1\n2.5 1 0 0 0 0 0 1\n");
  const std::optional<voca::Trajectory> tum = voca::loadGroundTruth(dataset, dir / "tum.txt");
  REQUIRE(tum.has_value());
  REQUIRE(tum->poses.size() == 2);
  CHECK(tum->poses[1].t_ns == 2500000000);

  fs::remove(dir / "poses" / "00.txt");
  CHECK_FALSE(voca::loadGroundTruth(voca::openDataset(seq)).has_value());
}

TEST_CASE("VOCA video layout lists videos and frame timestamps") {
  voca::test::ScratchDir dir("dataset-video");
  for (const char* cam : {"cam0", "cam1"}) {
    writeText(dir / "mav0" / cam / "data.mp4", "not decoded here");
    writeText(dir / "mav0" / cam / "data.csv", "#timestamp [ns],filename\n100,100.png\n200,200.png\n300,300.png\n");
  }
  const Dataset dataset = voca::openDataset(dir.path());
  CHECK(dataset.layout == DatasetLayout::kVocaVideo);
  CHECK(dataset.video_left == dir / "mav0/cam0/data.mp4");
  CHECK(dataset.video_right == dir / "mav0/cam1/data.mp4");
  REQUIRE(dataset.frames.size() == 3);
  CHECK(dataset.frames[1].t_ns == 200);
  CHECK(dataset.frames[1].left.empty());
  CHECK(dataset.warnings.empty());

  // Rows pair by position; a shorter right list truncates with a warning.
  writeText(dir / "mav0/cam1/data.csv", "100\n200\n");
  const Dataset shorter = voca::openDataset(dir / "mav0");
  CHECK(shorter.frames.size() == 2);
  REQUIRE(shorter.warnings.size() == 1);
  expectError(shorter.warnings[0], "only the first 2 rows count");

  fs::remove(dir / "mav0/cam1/data.mp4");
  expectError(errorOf(dir.path()), "cam1/data.mp4: missing");
}
