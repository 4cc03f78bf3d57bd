// The decoder's per-frame path (send, receive with the MotionField fill, outlier flags, I-frame
// bridging) makes no C++ heap allocation once the first frames have sized the buffers. libavcodec
// allocates internally with av_malloc (plain malloc, not counted here): only our code is in scope.
// This executable replaces the global operator new/delete with counting versions.

#include <doctest/doctest.h>

#include <cmath>
#include <functional>
#include <vector>

#include "drivers/decode/video_decoder.h"
#include "drivers/encode/video_encoder.h"
#include "drivers/encode/video_file_encoder.h"
#include "tests/test_alloc_counter.h"
#include "tests/test_moving_texture.h"
#include "tests/test_support.h"

namespace {

constexpr int kWidth = 160, kHeight = 128, kFrames = 20;
// Frames before the count starts: the first frame sizes the luma plane and the motion field.
constexpr int kWarmupFrames = 2;

voca::GrayImage frameAt(int k) { return voca::test::movingTexture(kWidth, kHeight, k); }

}  // namespace

TEST_CASE("decoder: no heap allocation per frame after warm-up, with motion export") {
  voca::test::ScratchDir dir("decode-alloc");
  voca::encode::EncoderSettings settings;
  settings.two_pass = false;
  // A keyframe every 8 frames, so I-frames (no vectors, bridged) are inside the counted range.
  settings.x264_params += ":keyint=8:min-keyint=8";
  std::vector<voca::GrayImage> frames;
  for (int k = 0; k < kFrames; ++k) frames.push_back(frameAt(k));
  voca::encode::encodeVideoFile(dir / "a.mp4", settings, [&](const std::function<void(voca::GrayView)>& emit) {
    for (const voca::GrayImage& f : frames) emit(f.view());
  });

  // Packets are read up front: the demuxer is outside the per-frame decode path measured here.
  voca::decode::Demuxer demuxer(dir / "a.mp4");
  const std::vector<voca::decode::Packet> packets = voca::decode::readAllPackets(demuxer);
  REQUIRE(packets.size() == static_cast<std::size_t>(kFrames));

  voca::decode::DecoderOptions options;
  options.kind = voca::decode::DecoderKind::kSoftware;
  options.log_choice = false;
  voca::decode::VideoDecoder decoder(demuxer.stream(), options, nullptr, "a.mp4");
  voca::decode::DecodedFrame frame;
  frame.reserve(kWidth, kHeight);
  voca::MotionPriorBridge bridge(kWidth, kHeight);

  int decoded = 0, with_vectors = 0, bridged = 0;
  long steady_allocations = 0;
  const auto receiveAll = [&] {
    for (;;) {
      const long before = voca::test::g_allocations.load();
      if (!decoder.receive(frame)) {
        if (decoded >= kWarmupFrames) steady_allocations += voca::test::g_allocations.load() - before;
        return;
      }
      frame.motion.flagOutliers();
      bool was_bridged = false;
      const voca::MotionField* prior = bridge.prior(frame.motion, 0, was_bridged);
      bridged += was_bridged ? 1 : 0;
      if (decoded >= kWarmupFrames) steady_allocations += voca::test::g_allocations.load() - before;
      with_vectors += prior != nullptr && prior->hasVectors() ? 1 : 0;  // own or bridged
      ++decoded;
    }
  };
  for (const voca::decode::Packet& packet : packets) {
    const long before = voca::test::g_allocations.load();
    decoder.send(packet);
    if (decoded >= kWarmupFrames) steady_allocations += voca::test::g_allocations.load() - before;
    receiveAll();
  }
  decoder.sendEnd();
  receiveAll();

  // The counter is live (the set-up above allocated), so zero below is a measurement.
  CHECK(voca::test::g_allocations.load() > 0);
  CHECK(decoded == kFrames);
  // The path measured really did the work: vectors on P-frames, and the later I-frames bridged.
  CHECK(with_vectors >= kFrames - 3);
  CHECK(bridged >= 1);
  CHECK(steady_allocations == 0);
}
