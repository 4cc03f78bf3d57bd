// Hardware pixels paired with the software motion-vector parse, exercised with a stand-in pixel
// decoder behind the PixelDecoder interface: a real libavcodec decoder whose output the stand-in
// reorders and thins as a device's output queue may. Every picture that comes out must carry the
// vectors parsed from its own packet. Also: the V4L2 M2M probe's rule (capabilities, not names).

#include <deque>
#include <map>
#include <vector>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/frame.h>
}

#include <linux/videodev2.h>

#include "drivers/decode/video_decoder.h"
#include "drivers/encode/live_encoder.h"
#include "platform/v4l2/m2m_devices.h"
#include "tests/test_encode_probe.h"
#include "tests/test_support.h"

using namespace voca;
using namespace voca::decode;

namespace {

constexpr int kWidth = 128, kHeight = 96, kFrames = 30;

struct Encoded {
  StreamInfo stream;
  std::vector<Packet> packets;
};

Encoded encodeSequence() {
  const std::vector<GrayImage> frames = test::makePanningSequence(kWidth, kHeight, kFrames, 0.6, 0.3, 5);
  encode::LiveEncoderSettings live;
  live.gop = 12;
  encode::VideoEncoder encoder;
  encoder.open(encode::lowLatencySettings(encode::EncoderKind::kX264, live), kWidth, kHeight);
  Encoded out;
  out.stream.codec = VideoCodec::kH264;
  out.stream.codec_name = "h264";
  out.stream.width = kWidth;
  out.stream.height = kHeight;
  out.stream.time_base_num = 1;
  out.stream.time_base_den = 20;
  for (int i = 0; i < kFrames; ++i) {
    for (const encode::EncodedPacket& p : encoder.encode(frames[static_cast<std::size_t>(i)].view(), i)) {
      Packet packet;
      packet.bytes = p.bytes;
      packet.pts = p.pts;
      packet.dts = p.dts;
      packet.keyframe = p.keyframe;
      packet.index = static_cast<std::int64_t>(out.packets.size());
      out.packets.push_back(packet);
    }
  }
  REQUIRE(out.packets.size() == static_cast<std::size_t>(kFrames));
  return out;
}

struct Reference {
  GrayImage luma;
  std::vector<MotionBlock> blocks;
  PictureType type = PictureType::kUnknown;
  int centre_qp = MotionField::kNoQp;
};

std::vector<DecodedFrame> decodeAll(VideoDecoder& decoder, const std::vector<Packet>& packets) {
  std::vector<DecodedFrame> out;
  DecodedFrame frame;
  auto take = [&] {
    while (decoder.receive(frame)) out.push_back(frame);
  };
  for (const Packet& p : packets) {
    decoder.send(p);
    take();
  }
  decoder.sendEnd();
  take();
  return out;
}

// A software H.264 decoder whose output order the test controls: the picture with pts `swap_pts`
// comes out after the one following it, and the picture with pts `drop_pts` never comes out.
class StandInDecoder final : public PixelDecoder {
 public:
  StandInDecoder(std::int64_t swap_pts, std::int64_t drop_pts) : swap_pts_(swap_pts), drop_pts_(drop_pts) {
    const AVCodec* codec = avcodec_find_decoder(AV_CODEC_ID_H264);
    ctx_ = avcodec_alloc_context3(codec);
    ctx_->thread_count = 1;
    REQUIRE(avcodec_open2(ctx_, codec, nullptr) == 0);
  }
  ~StandInDecoder() override {
    for (AVFrame* f : ready_) av_frame_free(&f);
    avcodec_free_context(&ctx_);
  }
  StandInDecoder(const StandInDecoder&) = delete;
  StandInDecoder& operator=(const StandInDecoder&) = delete;

  int send(const AVPacket* packet) override {
    if (packet == nullptr) ended_ = true;
    return avcodec_send_packet(ctx_, packet);
  }
  int receive(AVFrame* out) override {
    while (true) {
      AVFrame* f = av_frame_alloc();
      const int rc = avcodec_receive_frame(ctx_, f);
      if (rc < 0) {
        av_frame_free(&f);
        if (rc == AVERROR_EOF) break;
        if (rc != AVERROR(EAGAIN)) return rc;
        break;
      }
      if (f->pts == drop_pts_) {
        av_frame_free(&f);
        continue;
      }
      ready_.push_back(f);
    }
    if (ready_.empty()) return ended_ ? AVERROR_EOF : AVERROR(EAGAIN);
    std::size_t pick = 0;
    if (ready_[0]->pts == swap_pts_ && !swapped_) {
      if (ready_.size() < 2) return ended_ ? take(0, out) : AVERROR(EAGAIN);  // hold it back
      pick = 1;
      swapped_ = true;
    }
    return take(pick, out);
  }

 private:
  int take(std::size_t index, AVFrame* out) {
    AVFrame* f = ready_[index];
    ready_.erase(ready_.begin() + static_cast<std::ptrdiff_t>(index));
    av_frame_move_ref(out, f);
    av_frame_free(&f);
    return 0;
  }
  AVCodecContext* ctx_ = nullptr;
  std::deque<AVFrame*> ready_;
  std::int64_t swap_pts_, drop_pts_;
  bool ended_ = false;
  bool swapped_ = false;
};

DecoderOptions softwareOptions() {
  DecoderOptions options;
  options.kind = DecoderKind::kSoftware;
  options.log_choice = false;
  options.export_qp = true;  // the quantisers travel with the vectors too
  return options;
}

void checkSame(const DecodedFrame& got, const Reference& want) {
  CHECK(got.motion.pictureType() == want.type);
  REQUIRE(got.luma.width() == want.luma.width());
  bool same_pixels = true;
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) same_pixels = same_pixels && got.luma(x, y) == want.luma(x, y);
  CHECK(same_pixels);
  const auto blocks = got.motion.blocks();
  REQUIRE(blocks.size() == want.blocks.size());
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    CHECK(blocks[i].x == want.blocks[i].x);
    CHECK(blocks[i].y == want.blocks[i].y);
    CHECK(blocks[i].dx == want.blocks[i].dx);
    CHECK(blocks[i].dy == want.blocks[i].dy);
    CHECK(blocks[i].qp == want.blocks[i].qp);
  }
  // The stand-in's pixels carry no side data: the quantisers come from the software parse.
  CHECK(got.motion.hasQp());
  CHECK(got.motion.qpAt(kWidth / 2, kHeight / 2) == want.centre_qp);
}

}  // namespace

TEST_CASE("hardware pixels get the vectors of their own packet when the device reorders and drops") {
  const Encoded encoded = encodeSequence();
  std::map<std::int64_t, Reference> reference;
  {
    VideoDecoder software(encoded.stream, softwareOptions());
    for (const DecodedFrame& f : decodeAll(software, encoded.packets)) {
      reference[f.pts] = Reference{f.luma,
                                   {f.motion.blocks().begin(), f.motion.blocks().end()},
                                   f.motion.pictureType(),
                                   f.motion.qpAt(kWidth / 2, kHeight / 2)};
    }
  }
  REQUIRE(reference.size() == static_cast<std::size_t>(kFrames));
  // Every picture, I-frames included, has its quantisers, in H.264's range.
  for (const auto& [pts, ref] : reference) CHECK((ref.centre_qp >= 0 && ref.centre_qp <= 51));

  constexpr std::int64_t kSwap = 4, kDrop = 9;
  VideoDecoder paired(encoded.stream, softwareOptions(), std::make_unique<StandInDecoder>(kSwap, kDrop), "stand-in");
  const std::vector<DecodedFrame> frames = decodeAll(paired, encoded.packets);

  std::vector<std::int64_t> order;
  for (const DecodedFrame& f : frames) order.push_back(f.pts);
  std::vector<std::int64_t> expected;
  for (std::int64_t i = 0; i < kFrames; ++i) {
    if (i == kDrop) continue;
    expected.push_back(i);
  }
  std::swap(expected[kSwap], expected[kSwap + 1]);
  CHECK(order == expected);
  for (const DecodedFrame& f : frames) {
    INFO("pts " << f.pts);
    // Motion-carrying P-frames make a pairing mistake visible: neighbours' vectors differ.
    checkSame(f, reference.at(f.pts));
  }
  // The dropped picture's vectors were given up once later pictures had come out; nothing else was.
  CHECK(paired.pixelFramesDropped() == 1);
}

TEST_CASE("the V4L2 M2M probe accepts codec nodes by capabilities, not any /dev/video*") {
  using platform::fourcc;
  using platform::isM2mCodec;
  using platform::M2mRole;
  const std::uint32_t h264 = fourcc("H264");
  CHECK(h264 == V4L2_PIX_FMT_H264);
  CHECK(fourcc("MPG4") == V4L2_PIX_FMT_MPEG4);
  CHECK(fourcc("MPG2") == V4L2_PIX_FMT_MPEG2);

  platform::V4l2NodeCaps webcam;  // a UVC camera: capture only, compressed MJPEG and even H.264 out
  webcam.capabilities = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
  webcam.capture_formats = {fourcc("MJPG"), h264};
  CHECK_FALSE(isM2mCodec(webcam, M2mRole::kDecoder, h264));
  CHECK_FALSE(isM2mCodec(webcam, M2mRole::kEncoder, h264));

  platform::V4l2NodeCaps decoder;  // e.g. a stateful decoder: H.264 in on OUTPUT, NV12 out
  decoder.capabilities = V4L2_CAP_VIDEO_M2M_MPLANE | V4L2_CAP_STREAMING;
  decoder.output_formats = {h264, fourcc("VP80")};
  CHECK(isM2mCodec(decoder, M2mRole::kDecoder, h264));
  CHECK_FALSE(isM2mCodec(decoder, M2mRole::kEncoder, h264));
  CHECK_FALSE(isM2mCodec(decoder, M2mRole::kDecoder, fourcc("MPG2")));

  platform::V4l2NodeCaps encoder;  // single-planar M2M encoder: raw in, H.264 out on CAPTURE
  encoder.capabilities = V4L2_CAP_VIDEO_M2M | V4L2_CAP_STREAMING;
  encoder.capture_formats = {h264};
  CHECK(isM2mCodec(encoder, M2mRole::kEncoder, h264));
  CHECK_FALSE(isM2mCodec(encoder, M2mRole::kDecoder, h264));

  platform::V4l2NodeCaps scaler;  // an M2M scaler / ISP: no compressed formats at all
  scaler.capabilities = V4L2_CAP_VIDEO_M2M_MPLANE;
  CHECK_FALSE(isM2mCodec(scaler, M2mRole::kDecoder, h264));

  // On this machine: whatever the scan finds really is an M2M codec node (usually nothing).
  for (const std::string& node : platform::findM2mCodecNodes(M2mRole::kDecoder, h264)) {
    platform::V4l2NodeCaps caps;
    REQUIRE(platform::queryV4l2Node(node, caps));
    CHECK(isM2mCodec(caps, M2mRole::kDecoder, h264));
  }
}
