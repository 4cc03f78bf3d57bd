// Image datasets replayed as a stereo source, on small folders written to scratch space: an image
// that cannot be read is a damaged frame (skipped and named in a warning) unless the replay is
// strict, where it stops the replay naming the file and the frame.

#include <array>
#include <fstream>
#include <iterator>
#include <string>

#include "drivers/source/dataset_source.h"
#include "formats/dataset/dataset.h"
#include "formats/image/png_io.h"
#include "tests/test_support.h"
#include "voca/core/error.h"

namespace {

namespace fs = std::filesystem;
using voca::test::expectError;

constexpr int kWidth = 32, kHeight = 24;

std::int64_t stampOf(int frame) { return 1'000'000'000 + 50'000'000LL * frame; }

// A EuRoC folder of `frames` stereo pairs, each image filled with its frame's number.
voca::Dataset writeDataset(const fs::path& root, int frames) {
  voca::EurocWriter writer(root);
  for (int i = 0; i < frames; ++i) {
    const voca::GrayImage image(kWidth, kHeight, static_cast<std::uint8_t>(i));
    const std::array<voca::GrayView, 2> views = {image.view(), image.view()};
    writer.addFrame(stampOf(i), views);
  }
  writer.finish();
  return voca::openDataset(root);
}

// Cuts a PNG in the middle of its pixel data, as an interrupted copy does.
void truncatePng(const fs::path& png) {
  std::ifstream in(png, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  REQUIRE(bytes.size() > 60);
  std::ofstream(png, std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() / 2);
}

voca::ReplayOptions replay(bool strict) {
  voca::ReplayOptions options;
  options.strict = strict;
  return options;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

}  // namespace

TEST_CASE("image replay: an unreadable image makes its frame damaged, named in the warnings; the rest play") {
  voca::test::ScratchDir dir("source-damaged");
  const voca::Dataset dataset = writeDataset(dir.path(), 6);
  truncatePng(dataset.frames[2].left);
  // Listed in data.csv and present when the folder was opened, gone when its frame comes.
  fs::remove(dataset.frames[4].right);

  voca::ImageDatasetSource source(dataset, replay(false));
  CHECK(source.info().width == kWidth);
  CHECK(source.info().expected_frames == 6);
  voca::RawStereoFrame frame;
  for (int i = 0; i < 6; ++i) {
    INFO("frame " << i);
    REQUIRE(source.next(frame));
    CHECK(frame.frame_index == i);
    CHECK(frame.t_ns == stampOf(i));
    const bool unreadable = i == 2 || i == 4;
    CHECK(frame.damaged == unreadable);
    if (!unreadable) {
      // The pixels are the frame's own, not left over from the damaged one.
      REQUIRE(frame.images[0].width() == kWidth);
      CHECK(frame.images[0](0, 0) == i);
      CHECK(frame.images[1](kWidth - 1, kHeight - 1) == i);
    }
  }
  CHECK_FALSE(source.next(frame));

  const std::vector<std::string> warnings = source.warnings();
  REQUIRE(warnings.size() == 2);
  expectError(warnings[0], "frame 2 skipped as damaged");
  expectError(warnings[0], dataset.frames[2].left.string() + ": corrupt PNG");
  expectError(warnings[1], "frame 4 skipped as damaged");
  expectError(warnings[1], dataset.frames[4].right.string());
}

TEST_CASE("image replay: strict stops at the first unreadable image, naming the file and the frame") {
  voca::test::ScratchDir dir("source-damaged-strict");
  const voca::Dataset dataset = writeDataset(dir.path(), 5);
  truncatePng(dataset.frames[3].right);

  voca::ImageDatasetSource source(dataset, replay(true));
  voca::RawStereoFrame frame;
  for (int i = 0; i < 3; ++i) {
    REQUIRE(source.next(frame));
    CHECK_FALSE(frame.damaged);
  }
  const std::string error = voca::test::inputErrorOf([&] { source.next(frame); });
  expectError(error, "frame 3 is damaged");
  expectError(error, dataset.frames[3].right.string() + ": corrupt PNG");
  CHECK(source.warnings().empty());
}

TEST_CASE("image replay: an unreadable first frame") {
  voca::test::ScratchDir dir("source-damaged-first");
  const voca::Dataset dataset = writeDataset(dir.path(), 4);
  truncatePng(dataset.frames[0].left);

  // Strict: the source cannot even open.
  const std::string error = voca::test::inputErrorOf([&] { voca::ImageDatasetSource strict(dataset, replay(true)); });
  expectError(error, "frame 0 is damaged");
  expectError(error, dataset.frames[0].left.string());

  // Non-strict: the image size comes from the next readable pair, and frame 0 is the damaged one.
  voca::ImageDatasetSource source(dataset, replay(false));
  CHECK(source.info().width == kWidth);
  CHECK(source.info().height == kHeight);
  voca::RawStereoFrame frame;
  REQUIRE(source.next(frame));
  CHECK(frame.damaged);
  REQUIRE(source.next(frame));
  CHECK_FALSE(frame.damaged);
  CHECK(frame.frame_index == 1);

  // Nothing readable at all is not a replay.
  for (const voca::StereoFrameRef& ref : dataset.frames) truncatePng(ref.right);
  const std::string none = voca::test::inputErrorOf([&] { voca::ImageDatasetSource all(dataset, replay(false)); });
  expectError(none, "no frame of the 4 to replay has both images readable");
}

TEST_CASE("image replay: many damaged frames are listed up to ten, then counted") {
  voca::test::ScratchDir dir("source-damaged-many");
  const voca::Dataset dataset = writeDataset(dir.path(), 15);
  for (int i = 1; i <= 13; ++i) truncatePng(dataset.frames[static_cast<std::size_t>(i)].left);

  voca::ImageDatasetSource source(dataset, replay(false));
  voca::RawStereoFrame frame;
  int damaged = 0, frames = 0;
  while (source.next(frame)) {
    ++frames;
    damaged += frame.damaged ? 1 : 0;
  }
  CHECK(frames == 15);
  CHECK(damaged == 13);
  const std::vector<std::string> warnings = source.warnings();
  REQUIRE(warnings.size() == 11);
  CHECK(contains(warnings[9], "frame 10 skipped"));
  CHECK(warnings[10] == "3 more frames with unreadable images were skipped as damaged");
}
