// The software decoder's picture memory is allocated at its first picture: a stream damaged at
// random (concealed slices, refused packets, damaged keyframes) makes the decoder hold more pictures
// at times than a clean one does, which libavcodec's default allocator meets by allocating one more
// picture then and keeping it (an RSS step hours into a soak). The pool sized from the stream's
// headers must cover every such moment, so the count of pictures allocated never moves after the
// first frame.

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <random>
#include <vector>

#include "drivers/decode/pixel_decoder.h"
#include "drivers/decode/video_decoder.h"
#include "drivers/encode/video_encoder.h"
#include "drivers/encode/video_file_encoder.h"
#include "tests/test_moving_texture.h"
#include "tests/test_support.h"
#include "voca/core/error.h"

extern "C" {
#include <libavutil/error.h>
}

namespace {

constexpr int kWidth = 160, kHeight = 128, kFrames = 24, kPasses = 40;

voca::GrayImage frameAt(int k) { return voca::test::movingTexture(kWidth, kHeight, k); }

// Noise over the packet past its length prefix and first slice header bytes, as the soak's source does.
void damage(voca::decode::Packet& packet, std::mt19937_64& rng) {
  for (std::size_t i = std::min<std::size_t>(12, packet.bytes.size() / 2); i < packet.bytes.size(); ++i)
    packet.bytes[i] = static_cast<std::uint8_t>(rng());
}

}  // namespace

TEST_CASE("software decoding: picture memory allocated at the first picture covers a damaged stream") {
  voca::test::ScratchDir dir("decode-picture-pool");
  voca::encode::EncoderSettings settings;
  settings.two_pass = false;
  // A keyframe every 4 frames: many damaged keyframes, the case that needs a picture more.
  settings.x264_params += ":keyint=4:min-keyint=4:scenecut=0";
  voca::encode::encodeVideoFile(dir / "a.mp4", settings, [&](const std::function<void(voca::GrayView)>& emit) {
    for (int k = 0; k < kFrames; ++k) emit(frameAt(k).view());
  });
  voca::decode::Demuxer demuxer(dir / "a.mp4");
  const std::vector<voca::decode::Packet> packets = voca::decode::readAllPackets(demuxer);
  REQUIRE(packets.size() == static_cast<std::size_t>(kFrames));
  const std::int64_t pass_pts = packets.back().pts + (packets[1].pts - packets[0].pts);

  voca::decode::DecoderOptions options;
  options.kind = voca::decode::DecoderKind::kSoftware;
  options.strict = false;
  options.log_choice = false;
  voca::decode::silenceDamageMessages();
  voca::decode::VideoDecoder decoder(demuxer.stream(), options, nullptr, "a.mp4");
  REQUIRE(decoder.picturesAllocated() == 0);

  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  voca::decode::DecodedFrame frame;
  std::int64_t at_first_picture = -1, after_clean_pass = -1;
  int received = 0, damaged = 0, refused = 0;
  voca::decode::Packet packet;
  for (int pass = 0; pass < kPasses; ++pass) {
    for (const voca::decode::Packet& original : packets) {
      packet = original;
      packet.pts += pass * pass_pts;
      packet.dts += pass * pass_pts;
      packet.index += static_cast<std::int64_t>(pass) * kFrames;
      // The first pass clean; then one packet in four damaged, keyframes as often as the others.
      if (pass > 0 && uniform(rng) < 0.25) {
        damage(packet, rng);
        ++damaged;
      }
      try {
        if (!decoder.trySend(packet)) ++refused;
        while (decoder.receive(frame)) {
          if (++received == 1) at_first_picture = decoder.picturesAllocated();
        }
      } catch (const voca::InputError&) {
        ++refused;  // a damaged header can make a picture unusable; the stream goes on
      }
    }
    if (pass == 0) after_clean_pass = decoder.picturesAllocated();
  }
  INFO("received " << received << ", damaged " << damaged << ", refused " << refused);
  REQUIRE(received > kFrames);
  CHECK(damaged > 100);
  CHECK(at_first_picture > 0);
  // All allocated at the first picture, not as a clean stream's steady state needed them...
  CHECK(after_clean_pass == at_first_picture);
  // ... and the damage never made the decoder need a picture more (a pool filled on demand, as
  // libavcodec's default, grows here from 2 to 3 pictures).
  CHECK(decoder.picturesAllocated() == after_clean_pass);
}

TEST_CASE("pictures from a device (an external pixel decoder) are not counted as the pool's") {
  // A device that never returns a picture: only the construction matters here.
  struct NoPictures final : voca::decode::PixelDecoder {
    int send(const AVPacket* /*packet*/) override { return 0; }
    int receive(AVFrame* /*frame*/) override { return AVERROR(EAGAIN); }
  };
  voca::decode::StreamInfo stream;
  stream.codec = voca::decode::VideoCodec::kH264;
  stream.codec_name = "h264";
  stream.width = kWidth;
  stream.height = kHeight;
  voca::decode::DecoderOptions options;
  options.log_choice = false;
  voca::decode::VideoDecoder decoder(stream, options, std::make_unique<NoPictures>(), "device");
  CHECK(decoder.picturesAllocated() == -1);
}
