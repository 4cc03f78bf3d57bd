#include "drivers/decode/video_decoder.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "drivers/decode/codec_contexts.h"
#include "drivers/decode/picture_pool.h"
#include "drivers/ffmpeg/av_objects.h"
#include "voca/core/error.h"

extern "C" {
#include <libavutil/hwcontext.h>
#include <libavutil/motion_vector.h>
#include <libavutil/pixdesc.h>
#include <libavutil/video_enc_params.h>
}

namespace voca::decode {

using ffmpeg::avErrorText;

namespace {

using ffmpeg::BufferPtr;
using ffmpeg::CodecContextPtr;
using ffmpeg::FramePtr;
using ffmpeg::PacketPtr;

// The MV parse runs ahead of a hardware decoder by that decoder's internal queue depth.
constexpr std::size_t kMotionQueueDepth = 32;
// Parsed vectors whose picture has not come out after this many later pictures did were dropped by
// the device (a hardware decoder reorders within its few output buffers, never further).
constexpr int kMaxPixelReorder = 8;

// A libavcodec context as the pixel decoder (software, VAAPI or V4L2 M2M).
class CodecPixelDecoder final : public PixelDecoder {
 public:
  explicit CodecPixelDecoder(CodecContextPtr ctx) : ctx_(std::move(ctx)) {}
  int send(const AVPacket* packet) override { return avcodec_send_packet(ctx_.get(), packet); }
  int receive(AVFrame* frame) override { return avcodec_receive_frame(ctx_.get(), frame); }
  const AVCodecContext* context() const { return ctx_.get(); }

 private:
  CodecContextPtr ctx_;
};

void logChoiceOnce(const std::string& line) {
  static std::mutex mutex;
  static std::vector<std::string> logged;
  const std::lock_guard<std::mutex> lock(mutex);
  if (std::find(logged.begin(), logged.end(), line) != logged.end()) return;
  logged.push_back(line);
  std::fprintf(stderr, "%s\n", line.c_str());
}

PictureType pictureType(AVPictureType type) {
  switch (type) {
    case AV_PICTURE_TYPE_I:
    case AV_PICTURE_TYPE_SI:
      return PictureType::kI;
    case AV_PICTURE_TYPE_P:
    case AV_PICTURE_TYPE_SP:
      return PictureType::kP;
    case AV_PICTURE_TYPE_B:
      return PictureType::kB;
    default:
      return PictureType::kUnknown;
  }
}

// The per-macroblock quantiser of a decoded picture (AV_FRAME_DATA_VIDEO_ENC_PARAMS) into `motion`.
// H.264 and the MPEG-2-style codecs give each block's final quantiser as the frame value plus the
// block's delta; other types (VP9's segment deltas) mean something else and are left out.
void readQp(const AVFrame& frame, MotionField& motion) {
  const AVFrameSideData* side = av_frame_get_side_data(&frame, AV_FRAME_DATA_VIDEO_ENC_PARAMS);
  if (side == nullptr || side->size < sizeof(AVVideoEncParams)) return;
  auto* params = reinterpret_cast<AVVideoEncParams*>(side->data);
  if (params->type != AV_VIDEO_ENC_PARAMS_H264 && params->type != AV_VIDEO_ENC_PARAMS_MPEG2) return;
  // The block array must lie inside the side data (av_video_enc_params_block does not check).
  if (params->nb_blocks == 0 || params->block_size < sizeof(AVVideoBlockParams) || params->blocks_offset > side->size ||
      (side->size - params->blocks_offset) / params->block_size < params->nb_blocks) {
    return;
  }
  for (unsigned int i = 0; i < params->nb_blocks; ++i) {
    const AVVideoBlockParams* block = av_video_enc_params_block(params, i);
    const std::int64_t qp = std::int64_t{params->qp} + block->delta_qp;
    if (qp >= 0 && qp <= INT16_MAX) motion.setQp(block->src_x, block->src_y, block->w, block->h, static_cast<int>(qp));
  }
}

}  // namespace

void DecodedFrame::reserve(int max_width, int max_height) {
  luma.reserve(max_width, max_height);
  if (motion.maxWidth() < max_width || motion.maxHeight() < max_height) motion = MotionField(max_width, max_height);
}

struct VideoDecoder::Impl {
  StreamInfo stream;
  DecoderOptions options;
  std::string source;
  DecoderChoice choice;
  // Picture memory of the software contexts (declared before them: a context must not outlive its pool).
  std::unique_ptr<PicturePool> pixel_pool, motion_pool;
  const AVCodecContext* pixel_context = nullptr;  // the libavcodec pixel decoder, if pixel is one
  std::unique_ptr<PixelDecoder> pixel;            // produces the output frames (software, or the hardware decoder)
  CodecContextPtr motion;                         // hardware decoders only: software parse for the motion vectors
  BufferPtr hw_device;
  FramePtr frame, transfer;
  PacketPtr packet;
  // Parsed MV frames waiting for their pixels, matched by pts (a fixed set of slots: no allocation).
  struct MotionSlot {
    FramePtr frame;
    bool waiting = false;
    std::int64_t arrival = 0;  // parse order, for pictures without pts
    int passed = 0;            // later pictures that came out before this one
  };
  std::vector<MotionSlot> motion_slots;
  std::size_t motion_waiting = 0;
  std::int64_t motion_parsed = 0;
  std::int64_t pixel_dropped = 0;
  std::int64_t frames_out = 0;
  std::int64_t last_packet = -1;
  bool format_checked = false;

  // What both constructors do first: the stream, options and name, the codec check, the buffers.
  void init(const StreamInfo& stream_info, const DecoderOptions& decoder_options, std::string source_name) {
    stream = stream_info;
    options = decoder_options;
    source = std::move(source_name);
    if (stream.codec == VideoCodec::kOther) {
      throw InputError(source + ": codec '" + stream.codec_name + "' is not supported (H.264, MPEG-4 Part 2, MPEG-2)");
    }
    frame.reset(av_frame_alloc());
    transfer.reset(av_frame_alloc());
    packet.reset(av_packet_alloc());
    if (!frame || !transfer || !packet) throw RuntimeFailure("out of memory allocating decoder buffers");
  }
  detail::DecoderSetup setup() const { return {stream, options, source}; }
  void open(DecoderKind kind);
  // True when the decoder refused the packet's data as corrupt; throws for any other failure.
  bool refused(int rc, const AVPacket* pkt, std::int64_t index) const;
  // Feeds pkt (nullptr: the end) to the motion parse and the pixel decoder: 0, or the corrupt-data
  // code of the one that refused it.
  int feed(const AVPacket* pkt, std::int64_t index);
  void drainMotion();
  void allocMotionSlots();
  PicturePool& newPixelPool() {
    // Impl::frame keeps the picture last received until the next receive().
    pixel_pool = std::make_unique<PicturePool>(1);
    return *pixel_pool;
  }
  void usePixel(CodecContextPtr ctx) {
    auto decoder = std::make_unique<CodecPixelDecoder>(std::move(ctx));
    pixel_context = decoder->context();
    pixel = std::move(decoder);
  }
  const AVFrame* takeMotionFor(const AVFrame& pixels);
  [[noreturn]] void fail(int rc, const std::string& what) const;
  int refusal = 0;  // the code of the last packet trySend() saw refused
  void convert(const AVFrame& pixels, const AVFrame& vectors, DecodedFrame& out);
  void refuseUnusableStructure(const AVFrame& parsed);
};

// The method needs a causal, progressive, single-reference stream of 8-bit 4:2:0 (or 4:0:0)
// pictures; anything else is refused by name rather than giving wrong priors silently:
//  - B-frames: output order differs from decode order and half the vectors point forward;
//  - more than one reference frame: AVMotionVector::source says only "past", not which past
//    frame, so a vector to frame t-2 would be read as one-frame motion;
//  - interlaced or field pictures: a vector spans a field, half a frame's rows;
//  - other bit depths or chroma layouts: the pixel path copies an 8-bit luma plane.
// `parsed` is the software parse of the picture (the same frame for software decoding).
void VideoDecoder::Impl::refuseUnusableStructure(const AVFrame& parsed) {
  if (!motion && pixel_context == nullptr) return;  // an external pixel decoder with no parse beside it
  const AVCodecContext& ctx = motion ? *motion : *pixel_context;
  if (parsed.pict_type == AV_PICTURE_TYPE_B) {
    throw InputError(source + ": frame " + std::to_string(frames_out) +
                     " is a B-frame; VOCA needs a causal stream without B-frames (x264: bframes=0)");
  }
  // Every stage and buffer is sized from the stream's header; a raw stream can switch to another
  // SPS mid-way. Checked on software frames only (a hardware wrapper may report aligned sizes)
  // and when the stream has a header size (a live source may not).
  if ((motion || choice.kind == DecoderKind::kSoftware) && stream.width > 0 &&
      (parsed.width != stream.width || parsed.height != stream.height)) {
    throw InputError(source + ": frame " + std::to_string(frames_out) + " is " + std::to_string(parsed.width) + "x" +
                     std::to_string(parsed.height) + " but the stream starts at " + std::to_string(stream.width) + "x" +
                     std::to_string(stream.height) + "; a size change within a video is not supported");
  }
  if (parsed.interlaced_frame != 0) {
    throw InputError(source + ": frame " + std::to_string(frames_out) +
                     " is interlaced (field or MBAFF coding); VOCA needs progressive frames");
  }
  if (format_checked) return;
  format_checked = true;
  if (stream.codec == VideoCodec::kH264) {
    if (ctx.has_b_frames > 0) {
      throw InputError(source + ": the stream reorders frames (B-frames, reorder depth " +
                       std::to_string(ctx.has_b_frames) + "); VOCA needs a causal stream (x264: bframes=0)");
    }
    if (ctx.refs > 1) {
      throw InputError(source + ": the stream uses up to " + std::to_string(ctx.refs) +
                       " reference frames; VOCA needs one (x264: ref=1), since a motion vector does not say "
                       "which past frame it points to");
    }
  }
  const auto format = static_cast<AVPixelFormat>(parsed.format);
  const AVPixFmtDescriptor* desc = av_pix_fmt_desc_get(format);
  if (desc != nullptr && (desc->flags & AV_PIX_FMT_FLAG_HWACCEL) != 0) desc = av_pix_fmt_desc_get(ctx.sw_pix_fmt);
  if (desc == nullptr) return;  // a hardware wrapper that does not say; its pixels are checked in convert()
  const bool eight_bit = desc->comp[0].depth == 8;
  const bool gray = desc->nb_components == 1;
  const bool chroma_420 = desc->nb_components >= 3 && desc->log2_chroma_w == 1 && desc->log2_chroma_h == 1;
  if ((desc->flags & (AV_PIX_FMT_FLAG_RGB | AV_PIX_FMT_FLAG_PAL)) != 0 || !eight_bit || !(gray || chroma_420)) {
    const char* layout = gray                                                   ? "4:0:0"
                         : desc->log2_chroma_w == 1 && desc->log2_chroma_h == 1 ? "4:2:0"
                         : desc->log2_chroma_w == 1 && desc->log2_chroma_h == 0 ? "4:2:2"
                         : desc->log2_chroma_w == 0 && desc->log2_chroma_h == 0 ? "4:4:4"
                                                                                : "other chroma layout";
    throw InputError(source + ": pixel format " + desc->name + " (" + std::to_string(desc->comp[0].depth) + "-bit " +
                     layout + "); VOCA needs 8-bit 4:2:0 (or 4:0:0 gray) video");
  }
}

namespace {

// The packet's data, not the decoder, is at fault.
bool isCorruptData(int rc) { return rc == AVERROR_INVALIDDATA || rc == AVERROR_BUG || rc == AVERROR_PATCHWELCOME; }

}  // namespace

void VideoDecoder::Impl::fail(int rc, const std::string& what) const {
  if (isCorruptData(rc)) {
    throw InputError(source + ": corrupt bitstream " + what + " (" + avErrorText(rc) + ")");
  }
  throw RuntimeFailure(source + ": decoder failure " + what + " (" + avErrorText(rc) + ")");
}

void VideoDecoder::Impl::open(DecoderKind kind) {
  pixel.reset();
  pixel_context = nullptr;
  motion.reset();
  hw_device.reset();
  pixel_pool.reset();
  motion_pool.reset();
  if (!options.decode_pixels) {
    // An MV-only parse is software by nature: hardware would make pixels nobody reads.
    usePixel(detail::openSoftwareDecoder(setup(), true, newPixelPool()));
    return;
  }
  switch (kind) {
    case DecoderKind::kVaapi:
      usePixel(detail::openVaapiDecoder(setup(), hw_device));
      break;
    case DecoderKind::kV4l2m2m:
      usePixel(detail::openV4l2m2mDecoder(setup()));
      break;
    default:
      usePixel(detail::openSoftwareDecoder(setup(), false, newPixelPool()));
      return;
  }
  if (options.export_motion) allocMotionSlots();
}

void VideoDecoder::Impl::allocMotionSlots() {
  // The parsed frames waiting in the slots keep no picture (drainMotion releases it).
  motion_pool = std::make_unique<PicturePool>(0);
  motion = detail::openSoftwareDecoder(setup(), true, *motion_pool);
  motion_slots.clear();
  motion_slots.resize(kMotionQueueDepth);
  for (MotionSlot& slot : motion_slots) {
    slot.frame.reset(av_frame_alloc());
    if (!slot.frame) throw RuntimeFailure("out of memory allocating frames");
  }
  motion_waiting = 0;
}

VideoDecoder::VideoDecoder(const StreamInfo& stream, const DecoderOptions& options, const DecoderProbe* probe,
                           std::string source_name)
    : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.init(stream, options, std::move(source_name));

  if (!options.decode_pixels) {
    d.choice.kind = DecoderKind::kSoftware;
    d.choice.description = "decoder: software (MV-only parse)";
  } else {
    const DecoderProbe system = probe == nullptr ? systemDecoderProbe() : DecoderProbe{};
    d.choice = selectDecoderKind(options.kind, stream.codec, options.vaapi_device, options.export_motion,
                                 probe == nullptr ? system : *probe);
  }
  try {
    d.open(d.choice.kind);
  } catch (const RuntimeFailure& e) {
    // The probe said yes but opening failed after all: auto mode still falls back to software.
    if (options.kind != DecoderKind::kAuto || d.choice.kind == DecoderKind::kSoftware) throw;
    d.choice.notes.push_back(e.what());
    d.choice.kind = DecoderKind::kSoftware;
    d.choice.description = describeDecoder(DecoderKind::kSoftware, options.export_motion);
    d.open(DecoderKind::kSoftware);
  }
  if (options.log_choice) logChoiceOnce(d.choice.description);
}

VideoDecoder::VideoDecoder(const StreamInfo& stream, const DecoderOptions& options,
                           std::unique_ptr<PixelDecoder> pixels, std::string source_name)
    : impl_(std::make_unique<Impl>()) {
  if (!pixels) throw std::invalid_argument("VideoDecoder: null pixel decoder");
  Impl& d = *impl_;
  d.init(stream, options, std::move(source_name));
  d.options.decode_pixels = true;
  // Reported as hardware: that is what the stand-in stands for.
  d.choice.kind = options.kind == DecoderKind::kAuto || options.kind == DecoderKind::kSoftware ? DecoderKind::kV4l2m2m
                                                                                               : options.kind;
  d.choice.description =
      std::string("decoder: external pixel decoder") + (options.export_motion ? " (+ software MV parse)" : "");
  d.pixel = std::move(pixels);
  if (options.export_motion) d.allocMotionSlots();
}

VideoDecoder::~VideoDecoder() = default;

std::int64_t VideoDecoder::pixelFramesDropped() const { return impl_->pixel_dropped; }

std::int64_t VideoDecoder::picturesAllocated() const {
  const Impl& d = *impl_;
  const bool pooled = d.pixel_pool && d.pixel_context != nullptr && d.pixel_context->opaque == d.pixel_pool.get();
  return pooled ? d.pixel_pool->allocated() : -1;
}

DecoderKind VideoDecoder::kind() const { return impl_->choice.kind; }
const std::string& VideoDecoder::description() const { return impl_->choice.description; }
const StreamInfo& VideoDecoder::stream() const { return impl_->stream; }

bool VideoDecoder::Impl::refused(int rc, const AVPacket* pkt, std::int64_t index) const {
  if (rc == 0 || rc == AVERROR_EOF) return false;
  if (rc == AVERROR(EAGAIN)) {
    throw RuntimeFailure(source + ": decoder refused packet " + std::to_string(index) +
                         " (frames were not drained with receive())");
  }
  if (isCorruptData(rc)) return true;
  fail(rc, pkt == nullptr ? std::string("while flushing") : "in packet " + std::to_string(index));
}

int VideoDecoder::Impl::feed(const AVPacket* pkt, std::int64_t index) {
  if (motion) {
    drainMotion();
    const int rc = avcodec_send_packet(motion.get(), pkt);
    if (refused(rc, pkt, index)) return rc;
    drainMotion();
  }
  const int rc = pixel->send(pkt);
  return refused(rc, pkt, index) ? rc : 0;
}

void VideoDecoder::Impl::drainMotion() {
  while (true) {
    auto free_slot =
        std::find_if(motion_slots.begin(), motion_slots.end(), [](const MotionSlot& s) { return !s.waiting; });
    if (free_slot == motion_slots.end()) {
      throw RuntimeFailure(source + ": the hardware decoder fell more than " + std::to_string(kMotionQueueDepth) +
                           " frames behind the motion-vector parse");
    }
    AVFrame* slot = free_slot->frame.get();
    av_frame_unref(slot);
    const int rc = avcodec_receive_frame(motion.get(), slot);
    if (rc == AVERROR(EAGAIN) || rc == AVERROR_EOF) return;
    if (rc < 0) fail(rc, "in the motion-vector parse near packet " + std::to_string(last_packet));
    // Only the vectors and the picture's properties are read from a slot: its planes go back to the
    // pool now, so the decoder's picture memory does not depend on how far the device lags.
    for (AVBufferRef*& plane : slot->buf) av_buffer_unref(&plane);
    std::fill(std::begin(slot->data), std::end(slot->data), nullptr);
    free_slot->waiting = true;
    free_slot->arrival = motion_parsed++;
    free_slot->passed = 0;
    ++motion_waiting;
  }
}

// The parsed vectors of the picture `pixels`: the waiting slot with its pts (the oldest one when the
// device gives no pts). Slots passed over by more than kMaxPixelReorder later pictures are given up
// as pictures the device dropped. The returned frame stays valid until the next drainMotion().
const AVFrame* VideoDecoder::Impl::takeMotionFor(const AVFrame& pixels) {
  if (motion_waiting == 0) drainMotion();
  MotionSlot* match = nullptr;
  for (MotionSlot& slot : motion_slots) {
    if (!slot.waiting) continue;
    const bool by_order = pixels.pts == AV_NOPTS_VALUE || slot.frame->pts == AV_NOPTS_VALUE;
    if (by_order ? (match == nullptr || slot.arrival < match->arrival) : slot.frame->pts == pixels.pts) match = &slot;
  }
  if (match == nullptr) {
    throw RuntimeFailure(source + ": frame " + std::to_string(frames_out) +
                         ": no motion-vector parse for its pts (hardware and software decoders out of step)");
  }
  match->waiting = false;
  --motion_waiting;
  for (MotionSlot& slot : motion_slots) {
    if (!slot.waiting || slot.arrival > match->arrival) continue;
    if (++slot.passed > kMaxPixelReorder) {
      slot.waiting = false;
      --motion_waiting;
      ++pixel_dropped;
    }
  }
  return match->frame.get();
}

void VideoDecoder::send(const Packet& packet) {
  if (!trySend(packet)) impl_->fail(impl_->refusal, "in packet " + std::to_string(packet.index));
}

bool VideoDecoder::trySend(const Packet& packet) {
  Impl& d = *impl_;
  // An empty packet would mean "end of stream" to libavcodec; containers can carry empty samples.
  if (packet.bytes.empty()) return true;
  AVPacket* pkt = d.packet.get();
  av_packet_unref(pkt);
  // Not reference-counted: libavcodec copies the bytes into a padded buffer of its own.
  pkt->data = const_cast<std::uint8_t*>(packet.bytes.data());
  pkt->size = static_cast<int>(packet.bytes.size());
  pkt->pts = packet.pts == kNoPts ? AV_NOPTS_VALUE : packet.pts;
  pkt->dts = packet.dts == kNoPts ? AV_NOPTS_VALUE : packet.dts;
  pkt->flags = packet.keyframe ? AV_PKT_FLAG_KEY : 0;
  d.last_packet = packet.index;
  d.refusal = d.feed(pkt, packet.index);
  pkt->data = nullptr;
  pkt->size = 0;
  return d.refusal == 0;
}

void VideoDecoder::sendEnd() {
  Impl& d = *impl_;
  if (const int rc = d.feed(nullptr, d.last_packet + 1); rc != 0) d.fail(rc, "while flushing");
}

void VideoDecoder::Impl::convert(const AVFrame& pixels, const AVFrame& vectors, DecodedFrame& out) {
  const int width = pixels.width, height = pixels.height;
  // Hardware wrappers (V4L2 M2M) may not report the picture type; the software parse always does.
  const PictureType type = pictureType(&vectors != &pixels ? vectors.pict_type : pixels.pict_type);
  out.frame_index = frames_out;
  const std::int64_t pts = pixels.best_effort_timestamp != AV_NOPTS_VALUE ? pixels.best_effort_timestamp : pixels.pts;
  out.pts = pts == AV_NOPTS_VALUE ? kNoPts : pts;
  out.t_ns = out.pts == kNoPts ? 0
                               : av_rescale_q(out.pts, AVRational{stream.time_base_num, stream.time_base_den},
                                              AVRational{1, 1000000000});

  if (options.decode_pixels) {
    const AVFrame* plane = &pixels;
    if (pixels.format == AV_PIX_FMT_VAAPI) {
      av_frame_unref(transfer.get());
      const int rc = av_hwframe_transfer_data(transfer.get(), &pixels, 0);
      if (rc < 0) fail(rc, "transferring frame " + std::to_string(frames_out) + " from the GPU");
      plane = transfer.get();
    }
    const AVPixFmtDescriptor* desc = av_pix_fmt_desc_get(static_cast<AVPixelFormat>(plane->format));
    // Every planar/semi-planar YUV format starts with an 8-bit Y plane, which is all we need.
    if (desc == nullptr || (desc->flags & (AV_PIX_FMT_FLAG_HWACCEL | AV_PIX_FMT_FLAG_RGB | AV_PIX_FMT_FLAG_PAL)) != 0 ||
        desc->comp[0].depth != 8) {
      throw RuntimeFailure(source + ": decoder produced pixel format " +
                           (desc == nullptr ? std::string("?") : std::string(desc->name)) + ", expected 8-bit YUV");
    }
    out.luma.resize(width, height);
    for (int y = 0; y < height; ++y) {
      std::memcpy(out.luma.row(y), plane->data[0] + static_cast<std::ptrdiff_t>(y) * plane->linesize[0],
                  static_cast<std::size_t>(width));
    }
  } else {
    out.luma.resize(0, 0);
  }

  if (out.motion.maxWidth() < width || out.motion.maxHeight() < height) {
    out.motion = MotionField(std::max(width, stream.width), std::max(height, stream.height));
  }
  out.motion.reset(width, height, type);
  if (options.export_motion || !options.decode_pixels) {
    const AVFrameSideData* side = av_frame_get_side_data(&vectors, AV_FRAME_DATA_MOTION_VECTORS);
    if (side != nullptr) {
      const auto* mvs = reinterpret_cast<const AVMotionVector*>(side->data);
      const std::size_t count = side->size / sizeof(AVMotionVector);
      for (std::size_t i = 0; i < count; ++i) {
        const AVMotionVector& mv = mvs[i];
        if (mv.motion_scale == 0) continue;
        // dst is the block centre; the block's content came from dst + motion/scale in the
        // reference, so the forward flow is the negated vector (DESIGN.md section 4).
        const float scale = static_cast<float>(mv.motion_scale);
        out.motion.addBlock(mv.dst_x - mv.w / 2, mv.dst_y - mv.h / 2, mv.w, mv.h,
                            -static_cast<float>(mv.motion_x) / scale, -static_cast<float>(mv.motion_y) / scale,
                            mv.source < 0 ? RefDirection::kPast : RefDirection::kFuture);
      }
    }
    readQp(vectors, out.motion);
  }
  out.motion.finalize();
  ++frames_out;
}

bool VideoDecoder::receive(DecodedFrame& out) {
  Impl& d = *impl_;
  AVFrame* frame = d.frame.get();
  av_frame_unref(frame);
  const int rc = d.pixel->receive(frame);
  if (rc == AVERROR(EAGAIN) || rc == AVERROR_EOF) return false;
  if (rc < 0) d.fail(rc, "decoding frame " + std::to_string(d.frames_out));
  const bool damaged = frame->decode_error_flags != 0 || (frame->flags & AV_FRAME_FLAG_CORRUPT) != 0;
  if (d.options.strict && damaged) {
    throw InputError(d.source + ": frame " + std::to_string(d.frames_out) +
                     " is corrupt (damaged or missing bitstream data)");
  }
  const AVFrame* vectors = frame;
  if (d.motion) vectors = d.takeMotionFor(*frame);
  d.refuseUnusableStructure(*vectors);
  d.convert(*frame, *vectors, out);
  out.damaged = damaged;
  return true;
}

void silenceDamageMessages() { av_log_set_level(AV_LOG_FATAL); }

}  // namespace voca::decode
