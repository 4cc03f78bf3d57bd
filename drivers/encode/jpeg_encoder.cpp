#include "drivers/encode/jpeg_encoder.h"

#include <fmt/format.h>

#include <algorithm>

#include "drivers/ffmpeg/av_objects.h"
#include "voca/core/error.h"

extern "C" {
#include <libswscale/swscale.h>
}

namespace voca::encode {

struct JpegEncoder::Impl {
  int width = 0, height = 0;  // of the pictures given
  int quality = 5;
  ffmpeg::CodecContextPtr codec;
  ffmpeg::FramePtr frame;
  ffmpeg::PacketPtr packet;
  SwsContext* sws = nullptr;
  std::int64_t next_pts = 0;

  ~Impl() { sws_freeContext(sws); }
  void check(int rc, const char* what) const {
    if (rc < 0) throw RuntimeFailure(fmt::format("JPEG encoder: {} ({})", what, ffmpeg::avErrorText(rc)));
  }
};

JpegEncoder::JpegEncoder(int width, int height, int quality) : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  if (width < 2 || height < 2)
    throw InputError(fmt::format("JPEG encoder: a {}x{} picture is too small", width, height));
  d.width = width;
  d.height = height;
  d.quality = std::clamp(quality, 2, 31);
  const AVCodec* encoder = avcodec_find_encoder(AV_CODEC_ID_MJPEG);
  if (encoder == nullptr) throw RuntimeFailure("libavcodec was built without its MJPEG encoder (needed for --view)");
  d.codec.reset(avcodec_alloc_context3(encoder));
  d.frame.reset(av_frame_alloc());
  d.packet.reset(av_packet_alloc());
  if (!d.codec || !d.frame || !d.packet) throw RuntimeFailure("JPEG encoder: out of memory");
  d.codec->width = width & ~1;
  d.codec->height = height & ~1;
  // Full-range 4:2:0, what JPEG viewers (browsers, Foxglove) expect; said by the range, not by the
  // deprecated YUVJ formats (swscale warns about those).
  d.codec->pix_fmt = AV_PIX_FMT_YUV420P;
  d.codec->color_range = AVCOL_RANGE_JPEG;
  d.codec->time_base = AVRational{1, 1000};
  d.codec->flags |= AV_CODEC_FLAG_QSCALE;
  d.check(avcodec_open2(d.codec.get(), encoder, nullptr), "cannot open libavcodec's MJPEG encoder");
  d.frame->format = d.codec->pix_fmt;
  d.frame->width = d.codec->width;
  d.frame->height = d.codec->height;
  d.check(av_frame_get_buffer(d.frame.get(), 0), "cannot allocate a frame");
  d.sws = sws_getContext(d.codec->width, d.codec->height, AV_PIX_FMT_RGB24, d.codec->width, d.codec->height,
                         AV_PIX_FMT_YUV420P, SWS_BILINEAR, nullptr, nullptr, nullptr);
  if (d.sws == nullptr) throw RuntimeFailure("JPEG encoder: cannot create an RGB to YUV converter");
  // Full range in and out (JPEG's), BT.601 coefficients; brightness, contrast and saturation as they are.
  const int* bt601 = sws_getCoefficients(SWS_CS_ITU601);
  sws_setColorspaceDetails(d.sws, bt601, 1, bt601, 1, 0, 1 << 16, 1 << 16);
  d.frame->color_range = AVCOL_RANGE_JPEG;
}

JpegEncoder::~JpegEncoder() = default;

std::span<const std::uint8_t> JpegEncoder::encode(RgbView picture) {
  Impl& d = *impl_;
  if (picture.width != d.width || picture.height != d.height) {
    throw InputError(
        fmt::format("JPEG encoder: a {}x{} picture, made for {}x{}", picture.width, picture.height, d.width, d.height));
  }
  av_packet_unref(d.packet.get());
  d.check(av_frame_make_writable(d.frame.get()), "cannot write a frame");
  static_assert(sizeof(Rgb8) == 3, "Rgb8 must be packed RGB24");
  const std::uint8_t* src[1] = {reinterpret_cast<const std::uint8_t*>(picture.data)};
  const int src_stride[1] = {static_cast<int>(picture.stride * 3)};
  sws_scale(d.sws, src, src_stride, 0, d.codec->height, d.frame->data, d.frame->linesize);
  d.frame->pts = d.next_pts++;
  d.frame->quality = FF_QP2LAMBDA * d.quality;
  d.check(avcodec_send_frame(d.codec.get(), d.frame.get()), "encoding failed");
  // MJPEG has no delay: every picture comes straight back as one packet.
  d.check(avcodec_receive_packet(d.codec.get(), d.packet.get()), "encoding failed");
  return {d.packet->data, static_cast<std::size_t>(d.packet->size)};
}

}  // namespace voca::encode
