// The decode stage inside the staged runner with a real decoder that returns no picture for some
// packets: a stream joined after its keyframe (libavcodec's H.264 decoder outputs nothing until the
// next keyframe) and packets lost from one camera. Under the live policy the pool has only 4 slots,
// and a decode stage that kept a slot for every picture still inside the decoder used to hold all
// of them: the source then waited for a free slot, the decoder for more packets, and the run hung.
// Every slot must come back and every run must end, with every frame accounted for.

#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "drivers/encode/video_encoder.h"

extern "C" {
#include <libavcodec/avcodec.h>
}
#include "pipeline/runtime/runner.h"
#include "pipeline/stages/decode_stage.h"

using namespace voca;
using namespace voca::pipeline;

namespace {

constexpr int kWidth = 64, kHeight = 48;
constexpr int kKeyframeInterval = 16;
constexpr int kFrames = 3 * kKeyframeInterval;

// Both cameras' packets of a short H.264 stream (a drifting pattern, a keyframe every 16 frames, no
// B-frames, codec headers out of band as a container or SDP would carry them).
struct StereoStream {
  std::vector<encode::EncodedPacket> packets;  // one camera; the other is the same stream
  decode::StreamInfo info;
};

StereoStream encodeStream() {
  encode::silenceCodecLogs();
  encode::EncoderSettings settings;
  settings.x264_params = "keyint=16:min-keyint=16:scenecut=0:bframes=0:ref=1";
  settings.x264_preset = "ultrafast";
  settings.x264_tune = "zerolatency";
  settings.two_pass = false;
  settings.global_header = true;
  encode::VideoEncoder encoder;
  encoder.open(settings, kWidth, kHeight);
  StereoStream s;
  GrayImage image(kWidth, kHeight);
  const auto keep = [&](std::span<const encode::EncodedPacket> out) {
    for (const encode::EncodedPacket& p : out) s.packets.push_back(p);
  };
  for (int i = 0; i < kFrames; ++i) {
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        image(x, y) = static_cast<std::uint8_t>(128 + 100 * std::sin(0.3 * (x + i)) * std::cos(0.25 * y));
      }
    }
    keep(encoder.encode(image.view(), i));
  }
  keep(encoder.flush());
  s.info.codec = decode::VideoCodec::kH264;
  s.info.codec_name = "h264";
  s.info.width = kWidth;
  s.info.height = kHeight;
  const AVCodecContext* ctx = encoder.codecContext();
  s.info.extradata.assign(ctx->extradata, ctx->extradata + ctx->extradata_size);
  s.info.time_base_num = 1;
  s.info.time_base_den = 30;
  return s;
}

// Sends frames [first, kFrames) of the stream; camera `lossy_camera`'s packets in `lost` arrive
// empty (lost on the way).
class PacketSource final : public SourceStage {
 public:
  PacketSource(const StereoStream& stream, int first, int lossy_camera, std::vector<int> lost)
      : stream_(stream), next_(first), lossy_camera_(lossy_camera), lost_(std::move(lost)) {}
  std::string_view name() const override { return "receive"; }
  Produced produce(FrameSlot& slot) override {
    if (next_ >= static_cast<int>(stream_.packets.size())) return Produced::kEnd;
    const encode::EncodedPacket& p = stream_.packets[static_cast<std::size_t>(next_)];
    const bool lost = std::find(lost_.begin(), lost_.end(), next_) != lost_.end();
    for (int c = 0; c < 2; ++c) {
      decode::Packet& out = slot.encoded.packets[static_cast<std::size_t>(c)];
      if (lost && c == lossy_camera_) {
        out.bytes.clear();
      } else {
        out.bytes.assign(p.bytes.begin(), p.bytes.end());
      }
      out.pts = p.pts;
      out.dts = p.dts;
      out.keyframe = p.keyframe;
      out.index = sent_;
    }
    slot.encoded.frame_index = next_;
    slot.frame.frame_index = next_;
    ++next_;
    ++sent_;
    return Produced::kFrame;
  }

 private:
  const StereoStream& stream_;
  int next_;
  int lossy_camera_;
  std::vector<int> lost_;
  std::int64_t sent_ = 0;
};

class FrameRecorder final : public Stage {
 public:
  std::string_view name() const override { return "sink"; }
  void process(FrameSlot& slot, Emitter& out) override {
    frames.push_back(slot.frameIndex());
    out.forward(slot);
  }
  std::vector<std::int64_t> frames;
};

struct Outcome {
  RunReport report;
  std::vector<std::int64_t> frames;  // decoded frames, in order
};

Outcome run(const StereoStream& stream, int first, int lossy_camera, std::vector<int> lost, int threads, bool strict) {
  PacketSource source(stream, first, lossy_camera, std::move(lost));
  DecodeStageOptions decode_options;
  decode_options.decoder.kind = decode::DecoderKind::kSoftware;
  decode_options.decoder.strict = strict;
  decode_options.decoder.log_choice = false;
  DecodeStage decode({stream.info, stream.info}, decode_options);
  FrameRecorder sink;
  PipelineOptions options;
  options.threads = threads;
  options.live_policy = true;  // 4 slots
  // A hung run would wait forever; this turns it into a stopped run the test reports.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  options.stop_requested = [deadline] { return std::chrono::steady_clock::now() > deadline; };
  Pipeline pipeline(source, {&decode, &sink}, options);
  Outcome outcome;
  outcome.report = pipeline.run();
  outcome.frames = sink.frames;
  return outcome;
}

}  // namespace

TEST_CASE("decode stage: a decoder that returns no picture for many packets never hangs the live pipeline") {
  const StereoStream stream = encodeStream();
  REQUIRE(stream.packets.size() == static_cast<std::size_t>(kFrames));
  for (int i = 0; i < kFrames; ++i) {
    REQUIRE(stream.packets[static_cast<std::size_t>(i)].keyframe == (i % kKeyframeInterval == 0));
  }
  const auto contains = [](const std::vector<std::int64_t>& frames, std::int64_t first, std::int64_t last) {
    for (std::int64_t f = first; f <= last; ++f) {
      if (std::find(frames.begin(), frames.end(), f) == frames.end()) return false;
    }
    return true;
  };
  for (const int threads : {0, 1}) {
    CAPTURE(threads);
    SUBCASE("joined after the keyframe: nothing decodes until the next one") {
      // The decoder swallows frames 1..15 (no picture, no error): far more than the 3 slots the
      // stage may hold. They are given up as damaged; everything from the keyframe on decodes.
      const Outcome o = run(stream, 1, 0, {}, threads, false);
      CHECK_FALSE(o.report.stopped);
      CHECK_FALSE(o.report.error.has_value());
      CHECK(o.report.produced == kFrames - 1);
      CHECK(o.report.completed + o.report.damaged == o.report.produced);
      CHECK(o.report.damaged == kKeyframeInterval - 1);
      std::vector<std::int64_t> expected;
      for (int f = kKeyframeInterval; f < kFrames; ++f) expected.push_back(f);
      CHECK(o.frames == expected);
    }
    SUBCASE("one camera loses a P-frame") {
      const Outcome o = run(stream, 0, 1, {5}, threads, false);
      CHECK_FALSE(o.report.stopped);
      CHECK_FALSE(o.report.error.has_value());
      CHECK(o.report.completed + o.report.damaged == kFrames);
      CHECK(std::find(o.frames.begin(), o.frames.end(), 5) == o.frames.end());
      CHECK(contains(o.frames, 0, 4));
      CHECK(contains(o.frames, kKeyframeInterval, kFrames - 1));
      CHECK(std::is_sorted(o.frames.begin(), o.frames.end()));
    }
    SUBCASE("one camera loses a keyframe: its P-frames until the next one have no reference") {
      const Outcome o = run(stream, 0, 0, {kKeyframeInterval}, threads, false);
      CHECK_FALSE(o.report.stopped);
      CHECK_FALSE(o.report.error.has_value());
      CHECK(o.report.completed + o.report.damaged == kFrames);
      // libavcodec withholds most of the unreferenced P-frames (how many is its heuristic): more
      // than the stage may hold, which is what used to hang the run.
      CHECK(o.report.damaged > 3);
      CHECK(contains(o.frames, 0, kKeyframeInterval - 1));
      CHECK(contains(o.frames, 2 * kKeyframeInterval, kFrames - 1));
      CHECK(std::is_sorted(o.frames.begin(), o.frames.end()));
    }
    SUBCASE("strict decoding: the first frame given up stops the run with its name, without hanging") {
      const Outcome o = run(stream, 1, 0, {}, threads, true);
      CHECK_FALSE(o.report.stopped);
      REQUIRE(o.report.error.has_value());
      CHECK(o.report.error->stage == "decode");
      CHECK(o.report.error->message.find("frame 1 is damaged") != std::string::npos);
      CHECK(o.report.error->message.find("cam0: its picture had not come out of the decoder") != std::string::npos);
      CHECK(o.frames.empty());
    }
  }
}
