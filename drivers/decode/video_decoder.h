#pragma once
// Compressed packets -> DecodedFrame (luma plane, timestamp, motion field with the picture type).

#include <cstdint>
#include <memory>
#include <string>

#include "drivers/decode/decoder_kind.h"
#include "drivers/decode/demuxer.h"
#include "drivers/decode/pixel_decoder.h"
#include "voca/core/image.h"
#include "voca/motion/motion_field.h"

namespace voca::decode {

// One decoded picture. Buffers are sized for the stream on first use and reused afterwards.
struct DecodedFrame {
  GrayImage luma;         // the Y plane as coded (no colour conversion); empty for an MV-only parse
  std::int64_t t_ns = 0;  // dataset timestamp when known (VideoReader), else pts in ns
  std::int64_t pts = kNoPts;
  std::int64_t frame_index = 0;  // output order, from 0
  MotionField motion;            // picture type always; empty (no vectors) when motion export is off
  // Non-strict decoding only: the decoder flagged the picture as damaged (missing or corrupt
  // bitstream data, concealed). Strict decoding throws instead.
  bool damaged = false;

  // Size the buffers so later frames of at most this size never allocate.
  void reserve(int max_width, int max_height);
};

struct DecoderOptions {
  DecoderKind kind = DecoderKind::kAuto;
  bool export_motion = true;
  // With the vectors, also each macroblock's quantiser (MotionField::qpAt; the frontend's
  // prior_max_qp). Off unless asked: FFmpeg then allocates its side data for every picture.
  bool export_qp = false;
  // false: parse only for the motion vectors (software, loop filter skipped, luma left empty).
  bool decode_pixels = true;
  // Software decoding: skip H.264's deblocking (in-loop) filter for the pixels too. About a fifth of
  // the decode time, but the pictures then differ from the encoder's and the difference drifts until
  // the next I-frame; the vectors stay exact. Off by default: opt in where the accuracy allows.
  bool skip_loop_filter = false;
  // Software decoding: skip the chroma planes (AV_CODEC_FLAG_GRAY) when libavcodec was built with
  // --enable-gray (lumaOnlyDecodingAvailable). VOCA reads only the luma plane, which H.264 decodes
  // from luma alone, so the pictures it sees are the same; about a tenth of the decode time.
  bool luma_only = true;
  std::string vaapi_device = "/dev/dri/renderD128";
  // Corrupt bitstream data is an error naming the frame instead of being concealed.
  bool strict = true;
  bool log_choice = true;  // print the chosen decoder to stderr (once per process and description)
};

// Whether this libavcodec can skip the chroma planes (configured with --enable-gray; Debian's is not).
bool lumaOnlyDecodingAvailable();

// Decodes one video stream on the calling thread. Software decoding uses one thread and no frame
// threading (frame threading adds a frame of latency and reorders side data); hardware decoders
// decode the pixels while a software context parses the same packets for the motion vectors; each
// picture is paired with its vectors by pts, so a device that returns pictures out of order or drops
// one still gets the right vectors on every picture it returns.
// Errors throw voca::InputError (corrupt data, naming the packet/frame) or voca::RuntimeFailure.
class VideoDecoder {
 public:
  // probe: how to discover devices; nullptr = systemDecoderProbe(). source_name appears in errors.
  VideoDecoder(const StreamInfo& stream, const DecoderOptions& options, const DecoderProbe* probe = nullptr,
               std::string source_name = "video");
  // Pixels from `pixels` (standing in for a hardware decoder: tests, or a device libavcodec does not
  // wrap), vectors from a software parse of the same packets, paired by pts as for VAAPI / V4L2 M2M.
  VideoDecoder(const StreamInfo& stream, const DecoderOptions& options, std::unique_ptr<PixelDecoder> pixels,
               std::string source_name);
  ~VideoDecoder();
  VideoDecoder(const VideoDecoder&) = delete;
  VideoDecoder& operator=(const VideoDecoder&) = delete;

  // Feeds one packet (decode order). Call receive() until it returns false after each send.
  void send(const Packet& packet);
  // send() for a stream expected to carry damage: a packet the decoder refuses as corrupt returns
  // false (the frame is lost) instead of throwing, and allocates nothing. Other failures still throw.
  bool trySend(const Packet& packet);
  // Signals the end of the stream; receive() then drains the frames held back.
  void sendEnd();
  // The next decoded frame, or false when none is ready (or the stream has ended).
  bool receive(DecodedFrame& frame);

  DecoderKind kind() const;
  // Hardware decoders: pictures the pixel decoder never returned (their vectors were parsed, then
  // given up once later pictures had come out); the frame is missing from the output, not wrong.
  std::int64_t pixelFramesDropped() const;
  // Software decoding: picture buffers allocated for the decoder. They are allocated at its first
  // picture, as many as its stream's headers let it hold at once; a count rising after that means it
  // held more, and its memory grew. -1 when libavcodec allocates them (hardware decoders).
  std::int64_t picturesAllocated() const;
  const std::string& description() const;  // "decoder: software", "decoder: vaapi (+ software MV parse)"
  const StreamInfo& stream() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Turns off libavcodec's messages about damaged data ("error while decoding MB ..."), several per
// damaged picture, for the rest of the process: for runs that damage streams on purpose and count
// the damaged frames instead. Only fatal messages remain.
void silenceDamageMessages();

}  // namespace voca::decode
