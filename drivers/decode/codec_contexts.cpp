#include "drivers/decode/codec_contexts.h"

#include <cstdint>
#include <cstring>
#include <string_view>

#include "drivers/decode/ffmpeg_util.h"
#include "drivers/decode/picture_pool.h"
#include "voca/core/error.h"

extern "C" {
#include <libavutil/hwcontext.h>
}

namespace voca::decode {

bool lumaOnlyDecodingAvailable() {
  static const bool available =
      std::string_view(avcodec_configuration()).find("--enable-gray") != std::string_view::npos;
  return available;
}

namespace detail {

using ffmpeg::avErrorText;
using ffmpeg::BufferPtr;
using ffmpeg::CodecContextPtr;

namespace {

AVPixelFormat pickVaapiFormat(AVCodecContext* /*ctx*/, const AVPixelFormat* formats) {
  for (const AVPixelFormat* f = formats; *f != AV_PIX_FMT_NONE; ++f) {
    if (*f == AV_PIX_FMT_VAAPI) return *f;
  }
  return AV_PIX_FMT_NONE;
}

void setExtradata(AVCodecContext* ctx, const StreamInfo& stream) {
  if (stream.extradata.empty()) return;
  const std::size_t size = stream.extradata.size();
  ctx->extradata = static_cast<std::uint8_t*>(av_mallocz(size + AV_INPUT_BUFFER_PADDING_SIZE));
  if (ctx->extradata == nullptr) throw RuntimeFailure("out of memory copying codec headers");
  std::memcpy(ctx->extradata, stream.extradata.data(), size);
  ctx->extradata_size = static_cast<int>(size);
}

// A context for `codec` that knows the stream's frame size, time base and out-of-band headers.
CodecContextPtr allocContext(const AVCodec* codec, const StreamInfo& stream) {
  CodecContextPtr ctx(avcodec_alloc_context3(codec));
  if (!ctx) throw RuntimeFailure("out of memory allocating a decoder");
  ctx->width = stream.width;
  ctx->height = stream.height;
  ctx->pkt_timebase = AVRational{stream.time_base_num, stream.time_base_den};
  setExtradata(ctx.get(), stream);
  return ctx;
}

}  // namespace

CodecContextPtr openSoftwareDecoder(const DecoderSetup& setup, bool motion_only, PicturePool& pool) {
  const StreamInfo& stream = setup.stream;
  const DecoderOptions& options = setup.options;
  const AVCodec* codec = avcodec_find_decoder(avCodecId(stream.codec));
  if (codec == nullptr) throw RuntimeFailure(setup.source + ": libavcodec has no decoder for " + stream.codec_name);
  CodecContextPtr ctx = allocContext(codec, stream);
  // One thread, slice threading only: frame threading delays output and costs memory per thread.
  ctx->thread_count = 1;
  ctx->thread_type = FF_THREAD_SLICE;
  // The quantiser of each macroblock beside its vectors: how coarsely the encoder coded the block, a
  // confidence signal for the vector (frontend prior_max_qp).
  if (options.export_motion || motion_only) {
    ctx->export_side_data |= AV_CODEC_EXPORT_DATA_MVS;
    if (options.export_qp) ctx->export_side_data |= AV_CODEC_EXPORT_DATA_VIDEO_ENC_PARAMS;
  }
  // Vectors do not depend on reconstructed pixels, so the deblocking filter can be skipped.
  if (motion_only || options.skip_loop_filter) ctx->skip_loop_filter = AVDISCARD_ALL;
  // Asked of a libavcodec built without it, the flag is ignored with a warning on every open.
  if (options.luma_only && lumaOnlyDecodingAvailable()) ctx->flags |= AV_CODEC_FLAG_GRAY;
  if (options.strict) ctx->err_recognition |= AV_EF_EXPLODE;
  pool.attach(ctx.get());
  const int rc = avcodec_open2(ctx.get(), codec, nullptr);
  if (rc < 0) {
    throw RuntimeFailure(setup.source + ": cannot open the " + stream.codec_name + " decoder (" + avErrorText(rc) +
                         ")");
  }
  return ctx;
}

CodecContextPtr openVaapiDecoder(const DecoderSetup& setup, BufferPtr& hw_device) {
  const StreamInfo& stream = setup.stream;
  const DecoderOptions& options = setup.options;
  const AVCodec* codec = avcodec_find_decoder(avCodecId(stream.codec));
  if (codec == nullptr || !codecSupportsVaapi(codec)) {
    throw RuntimeFailure(setup.source + ": libavcodec cannot decode " + stream.codec_name + " with VAAPI");
  }
  AVBufferRef* device = nullptr;
  int rc = av_hwdevice_ctx_create(&device, AV_HWDEVICE_TYPE_VAAPI, options.vaapi_device.c_str(), nullptr, 0);
  if (rc < 0) {
    throw RuntimeFailure("cannot open VAAPI device " + options.vaapi_device + " (" + avErrorText(rc) + ")");
  }
  hw_device.reset(device);
  CodecContextPtr ctx = allocContext(codec, stream);
  ctx->hw_device_ctx = av_buffer_ref(hw_device.get());
  if (ctx->hw_device_ctx == nullptr) throw RuntimeFailure("out of memory referencing the VAAPI device");
  ctx->get_format = pickVaapiFormat;
  ctx->thread_count = 1;
  if (options.strict) ctx->err_recognition |= AV_EF_EXPLODE;
  rc = avcodec_open2(ctx.get(), codec, nullptr);
  if (rc < 0) throw RuntimeFailure(setup.source + ": cannot open the VAAPI decoder (" + avErrorText(rc) + ")");
  return ctx;
}

CodecContextPtr openV4l2m2mDecoder(const DecoderSetup& setup) {
  const StreamInfo& stream = setup.stream;
  const char* name = v4l2m2mDecoderName(stream.codec);
  const AVCodec* codec = name == nullptr ? nullptr : avcodec_find_decoder_by_name(name);
  if (codec == nullptr) {
    throw RuntimeFailure(setup.source + ": libavcodec has no V4L2 M2M decoder for " + stream.codec_name);
  }
  CodecContextPtr ctx = allocContext(codec, stream);
  const int rc = avcodec_open2(ctx.get(), codec, nullptr);
  if (rc < 0) {
    throw RuntimeFailure(setup.source + ": cannot open " + name + " (" + avErrorText(rc) +
                         "); no V4L2 memory-to-memory decoder device?");
  }
  return ctx;
}

}  // namespace detail
}  // namespace voca::decode
