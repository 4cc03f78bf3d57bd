// libavcodec encoder for gray frames.

#include "drivers/encode/video_encoder.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <system_error>

#include <fmt/core.h>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/error.h>
#include <libavutil/hwcontext.h>
#include <libavutil/log.h>
#include <libavutil/mem.h>
#include <libavutil/opt.h>
}

#include "drivers/ffmpeg/av_objects.h"
#include "platform/filesystem/temp_dir.h"
#include "platform/process/child_process.h"
#include "voca/core/error.h"

namespace voca::encode {

namespace {

constexpr std::array<std::string_view, 5> kSupportedCodecs = {"libx264", "mpeg4", "mpeg2video", "h264_v4l2m2m",
                                                              "h264_vaapi"};

using ffmpeg::avErrorText;
using ffmpeg::BufferPtr;
using ffmpeg::CodecContextPtr;
using ffmpeg::FramePtr;
using ffmpeg::PacketPtr;

std::string readWholeFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw RuntimeFailure(fmt::format("cannot read the first-pass statistics {}", path.string()));
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// x264's AVX-512 routines (Debian 12's build, 0.164) read memory they have not written: the first
// video a process encodes comes out the same every run (fresh pages are zero), a second one does
// not (the heap holds earlier data, pointers included, which vary with address randomisation). On
// a CPU with AVX-512 we therefore run x264 with its AVX2-level routines, every one of which such a
// CPU has; the user's own "asm" setting wins. Measured on micro EuRoC: 6 runs encoding both
// cameras gave 5 different cam1 videos before; after, 6 identical ones, the same bytes as a run in
// which x264 found no AVX-512 itself (under valgrind).
std::string withReproducibleX264Asm(const std::string& params) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  if (params.find("asm") == std::string::npos && __builtin_cpu_supports("avx512f")) {
    const std::string avx2_level =
        "asm=MMX2,SSE,SSE2,SSE2Fast,SSE3,SSSE3,SSE4.1,SSE4.2,AVX,FMA3,BMI1,BMI2,AVX2,LZCNT,Cache64";
    return params.empty() ? avx2_level : params + ":" + avx2_level;
  }
#endif
  return params;
}

// Gray has no colour: chroma at 128 in every chroma plane (U and V planes of yuv420p, or the
// interleaved UV plane of nv12, which is as wide as the luma in bytes).
void fillNeutralChroma(AVFrame& frame) {
  if (frame.format != AV_PIX_FMT_NV12 && frame.format != AV_PIX_FMT_YUV420P) return;  // gray: no chroma
  const bool interleaved = frame.format == AV_PIX_FMT_NV12;
  const int planes = interleaved ? 2 : 3;
  const int chroma_width = (frame.width + 1) / 2;
  const int chroma_bytes = interleaved ? 2 * chroma_width : chroma_width;
  for (int plane = 1; plane < planes; ++plane) {
    for (int y = 0; y < (frame.height + 1) / 2; ++y) {
      std::memset(frame.data[plane] + static_cast<std::ptrdiff_t>(y) * frame.linesize[plane], 128,
                  static_cast<std::size_t>(chroma_bytes));
    }
  }
}

}  // namespace

bool isHardwareEncoder(std::string_view codec) { return codec == "h264_v4l2m2m" || codec == "h264_vaapi"; }

namespace {

BufferPtr createVaapiDevice(const std::string& device) {
  AVBufferRef* ref = nullptr;
  if (const int r = av_hwdevice_ctx_create(&ref, AV_HWDEVICE_TYPE_VAAPI, device.c_str(), nullptr, 0); r < 0) {
    throw RuntimeFailure(fmt::format("cannot open the VAAPI device {}: {}", device, avErrorText(r)));
  }
  return BufferPtr(ref);
}

// The pool of GPU surfaces the encoder reads: nv12 in memory, a few in flight.
BufferPtr createVaapiFrames(AVBufferRef* device, int width, int height) {
  BufferPtr frames(av_hwframe_ctx_alloc(device));
  if (!frames) throw RuntimeFailure("out of memory allocating VAAPI frames");
  auto* desc = reinterpret_cast<AVHWFramesContext*>(frames->data);
  desc->format = AV_PIX_FMT_VAAPI;
  desc->sw_format = AV_PIX_FMT_NV12;
  desc->width = width;
  desc->height = height;
  desc->initial_pool_size = 8;
  if (const int r = av_hwframe_ctx_init(frames.get()); r < 0) {
    throw RuntimeFailure(fmt::format("cannot create {}x{} VAAPI surfaces: {}", width, height, avErrorText(r)));
  }
  return frames;
}

// libavcodec 5.1's mpegvideo encoders (mpeg4, mpeg2video) free their rate-control state twice when
// the second pass cannot reach the bitrate (init_pass2 fails: the first pass's headers and vectors
// alone exceed it, or no quantiser gets below it), which corrupts the heap and aborts the process.
// So the second pass is opened in a forked copy first; a refusal there becomes an InputError here,
// with libavcodec's own reason.
void checkSecondPassOpens(AVCodecContext* ctx, const AVCodec* codec, const EncoderSettings& settings) {
  const platform::ForkedRun trial = platform::runForked([&] {
    av_log_set_level(AV_LOG_ERROR);
    return avcodec_open2(ctx, codec, nullptr) < 0 ? 1 : 0;
  });
  if (trial.exit.succeeded()) return;
  // libavcodec's messages ("[mpeg2video @ 0x...] requested bitrate is too low"), without the heap
  // checker's report that may follow them.
  std::string reason;
  std::istringstream lines(trial.output);
  for (std::string line; std::getline(lines, line);) {
    if (line.empty() || line.front() != '[') continue;
    const std::size_t tag_end = line.find("] ");
    reason +=
        fmt::format("{}{}", reason.empty() ? "" : "; ", tag_end == std::string::npos ? line : line.substr(tag_end + 2));
  }
  if (reason.empty()) reason = platform::describeExit(trial.exit);
  throw InputError(
      fmt::format("the {} encoder cannot reach {} bit/s on this video in two passes ({}); raise the "
                  "bitrate or encode in one pass",
                  settings.codec, settings.bitrate_bps, reason));
}

}  // namespace

void silenceCodecLogs() { av_log_set_level(AV_LOG_ERROR); }

std::int64_t parseBitrate(std::string_view text) {
  const auto bad = [&] {
    return InputError(
        fmt::format("bitrate '{}': expected a positive number of bits per second, optionally with "
                    "a k or M suffix (e.g. 500k, 1M, 1000000)",
                    text));
  };
  if (text.empty()) throw bad();
  double scale = 1.0;
  std::string_view number = text;
  const char suffix = text.back();
  if (suffix == 'k' || suffix == 'K') {
    scale = 1e3;
    number.remove_suffix(1);
  } else if (suffix == 'm' || suffix == 'M') {
    scale = 1e6;
    number.remove_suffix(1);
  }
  // Digits with at most one decimal point; no signs, exponents or spaces.
  if (number.empty() || std::count(number.begin(), number.end(), '.') > 1 ||
      !std::all_of(number.begin(), number.end(), [](char c) { return (c >= '0' && c <= '9') || c == '.'; }) ||
      number == ".") {
    throw bad();
  }
  const double value = std::stod(std::string(number)) * scale;
  // Below 1 kbit/s no codec can hold a frame; above 10 Gbit/s it is surely a typo.
  if (!(value >= 1000.0 && value <= 1e10)) {
    throw InputError(fmt::format("bitrate '{}' = {} bit/s is outside 1k..10000M", text, value));
  }
  return static_cast<std::int64_t>(std::llround(value));
}

std::string bitrateLabel(std::int64_t bps) {
  if (bps % 1000 == 0) return fmt::format("{}k", bps / 1000);
  return fmt::format("{}", bps);
}

struct VideoEncoder::Impl {
  EncoderSettings settings;
  EncoderPass pass = EncoderPass::kSingle;
  std::filesystem::path stats_file;
  std::string stats;  // mpeg4/mpeg2video first pass: accumulated rate-control lines
  CodecContextPtr ctx;
  FramePtr frame;     // the gray frame in the codec's software format
  FramePtr hw_frame;  // VAAPI: the GPU surface frame is uploaded to
  BufferPtr hw_device, hw_frames;
  PacketPtr packet;
  int input_width = 0, input_height = 0;
  std::vector<EncodedPacket> packets;  // grows to the largest burst, then reused
  std::size_t num_packets = 0;
  bool flushed = false;

  void drain() {
    while (true) {
      const int ret = avcodec_receive_packet(ctx.get(), packet.get());
      if (ret == AVERROR(EAGAIN) || ret == AVERROR_EOF) break;
      if (ret < 0) throw RuntimeFailure(fmt::format("{} encoder failed: {}", settings.codec, avErrorText(ret)));
      if (num_packets == packets.size()) packets.emplace_back();
      EncodedPacket& out = packets[num_packets++];
      out.bytes.assign(packet->data, packet->data + packet->size);
      out.pts = packet->pts;
      out.dts = packet->dts;
      out.keyframe = (packet->flags & AV_PKT_FLAG_KEY) != 0;
      av_packet_unref(packet.get());
      if (pass == EncoderPass::kFirst && ctx->stats_out != nullptr) stats += ctx->stats_out;
    }
  }
};

VideoEncoder::VideoEncoder() : impl_(std::make_unique<Impl>()) {}
VideoEncoder::~VideoEncoder() = default;
VideoEncoder::VideoEncoder(VideoEncoder&&) noexcept = default;
VideoEncoder& VideoEncoder::operator=(VideoEncoder&&) noexcept = default;

void VideoEncoder::open(const EncoderSettings& settings, int width, int height, EncoderPass pass,
                        const std::filesystem::path& stats_file) {
  Impl& s = *impl_;
  s.ctx.reset();
  s.hw_frame.reset();
  s.hw_frames.reset();
  s.hw_device.reset();
  s.flushed = false;
  s.stats.clear();
  s.num_packets = 0;

  if (std::find(kSupportedCodecs.begin(), kSupportedCodecs.end(), settings.codec) == kSupportedCodecs.end()) {
    throw InputError(fmt::format("codec '{}': expected one of libx264, mpeg4, mpeg2video, h264_v4l2m2m, h264_vaapi",
                                 settings.codec));
  }
  const bool hardware = isHardwareEncoder(settings.codec);
  const bool vaapi = settings.codec == "h264_vaapi";
  if (hardware && pass != EncoderPass::kSingle) {
    throw InputError(fmt::format("{} encodes in one pass only", settings.codec));
  }
  if (settings.bitrate_bps <= 0)
    throw InputError(fmt::format("bitrate {} bit/s: must be positive", settings.bitrate_bps));
  if (settings.fps_num <= 0 || settings.fps_den <= 0) {
    throw InputError(fmt::format("frame rate {}/{}: must be positive", settings.fps_num, settings.fps_den));
  }
  // Every pixel is coded, odd sizes included. H.264 codes whole 16x16 macroblocks and signals the
  // picture size through the SPS crop window, whose unit is one pixel only without chroma (4:0:0)
  // and two pixels in 4:2:0. So libx264 codes an odd-sized frame as 4:0:0 (monochrome, High
  // profile): x264 pads to the macroblock grid by repeating the last column and row, and every
  // decoder crops back to exactly width x height. Even sizes stay 4:2:0 with neutral chroma, as
  // the paper encoded. MPEG-4 Part 2 and MPEG-2 store the size itself and take odd sizes in 4:2:0.
  const int coded_width = width;
  const int coded_height = height;
  const bool odd_size = (width % 2) != 0 || (height % 2) != 0;
  if (settings.monochrome && settings.codec != "libx264") {
    throw InputError(
        fmt::format("4:0:0 (gray) coding: only libx264 codes frames without chroma, not {}", settings.codec));
  }
  if (hardware && odd_size) {
    throw InputError(fmt::format("frame size {}x{}: {} needs even sizes", width, height, settings.codec));
  }
  if (coded_width < 16 || coded_height < 16) {
    throw InputError(fmt::format("frame size {}x{}: the encoder needs at least 16x16 pixels", width, height));
  }
  if (pass != EncoderPass::kSingle && stats_file.empty()) {
    throw InputError("two-pass encoding needs a statistics file path");
  }

  const AVCodec* codec = avcodec_find_encoder_by_name(settings.codec.c_str());
  if (codec == nullptr) {
    throw RuntimeFailure(fmt::format("this FFmpeg build has no {} encoder (install libavcodec with {})", settings.codec,
                                     settings.codec));
  }
  const AVRational rate{settings.fps_num, settings.fps_den};
  if (codec->supported_framerates != nullptr) {
    bool supported = false;
    std::string list;
    for (const AVRational* r = codec->supported_framerates; r->num != 0; ++r) {
      supported = supported || av_cmp_q(*r, rate) == 0;
      if (r->den == 1) list += fmt::format("{}{}", list.empty() ? "" : ", ", r->num);
    }
    if (!supported) {
      throw InputError(fmt::format("frame rate {}/{}: {} supports only standard rates ({}, and the /1001 ones)",
                                   settings.fps_num, settings.fps_den, settings.codec, list));
    }
  }

  CodecContextPtr ctx(avcodec_alloc_context3(codec));
  if (!ctx) throw RuntimeFailure("out of memory allocating the encoder");
  ctx->width = coded_width;
  ctx->height = coded_height;
  // VAAPI encodes GPU surfaces (uploaded from nv12, the format every VAAPI driver takes).
  ctx->pix_fmt = vaapi                                                              ? AV_PIX_FMT_VAAPI
                 : settings.codec == "libx264" && (odd_size || settings.monochrome) ? AV_PIX_FMT_GRAY8
                                                                                    : AV_PIX_FMT_YUV420P;
  // Gray images use the full 0..255 range; signalling it keeps the luma values as they are instead
  // of squeezing them into studio range 16..235 as a swscale conversion would.
  ctx->color_range = AVCOL_RANGE_JPEG;
  ctx->time_base = av_inv_q(rate);  // one tick per frame: pts = frame index
  ctx->framerate = rate;
  ctx->bit_rate = settings.bitrate_bps;
  ctx->max_b_frames = 0;  // causal stream: decode order = capture order
  ctx->thread_count = settings.threads;
  if (settings.constant_bitrate) {
    // A one-second window: the rate a network link sees, not just the average over the video.
    ctx->rc_max_rate = settings.bitrate_bps;
    ctx->rc_min_rate = hardware ? settings.bitrate_bps : 0;
    ctx->rc_buffer_size = static_cast<int>(std::min<std::int64_t>(settings.bitrate_bps, 1 << 30));
  }
  if (settings.global_header) ctx->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
  if (pass == EncoderPass::kFirst) ctx->flags |= AV_CODEC_FLAG_PASS1;
  if (pass == EncoderPass::kSecond) ctx->flags |= AV_CODEC_FLAG_PASS2;

  AVDictionary* options = nullptr;
  if (settings.codec == "libx264") {
    // libavcodec's libx264 wrapper maps PASS1/PASS2 to x264's stat write/read and hands the file
    // name to x264 as its "stats" option (x264 also writes <stats>.mbtree beside it).
    av_dict_set(&options, "preset", settings.x264_preset.c_str(), 0);
    if (!settings.x264_tune.empty()) av_dict_set(&options, "tune", settings.x264_tune.c_str(), 0);
    const std::string x264_params = withReproducibleX264Asm(settings.x264_params);
    if (!x264_params.empty()) av_dict_set(&options, "x264-params", x264_params.c_str(), 0);
    if (pass != EncoderPass::kSingle) av_dict_set(&options, "stats", stats_file.c_str(), 0);
  } else if (hardware) {
    // Low latency on the device: keyframe interval, no B-frames (set above), one reference.
    ctx->gop_size = settings.gop_size;
    ctx->refs = 1;
    if (vaapi) {
      av_dict_set(&options, "rc_mode", settings.constant_bitrate ? "CBR" : "VBR", 0);
      av_dict_set(&options, "async_depth", "1", 0);  // hand each packet back before the next frame
      s.hw_device = createVaapiDevice(settings.vaapi_device);
      s.hw_frames = createVaapiFrames(s.hw_device.get(), coded_width, coded_height);
      ctx->hw_frames_ctx = av_buffer_ref(s.hw_frames.get());
      if (ctx->hw_frames_ctx == nullptr) throw RuntimeFailure("out of memory referencing the VAAPI frames");
    }
  } else {
    ctx->gop_size = settings.gop_size;
    if (pass == EncoderPass::kSecond) {
      // mpegvideo's two-pass rate control reads pass 1's lines from stats_in.
      ctx->stats_in = av_strdup(readWholeFile(stats_file).c_str());
    }
  }
  if (pass == EncoderPass::kSecond && settings.codec != "libx264") checkSecondPassOpens(ctx.get(), codec, settings);
  const int ret = avcodec_open2(ctx.get(), codec, &options);
  std::string unused;
  for (const AVDictionaryEntry* e = av_dict_get(options, "", nullptr, AV_DICT_IGNORE_SUFFIX); e != nullptr;
       e = av_dict_get(options, "", e, AV_DICT_IGNORE_SUFFIX)) {
    unused += fmt::format(" {}={}", e->key, e->value);
  }
  av_dict_free(&options);
  if (ret < 0) {
    throw InputError(
        fmt::format("cannot open the {} encoder for {}x{} at {} bit/s, {}/{} fps ({}); check the "
                    "settings (x264 params '{}')",
                    settings.codec, coded_width, coded_height, settings.bitrate_bps, settings.fps_num, settings.fps_den,
                    avErrorText(ret), settings.x264_params));
  }
  if (!unused.empty()) throw InputError(fmt::format("{} encoder does not know the options:{}", settings.codec, unused));

  FramePtr frame(av_frame_alloc());
  PacketPtr packet(av_packet_alloc());
  if (!frame || !packet) throw RuntimeFailure("out of memory allocating encoder buffers");
  frame->format = vaapi ? AV_PIX_FMT_NV12 : ctx->pix_fmt;
  frame->width = coded_width;
  frame->height = coded_height;
  frame->color_range = AVCOL_RANGE_JPEG;
  if (const int r = av_frame_get_buffer(frame.get(), 0); r < 0) {
    throw RuntimeFailure(fmt::format("cannot allocate a {}x{} frame: {}", coded_width, coded_height, avErrorText(r)));
  }
  fillNeutralChroma(*frame);
  if (vaapi) {
    s.hw_frame.reset(av_frame_alloc());
    if (!s.hw_frame) throw RuntimeFailure("out of memory allocating encoder buffers");
  }

  s.settings = settings;
  s.pass = pass;
  s.stats_file = stats_file;
  s.ctx = std::move(ctx);
  s.frame = std::move(frame);
  s.packet = std::move(packet);
  s.input_width = width;
  s.input_height = height;
}

std::span<const EncodedPacket> VideoEncoder::encode(GrayView image, std::int64_t pts) {
  Impl& s = *impl_;
  if (!s.ctx || s.flushed) throw RuntimeFailure("VideoEncoder::encode called on an encoder that is not open");
  if (image.width != s.input_width || image.height != s.input_height) {
    throw InputError(
        fmt::format("frame of {}x{} given to an encoder opened for {}x{}: all frames of a video must "
                    "have the same size",
                    image.width, image.height, s.input_width, s.input_height));
  }
  s.num_packets = 0;
  // The codec may still reference the previous frame's buffer; this copies (chroma included) if so.
  if (const int r = av_frame_make_writable(s.frame.get()); r < 0) {
    throw RuntimeFailure(fmt::format("cannot get a writable frame: {}", avErrorText(r)));
  }
  AVFrame& frame = *s.frame;
  for (int y = 0; y < frame.height; ++y) {
    std::memcpy(frame.data[0] + static_cast<std::ptrdiff_t>(y) * frame.linesize[0], image.row(y),
                static_cast<std::size_t>(frame.width));
  }
  frame.pts = pts;
  AVFrame* input = &frame;
  if (s.hw_frame) {
    // VAAPI: a surface from the frames pool (recycled, no allocation once warm), filled by upload.
    av_frame_unref(s.hw_frame.get());
    if (const int r = av_hwframe_get_buffer(s.hw_frames.get(), s.hw_frame.get(), 0); r < 0) {
      throw RuntimeFailure(fmt::format("no free VAAPI surface for frame pts {}: {}", pts, avErrorText(r)));
    }
    if (const int r = av_hwframe_transfer_data(s.hw_frame.get(), &frame, 0); r < 0) {
      throw RuntimeFailure(fmt::format("cannot upload frame pts {} to the GPU: {}", pts, avErrorText(r)));
    }
    s.hw_frame->pts = pts;
    input = s.hw_frame.get();
  }
  const int ret = avcodec_send_frame(s.ctx.get(), input);
  if (ret < 0)
    throw RuntimeFailure(fmt::format("{} encoder rejected frame pts {}: {}", s.settings.codec, pts, avErrorText(ret)));
  s.drain();
  return {s.packets.data(), s.num_packets};
}

std::span<const EncodedPacket> VideoEncoder::flush() {
  Impl& s = *impl_;
  if (!s.ctx) throw RuntimeFailure("VideoEncoder::flush called on an encoder that is not open");
  s.num_packets = 0;
  if (s.flushed) return {};
  if (const int ret = avcodec_send_frame(s.ctx.get(), nullptr); ret < 0) {
    throw RuntimeFailure(fmt::format("{} encoder failed to flush: {}", s.settings.codec, avErrorText(ret)));
  }
  s.drain();
  s.flushed = true;
  if (s.pass == EncoderPass::kFirst && s.settings.codec != "libx264") {
    std::ofstream out(s.stats_file, std::ios::binary);
    out << s.stats;
    if (!out) throw RuntimeFailure(fmt::format("cannot write the first-pass statistics {}", s.stats_file.string()));
  }
  return {s.packets.data(), s.num_packets};
}

bool VideoEncoder::isOpen() const { return impl_ && impl_->ctx != nullptr; }
int VideoEncoder::width() const { return impl_->ctx ? impl_->ctx->width : 0; }
int VideoEncoder::height() const { return impl_->ctx ? impl_->ctx->height : 0; }
const EncoderSettings& VideoEncoder::settings() const { return impl_->settings; }
const AVCodecContext* VideoEncoder::codecContext() const { return impl_->ctx.get(); }

}  // namespace voca::encode
