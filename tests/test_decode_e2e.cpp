// End to end: the micro EuRoC sequence (95 real stereo frames) encoded per camera as the paper does
// (libx264, two-pass 500 kbit/s at 30 fps) into the VOCA video layout, then read back in lockstep.

#include <doctest/doctest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <vector>

#include "drivers/decode/video_reader.h"
#include "drivers/encode/video_encoder.h"
#include "drivers/encode/video_file_encoder.h"
#include "formats/dataset/dataset.h"
#include "formats/image/png_io.h"
#include "test_support.h"

namespace fs = std::filesystem;

TEST_CASE("micro EuRoC at 500 kbit/s decodes back with vectors on every P-frame") {
  const auto root = voca::test::sharedData("euroc_v101_micro");
  if (!root) return;
  const voca::Dataset images = voca::openDataset(*root);
  REQUIRE(images.frames.size() == 95);

  voca::test::ScratchDir dir("decode-e2e");
  const fs::path mav0 = dir / "mav0";
  for (int cam = 0; cam < 2; ++cam) {
    const fs::path cam_dir = mav0 / ("cam" + std::to_string(cam));
    fs::create_directories(cam_dir);
    std::ofstream csv(cam_dir / "data.csv");
    csv << "#timestamp [ns],filename\n";
    for (const voca::StereoFrameRef& f : images.frames) csv << f.t_ns << "," << f.t_ns << ".png\n";
    voca::encode::EncoderSettings settings;  // paper defaults: libx264, 500 kbit/s, 30 fps, two passes
    voca::encode::encodeVideoFile(cam_dir / "data.mp4", settings, [&](const std::function<void(voca::GrayView)>& emit) {
      voca::GrayImage image;
      for (const voca::StereoFrameRef& f : images.frames) {
        voca::readPngGray(cam == 0 ? f.left : f.right, image);
        emit(image.view());
      }
    });
  }

  const voca::Dataset video = voca::openDataset(dir.path());
  REQUIRE(video.layout == voca::DatasetLayout::kVocaVideo);
  voca::decode::DecoderOptions options;
  options.kind = voca::decode::DecoderKind::kSoftware;
  voca::decode::StereoVideoReader reader(video, options);
  CHECK(reader.size() == 95);

  // A parallel MV-only parse of the left video: DESIGN.md says skipping the loop filter keeps the
  // vectors exactly; the pipeline relies on that for hardware decoding.
  voca::decode::DecoderOptions parse_options = options;
  parse_options.decode_pixels = false;
  voca::decode::VideoReader parse(video.video_left, voca::decode::datasetTimestamps(video), parse_options);

  voca::decode::DecodedFrame left, right, parsed;
  voca::GrayImage original;
  std::size_t n = 0;
  int p_frames = 0, mv_mismatches = 0;
  double abs_error = 0.0;
  while (reader.next(left, right)) {
    REQUIRE(n < images.frames.size());
    CAPTURE(n);
    CHECK(left.frame_index == static_cast<std::int64_t>(n));
    CHECK(left.t_ns == images.frames[n].t_ns);
    CHECK(right.t_ns == images.frames[n].t_ns);
    CHECK(left.luma.width() == 752);
    CHECK(left.luma.height() == 480);
    if (n == 0) {
      CHECK(left.motion.pictureType() == voca::PictureType::kI);
      CHECK_FALSE(left.motion.hasVectors());
    } else {
      // keyint=1000 and 95 frames: every later frame is a P-frame and must carry vectors.
      CHECK(left.motion.pictureType() == voca::PictureType::kP);
      CHECK(right.motion.pictureType() == voca::PictureType::kP);
      CHECK(left.motion.hasVectors());
      CHECK(right.motion.hasVectors());
      p_frames += left.motion.pictureType() == voca::PictureType::kP ? 1 : 0;
    }
    REQUIRE(parse.next(parsed));
    const auto a = left.motion.blocks(), b = parsed.motion.blocks();
    bool same = a.size() == b.size();
    for (std::size_t i = 0; same && i < a.size(); ++i) {
      same = a[i].x == b[i].x && a[i].y == b[i].y && a[i].w == b[i].w && a[i].dx == b[i].dx && a[i].dy == b[i].dy;
    }
    mv_mismatches += same ? 0 : 1;
    if (n % 10 == 0) {
      voca::readPngGray(images.frames[n].left, original);
      double sum = 0;
      for (int y = 0; y < 480; ++y)
        for (int x = 0; x < 752; ++x) sum += std::abs(int(original(x, y)) - int(left.luma(x, y)));
      abs_error = std::max(abs_error, sum / (752.0 * 480.0));
    }
    ++n;
  }
  CHECK(n == 95);
  CHECK(p_frames == 94);
  CHECK(mv_mismatches == 0);
  // 500 kbit/s on 752x480 is ~0.05 bit/pixel/frame: visibly lossy, but the Y plane must still be the
  // image (no colour conversion or range change): the mean absolute error stays a few grey levels.
  MESSAGE("worst mean absolute luma error: " << abs_error);
  CHECK(abs_error < 6.0);
}
