// The live encoder: the choice between V4L2 M2M, VAAPI and libx264 (with injected device probes, so
// the logic is tested on a machine without the devices), and libx264's low-latency stream: one
// packet per frame at once, no B-frames, motion vectors that follow the scene.

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "drivers/decode/video_decoder.h"
#include "drivers/encode/live_encoder.h"
#include "tests/test_encode_probe.h"
#include "tests/test_support.h"
#include "voca/core/error.h"

using namespace voca;
using namespace voca::encode;

namespace {

EncoderProbe probeWith(bool m2m, bool vaapi) {
  EncoderProbe probe;
  probe.v4l2m2m_present = [m2m] { return m2m; };
  probe.vaapi_present = [vaapi](const std::string&) { return vaapi; };
  return probe;
}

// Records what was opened; kinds in `failing` throw as a driver that refuses would.
struct FakeOpener {
  std::vector<EncoderKind> failing;
  std::vector<EncoderKind> opened;
  EncoderOpener fn() {
    return [this](EncoderKind kind) {
      opened.push_back(kind);
      if (std::find(failing.begin(), failing.end(), kind) != failing.end()) {
        throw RuntimeFailure(std::string("cannot open ") + encoderCodecName(kind));
      }
    };
  }
};

LiveEncoderSettings withKind(EncoderKind kind) {
  LiveEncoderSettings s;
  s.kind = kind;
  return s;
}

}  // namespace

TEST_CASE("encoder kinds parse by name and reject anything else") {
  CHECK(parseEncoderKind("auto") == EncoderKind::kAuto);
  CHECK(parseEncoderKind("x264") == EncoderKind::kX264);
  CHECK(parseEncoderKind("v4l2m2m") == EncoderKind::kV4l2m2m);
  CHECK(parseEncoderKind("vaapi") == EncoderKind::kVaapi);
  CHECK_THROWS_WITH_AS(parseEncoderKind("nvenc"), doctest::Contains("expected auto, x264, v4l2m2m or vaapi"),
                       InputError);
}

TEST_CASE("auto takes the first encoder whose device is present and opens") {
  SUBCASE("no devices: x264, saying why the hardware was not taken") {
    FakeOpener opener;
    const EncoderChoice choice = selectEncoder(withKind(EncoderKind::kAuto), probeWith(false, false), opener.fn());
    CHECK(choice.kind == EncoderKind::kX264);
    CHECK(opener.opened == std::vector<EncoderKind>{EncoderKind::kX264});
    REQUIRE(choice.notes.size() == 2);
    CHECK(choice.notes[0].find("v4l2m2m") == 0);
    CHECK(choice.notes[1].find("vaapi") == 0);
    CHECK(choice.description.find("encoder: x264 (libx264") == 0);
  }
  SUBCASE("an M2M encoder is preferred") {
    FakeOpener opener;
    const EncoderChoice choice = selectEncoder(withKind(EncoderKind::kAuto), probeWith(true, true), opener.fn());
    CHECK(choice.kind == EncoderKind::kV4l2m2m);
    CHECK(opener.opened == std::vector<EncoderKind>{EncoderKind::kV4l2m2m});
  }
  SUBCASE("present but refusing to open falls through to the next") {
    FakeOpener opener;
    opener.failing = {EncoderKind::kV4l2m2m, EncoderKind::kVaapi};
    const EncoderChoice choice = selectEncoder(withKind(EncoderKind::kAuto), probeWith(true, true), opener.fn());
    CHECK(choice.kind == EncoderKind::kX264);
    CHECK(opener.opened == std::vector<EncoderKind>{EncoderKind::kV4l2m2m, EncoderKind::kVaapi, EncoderKind::kX264});
    REQUIRE(choice.notes.size() == 2);
    CHECK(choice.notes[1].find("cannot open h264_vaapi") != std::string::npos);
  }
  SUBCASE("VAAPI when there is no M2M node") {
    FakeOpener opener;
    const EncoderChoice choice = selectEncoder(withKind(EncoderKind::kAuto), probeWith(false, true), opener.fn());
    CHECK(choice.kind == EncoderKind::kVaapi);
  }
}

TEST_CASE("an explicitly requested encoder that is missing is a clear error, never a silent fallback") {
  FakeOpener opener;
  CHECK_THROWS_WITH_AS(selectEncoder(withKind(EncoderKind::kV4l2m2m), probeWith(false, true), opener.fn()),
                       doctest::Contains("encoder v4l2m2m requested but unusable: no V4L2 memory-to-memory"),
                       InputError);
  CHECK_THROWS_WITH_AS(selectEncoder(withKind(EncoderKind::kVaapi), probeWith(true, false), opener.fn()),
                       doctest::Contains("no VAAPI render node /dev/dri/renderD128"), InputError);
  CHECK(opener.opened.empty());  // nothing else was tried behind the user's back
  opener.failing = {EncoderKind::kVaapi};
  CHECK_THROWS_WITH_AS(selectEncoder(withKind(EncoderKind::kVaapi), probeWith(false, true), opener.fn()),
                       doctest::Contains("cannot open h264_vaapi"), InputError);
  CHECK(opener.opened == std::vector<EncoderKind>{EncoderKind::kVaapi});
  const EncoderChoice x264 = selectEncoder(withKind(EncoderKind::kX264), probeWith(true, true), opener.fn());
  CHECK(x264.kind == EncoderKind::kX264);
}

TEST_CASE("the system probe on this machine picks an encoder that really opens") {
  VideoEncoder encoder;
  LiveEncoderSettings live;
  const EncoderChoice choice = openLiveEncoder(encoder, live, 64, 48);
  CHECK(encoder.isOpen());
  CHECK(encoder.settings().codec == encoderCodecName(choice.kind));
}

TEST_CASE("low-latency x264: one packet per frame at once, no B-frames, vectors that follow the scene") {
  constexpr int kWidth = 160, kHeight = 96, kFrames = 24, kGop = 10;
  const std::vector<GrayImage> frames = test::makePanningSequence(kWidth, kHeight, kFrames, 0.75, -0.5, 11);
  for (const bool monochrome : {false, true}) {
    CAPTURE(monochrome);
    LiveEncoderSettings live;
    live.kind = EncoderKind::kX264;
    live.bitrate_bps = 800000;
    live.gop = kGop;
    live.monochrome = monochrome;
    VideoEncoder encoder;
    encoder.open(lowLatencySettings(EncoderKind::kX264, live), kWidth, kHeight);

    decode::StreamInfo stream;
    stream.codec = decode::VideoCodec::kH264;
    stream.codec_name = "h264";
    stream.width = kWidth;
    stream.height = kHeight;
    stream.time_base_num = 1;
    stream.time_base_den = 20;
    decode::DecoderOptions options;
    options.kind = decode::DecoderKind::kSoftware;
    options.log_choice = false;
    decode::VideoDecoder decoder(stream, options);
    decode::DecodedFrame frame;
    decode::Packet packet;
    int decoded = 0, p_frames = 0;
    double sum_dx = 0.0, sum_dy = 0.0;
    std::size_t blocks = 0;
    for (int i = 0; i < kFrames; ++i) {
      const auto out = encoder.encode(frames[static_cast<std::size_t>(i)].view(), i);
      // Zero delay: the packet of frame i comes out of the call that took frame i.
      REQUIRE(out.size() == 1);
      CHECK(out[0].pts == i);
      CHECK(out[0].dts == i);
      CHECK(out[0].keyframe == (i % kGop == 0));
      // Headers in band with every keyframe: luma alone (0) or 4:2:0 (1), as asked.
      if (out[0].keyframe) CHECK(test::h264AnnexBChromaFormatIdc(out[0].bytes) == (monochrome ? 0 : 1));
      packet.bytes = out[0].bytes;
      packet.pts = out[0].pts;
      packet.dts = out[0].dts;
      packet.keyframe = out[0].keyframe;
      packet.index = i;
      decoder.send(packet);
      // And it decodes at once: no reordering delay in the decoder either.
      REQUIRE(decoder.receive(frame));
      CHECK(frame.pts == i);
      CHECK(frame.motion.pictureType() == (i % kGop == 0 ? PictureType::kI : PictureType::kP));
      ++decoded;
      if (frame.motion.pictureType() == PictureType::kP) {
        ++p_frames;
        for (const MotionBlock& b : frame.motion.blocks()) {
          sum_dx += b.dx;
          sum_dy += b.dy;
          ++blocks;
        }
      }
    }
    CHECK(encoder.flush().empty());  // nothing was held back
    CHECK(decoded == kFrames);
    CHECK(p_frames == kFrames - kFrames / kGop - 1);
    REQUIRE(blocks > 100);
    // The camera pans by (0.75, -0.5) px per frame, so the image content flows by (-0.75, 0.5);
    // quarter-pel vectors averaged over the frame land within a quarter pixel of it.
    const double mean_dx = sum_dx / static_cast<double>(blocks), mean_dy = sum_dy / static_cast<double>(blocks);
    CHECK(std::abs(mean_dx + 0.75) < 0.25);
    CHECK(std::abs(mean_dy - 0.5) < 0.25);
  }
}

TEST_CASE("luma alone (gray) is x264's: auto passes over the hardware, an explicit hardware encoder refuses") {
  LiveEncoderSettings live = withKind(EncoderKind::kAuto);
  live.monochrome = true;
  FakeOpener opener;
  const EncoderChoice choice = selectEncoder(live, probeWith(true, true), opener.fn());
  CHECK(choice.kind == EncoderKind::kX264);
  CHECK(opener.opened == std::vector<EncoderKind>{EncoderKind::kX264});  // no device was opened
  REQUIRE(choice.notes.size() == 2);
  CHECK(choice.notes[0] == "v4l2m2m: codes 4:2:0 only, and luma alone (gray, 4:0:0) was asked for");
  CHECK(choice.description.find("gray 4:0:0") != std::string::npos);
  live.kind = EncoderKind::kVaapi;
  CHECK_THROWS_WITH_AS(selectEncoder(live, probeWith(true, true), opener.fn()),
                       doctest::Contains("encoder vaapi requested but unusable: codes 4:2:0 only"), InputError);
}
