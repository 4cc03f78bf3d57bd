// The looping video source of `voca bench soak`: one long stream made from a short recording (indices,
// times and pts keep increasing across the seam, packets are the recording's), seeded drops that
// resume at a keyframe of both cameras, damaged packets, every frame index accounted for, and no
// allocation per frame once its buffers hold the largest packet.

#include <doctest/doctest.h>

#include <fstream>
#include <string>
#include <vector>

#include "drivers/encode/video_encoder.h"
#include "drivers/encode/video_file_encoder.h"
#include "drivers/source/dataset_source.h"
#include "drivers/source/looping_source.h"
#include "formats/dataset/dataset.h"
#include "tests/test_alloc_counter.h"
#include "tests/test_frontend_support.h"
#include "tests/test_support.h"
#include "voca/core/error.h"

using namespace voca;
namespace fs = std::filesystem;

namespace {

constexpr int kWidth = 160, kHeight = 96, kFrames = 12, kKeyframeInterval = 4;
constexpr std::int64_t kFirstNs = 1'000'000'000, kIntervalNs = 50'000'000;

// A VOCA video folder of a moving texture, a keyframe every kKeyframeInterval frames.
fs::path makeVideoFolder(const test::ScratchDir& dir) {
  const fs::path mav0 = dir / "seq" / "mav0";
  const test::WaveTexture texture(5);
  encode::EncoderSettings settings;
  settings.two_pass = false;
  settings.x264_params += ":keyint=" + std::to_string(kKeyframeInterval) +
                          ":min-keyint=" + std::to_string(kKeyframeInterval) + ":scenecut=0";
  encode::silenceCodecLogs();
  for (int c = 0; c < 2; ++c) {
    const fs::path cam = mav0 / ("cam" + std::to_string(c));
    fs::create_directories(cam);
    encode::encodeVideoFile(cam / "data.mp4", settings, [&](const std::function<void(GrayView)>& emit) {
      GrayImage image;
      for (int k = 0; k < kFrames; ++k) {
        texture.render(image, kWidth, kHeight, 2.0 * k - 6.0 * c, 1.0 * k);
        emit(image.view());
      }
    });
    std::ofstream csv(cam / "data.csv");
    csv << "#timestamp [ns],filename\n";
    for (int k = 0; k < kFrames; ++k) csv << kFirstNs + kIntervalNs * k << "," << k << ".png\n";
  }
  return dir / "seq";
}

std::vector<EncodedStereoPacket> readRecording(const Dataset& dataset) {
  VideoFolderSource source(dataset);
  std::vector<EncodedStereoPacket> packets;
  EncodedStereoPacket packet;
  while (source.next(packet)) packets.push_back(packet);
  return packets;
}

}  // namespace

TEST_CASE("looping source: a short recording becomes one long stream, seam included") {
  const test::ScratchDir dir("looping-source");
  const Dataset dataset = openDataset(makeVideoFolder(dir));
  const std::vector<EncodedStereoPacket> recording = readRecording(dataset);
  REQUIRE(recording.size() == kFrames);
  const std::int64_t pts_step = recording[1].packets[0].pts - recording[0].packets[0].pts;
  REQUIRE(pts_step > 0);

  constexpr std::int64_t kTotal = 3 * kFrames + 5;
  LoopingVideoSource source(dataset, {.frames = kTotal});
  CHECK(source.info().kind == SourceKind::kEncoded);
  CHECK(source.info().expected_frames == kTotal);
  CHECK(source.framesPerPass() == kFrames);
  EncodedStereoPacket packet;
  for (std::int64_t i = 0; i < kTotal; ++i) {
    REQUIRE(source.next(packet));
    const EncodedStereoPacket& original = recording[static_cast<std::size_t>(i % kFrames)];
    CHECK(packet.frame_index == i);
    // Evenly spaced across the seam: a pass lasts kFrames intervals.
    CHECK(packet.t_ns == kFirstNs + kIntervalNs * i);
    for (std::size_t c = 0; c < 2; ++c) {
      CHECK(packet.packets[c].bytes == original.packets[c].bytes);
      CHECK(packet.packets[c].keyframe == original.packets[c].keyframe);
      CHECK(packet.packets[c].pts == recording[0].packets[c].pts + pts_step * i);
    }
  }
  CHECK_FALSE(source.next(packet));
  const LoopCounters counters = source.loopCounters();
  CHECK(counters.frames == kTotal);
  CHECK(counters.delivered == kTotal);
  CHECK(counters.passes == 4);
  CHECK(counters.dropped + counters.skipped + counters.damaged_packets == 0);
  CHECK(source.counters().frames_lost == 0);
}

TEST_CASE("looping source: drops resume at a keyframe of both cameras, damage changes packets, all counted") {
  const test::ScratchDir dir("looping-source-faults");
  const Dataset dataset = openDataset(makeVideoFolder(dir));
  const std::vector<EncodedStereoPacket> recording = readRecording(dataset);
  constexpr std::int64_t kTotal = 400;
  const LoopOptions options{.frames = kTotal, .drop_rate = 0.05, .damage_rate = 0.1, .seed = 11};

  const auto replay = [&](std::vector<std::int64_t>& indices, std::int64_t& damaged) {
    LoopingVideoSource source(dataset, options);
    EncodedStereoPacket packet;
    std::int64_t previous = -1;
    while (source.next(packet)) {
      indices.push_back(packet.frame_index);
      const EncodedStereoPacket& original = recording[static_cast<std::size_t>(packet.frame_index % kFrames)];
      if (packet.frame_index != previous + 1) {
        // Frames were lost: the stream goes on where both decoders can start again.
        CHECK(packet.packets[0].keyframe);
        CHECK(packet.packets[1].keyframe);
      }
      const bool left_damaged = packet.packets[0].bytes != original.packets[0].bytes;
      const bool right_damaged = packet.packets[1].bytes != original.packets[1].bytes;
      CHECK_FALSE((left_damaged && right_damaged));  // one camera's packet per damaged frame
      for (std::size_t c = 0; c < 2; ++c) CHECK(packet.packets[c].bytes.size() == original.packets[c].bytes.size());
      damaged += left_damaged || right_damaged ? 1 : 0;
      previous = packet.frame_index;
    }
    return source.loopCounters();
  };
  std::vector<std::int64_t> indices;
  std::int64_t damaged = 0;
  const LoopCounters counters = replay(indices, damaged);
  CHECK(counters.frames == kTotal);
  CHECK(counters.dropped > 5);
  CHECK(counters.skipped > counters.dropped);  // a drop costs the rest of its GOP
  CHECK(counters.damaged_packets > 10);
  CHECK(damaged == counters.damaged_packets);
  CHECK(counters.delivered == static_cast<std::int64_t>(indices.size()));
  CHECK(counters.delivered + counters.dropped + counters.skipped == kTotal);

  // The same seed, the same faults.
  std::vector<std::int64_t> again;
  std::int64_t damaged_again = 0;
  replay(again, damaged_again);
  CHECK(again == indices);
  CHECK(damaged_again == damaged);
}

TEST_CASE("looping source: no allocation per frame once the buffers hold the largest packet") {
  const test::ScratchDir dir("looping-source-alloc");
  const Dataset dataset = openDataset(makeVideoFolder(dir));
  LoopingVideoSource source(dataset, {.frames = 0, .drop_rate = 0.05, .damage_rate = 0.1, .seed = 2});
  EncodedStereoPacket packet;
  for (int i = 0; i < kFrames; ++i) REQUIRE(source.next(packet));  // one pass: every packet size seen
  const long before = test::g_allocations.load();
  for (int i = 0; i < 20 * kFrames; ++i) REQUIRE(source.next(packet));
  CHECK(test::g_allocations.load() - before == 0);
}

TEST_CASE("looping source: refuses rates outside [0, 1) and inputs that are no video folder") {
  const test::ScratchDir dir("looping-source-bad");
  const Dataset dataset = openDataset(makeVideoFolder(dir));
  CHECK_THROWS_AS(LoopingVideoSource(dataset, {.drop_rate = 1.0}), InputError);
  CHECK_THROWS_AS(LoopingVideoSource(dataset, {.damage_rate = -0.1}), InputError);
  CHECK_THROWS_AS(LoopingVideoSource(dataset, {.frames = -1}), InputError);
  Dataset images = dataset;
  images.layout = DatasetLayout::kEuroc;
  CHECK_THROWS_AS(LoopingVideoSource(images, {}), InputError);
}
