// A video file end to end as the pipeline reads one: demux (any container libavformat probes),
// software decode with motion-vector export, conversion to the MotionField, outlier flagging and
// I-frame bridging. libav itself is not instrumented; our side of every call is.
#include <algorithm>

#include "drivers/decode/demuxer.h"
#include "drivers/decode/video_decoder.h"
#include "tests/fuzz/fuzz_support.h"
#include "voca/motion/motion_field.h"

namespace {

// Enough packets to reach P-frames after the headers; keeps one input to milliseconds.
constexpr int kMaxPackets = 48;

void consume(voca::decode::DecodedFrame& frame, voca::MotionPriorBridge& bridge) {
  frame.motion.flagOutliers();
  bool bridged = false;
  const voca::MotionField* prior = bridge.prior(frame.motion, 0, bridged);
  // Every block lookup inside the frame, in its own field and in the prior the tracker would use,
  // must stay in bounds.
  for (int y = 0; y < frame.motion.height(); y += 7) {
    for (int x = 0; x < frame.motion.width(); x += 7) {
      (void)frame.motion.blockAt(x, y);
      if (prior != nullptr) (void)prior->blockAt(x, y);
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = voca::fuzz::writeInput("video.bin", data, size);
  voca::fuzz::expectOnlyInputErrors([&] {
    voca::decode::Demuxer demuxer(path);
    const voca::decode::StreamInfo& stream = demuxer.stream();
    // Refuse absurd frame sizes before the decoder allocates them: the pipeline would too.
    if (static_cast<long long>(stream.width) * stream.height > 4096LL * 4096LL) return;
    voca::decode::DecoderOptions options;
    options.kind = voca::decode::DecoderKind::kSoftware;
    options.strict = false;
    options.log_choice = false;
    voca::decode::VideoDecoder decoder(stream, options, nullptr, "fuzz");
    voca::decode::Packet packet;
    voca::decode::DecodedFrame frame;
    voca::MotionPriorBridge bridge(std::max(stream.width, 16), std::max(stream.height, 16));
    for (int n = 0; n < kMaxPackets && demuxer.read(packet); ++n) {
      decoder.send(packet);
      while (decoder.receive(frame)) consume(frame, bridge);
    }
    decoder.sendEnd();
    while (decoder.receive(frame)) consume(frame, bridge);
  });
  return 0;
}
