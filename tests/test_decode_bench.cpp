// `voca bench decode` on a small VOCA video folder made here: the paper's encoding codes at 30 fps
// while the recording runs at 20 Hz (data.csv), and the result says both rates and both bitrates.

#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>

#include "drivers/encode/video_encoder.h"
#include "drivers/encode/video_file_encoder.h"
#include "pipeline/bench/decode_bench.h"
#include "test_support.h"

namespace fs = std::filesystem;

TEST_CASE("decode bench: the stream's nominal rate and the recording's own rate are both reported") {
  voca::test::ScratchDir dir("decode-bench");
  constexpr int kFrames = 12, kWidth = 96, kHeight = 64;
  for (int cam = 0; cam < 2; ++cam) {
    const fs::path cam_dir = dir / "mav0" / ("cam" + std::to_string(cam));
    fs::create_directories(cam_dir);
    std::ofstream csv(cam_dir / "data.csv");
    csv << "#timestamp [ns],filename\n";
    const std::int64_t start_ns = 1000000000;
    for (int k = 0; k < kFrames; ++k) csv << start_ns + 50000000LL * k << "," << start_ns + 50000000LL * k << ".png\n";
    voca::encode::EncoderSettings settings;  // the paper's: libx264 at 30 fps whatever the recording's rate
    settings.two_pass = false;
    voca::encode::encodeVideoFile(cam_dir / "data.mp4", settings, [&](const std::function<void(voca::GrayView)>& emit) {
      voca::GrayImage image(kWidth, kHeight);
      for (int k = 0; k < kFrames; ++k) {
        for (int y = 0; y < kHeight; ++y)
          for (int x = 0; x < kWidth; ++x)
            image(x, y) = static_cast<std::uint8_t>(((x + 2 * k) / 6 + y / 6) % 2 * 160 + cam);
        emit(image.view());
      }
    });
  }
  voca::pipeline::DecodeBenchOptions options;
  options.input = dir.path();
  options.repeat = 1;
  options.progress = false;
  const voca::pipeline::DecodeBenchResult result = voca::pipeline::runDecodeBench(options);
  CHECK(result.videos.size() == 2);
  CHECK(result.frames == kFrames);
  CHECK(result.stream_fps == doctest::Approx(30.0));
  CHECK(result.recording_fps == doctest::Approx(20.0));
  REQUIRE(result.kbit_per_s > 0.0);
  // The same bytes spread over 1.5 times as long a recording.
  CHECK(result.recording_kbit_per_s == doctest::Approx(result.kbit_per_s * 20.0 / 30.0));
  CHECK(result.parse_vectors_identical);
}
