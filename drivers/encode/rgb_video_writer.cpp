#include "drivers/encode/rgb_video_writer.h"

#include <string>
#include <system_error>
#include <utility>

#include "drivers/ffmpeg/av_objects.h"
#include "voca/core/error.h"

extern "C" {
#include <libavformat/avformat.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}

namespace voca::encode {

using ffmpeg::avErrorText;

struct RgbVideoWriter::Impl {
  std::filesystem::path path;
  AVRational fps{30, 1};
  AVIOContext* file = nullptr;  // opened by the constructor, handed to `format` by open()
  AVFormatContext* format = nullptr;
  AVStream* stream = nullptr;
  ffmpeg::CodecContextPtr codec;
  ffmpeg::FramePtr frame;
  ffmpeg::PacketPtr packet;
  SwsContext* sws = nullptr;
  std::int64_t next_pts = 0;
  bool header_written = false, finished = false, open_failed = false;

  ~Impl() {
    sws_freeContext(sws);
    if (file != nullptr) {  // no frame came: no empty .mp4 left behind
      avio_closep(&file);
      std::error_code ignored;
      std::filesystem::remove(path, ignored);
    }
    if (format != nullptr) {
      if (format->pb != nullptr) avio_closep(&format->pb);
      avformat_free_context(format);
    }
  }
  void check(int rc, const std::string& what) const {
    if (rc < 0) throw InputError(path.string() + ": " + what + " (" + avErrorText(rc) + ")");
  }
  void open(int width, int height);
  void drain();
};

RgbVideoWriter::RgbVideoWriter(const std::filesystem::path& path, int fps_num, int fps_den)
    : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  impl_->fps = AVRational{fps_num, fps_den};
  // The file now, so an unwritable path fails before any frame is made for it.
  impl_->check(avio_open(&impl_->file, path.string().c_str(), AVIO_FLAG_WRITE), "cannot open for writing");
}

RgbVideoWriter::~RgbVideoWriter() {
  try {
    finish();
  } catch (const std::exception&) {
    // Destructors must not throw; callers wanting the error call finish() themselves.
  }
}

void RgbVideoWriter::Impl::open(int width, int height) {
  check(avformat_alloc_output_context2(&format, nullptr, "mp4", path.string().c_str()), "cannot create an mp4");
  const AVCodec* encoder = avcodec_find_encoder_by_name("libx264");
  if (encoder == nullptr) encoder = avcodec_find_encoder(AV_CODEC_ID_MPEG4);
  if (encoder == nullptr) throw RuntimeFailure("libavcodec has neither libx264 nor an MPEG-4 encoder");
  codec.reset(avcodec_alloc_context3(encoder));
  frame.reset(av_frame_alloc());
  packet.reset(av_packet_alloc());
  if (!codec || !frame || !packet) throw RuntimeFailure("out of memory");
  // 4:2:0 needs even sizes; the odd last row/column is dropped.
  codec->width = width & ~1;
  codec->height = height & ~1;
  codec->pix_fmt = AV_PIX_FMT_YUV420P;
  codec->time_base = av_inv_q(fps);
  codec->framerate = fps;
  codec->gop_size = 60;
  codec->max_b_frames = 0;
  if ((format->oformat->flags & AVFMT_GLOBALHEADER) != 0) codec->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
  if (std::string(encoder->name) == "libx264") {
    av_opt_set(codec->priv_data, "crf", "18", 0);  // visually lossless: thin coloured lines survive
    av_opt_set(codec->priv_data, "preset", "fast", 0);
    av_opt_set(codec->priv_data, "x264-params", "log=-1", 0);  // no per-run statistics on stderr
  } else {
    codec->bit_rate = static_cast<std::int64_t>(codec->width) * codec->height * 8;
  }
  check(avcodec_open2(codec.get(), encoder, nullptr), "cannot open the encoder");
  stream = avformat_new_stream(format, nullptr);
  if (stream == nullptr) throw RuntimeFailure("out of memory");
  stream->time_base = codec->time_base;
  check(avcodec_parameters_from_context(stream->codecpar, codec.get()), "cannot set stream parameters");
  format->pb = std::exchange(file, nullptr);
  check(avformat_write_header(format, nullptr), "cannot write the mp4 header");
  header_written = true;
  frame->format = codec->pix_fmt;
  frame->width = codec->width;
  frame->height = codec->height;
  check(av_frame_get_buffer(frame.get(), 0), "cannot allocate a frame");
  sws = sws_getContext(codec->width, codec->height, AV_PIX_FMT_RGB24, codec->width, codec->height, AV_PIX_FMT_YUV420P,
                       SWS_BILINEAR, nullptr, nullptr, nullptr);
  if (sws == nullptr) throw RuntimeFailure("cannot create an RGB to YUV converter");
}

void RgbVideoWriter::Impl::drain() {
  for (;;) {
    const int rc = avcodec_receive_packet(codec.get(), packet.get());
    if (rc == AVERROR(EAGAIN) || rc == AVERROR_EOF) return;
    check(rc, "encoding failed");
    av_packet_rescale_ts(packet.get(), codec->time_base, stream->time_base);
    packet->stream_index = stream->index;
    check(av_interleaved_write_frame(format, packet.get()), "write failed (disk full?)");
  }
}

void RgbVideoWriter::write(RgbView image) {
  Impl& d = *impl_;
  if (d.finished) throw InputError(d.path.string() + ": write after finish");
  if (d.open_failed) throw InputError(d.path.string() + ": the video could not be opened (see the first error)");
  if (!d.codec) {
    try {
      d.open(image.width, image.height);
    } catch (...) {
      // A half-opened encoder (no scaler, maybe no header) must not be used by a later write().
      d.open_failed = true;
      throw;
    }
  }
  if ((image.width & ~1) != d.codec->width || (image.height & ~1) != d.codec->height) {
    throw InputError(d.path.string() + ": frame size changed to " + std::to_string(image.width) + "x" +
                     std::to_string(image.height));
  }
  d.check(av_frame_make_writable(d.frame.get()), "cannot write a frame");
  static_assert(sizeof(Rgb8) == 3, "Rgb8 must be packed RGB24");
  const std::uint8_t* src[1] = {reinterpret_cast<const std::uint8_t*>(image.data)};
  const int src_stride[1] = {static_cast<int>(image.stride * 3)};
  sws_scale(d.sws, src, src_stride, 0, d.codec->height, d.frame->data, d.frame->linesize);
  d.frame->pts = d.next_pts++;
  d.check(avcodec_send_frame(d.codec.get(), d.frame.get()), "encoding failed");
  d.drain();
}

void RgbVideoWriter::finish() {
  Impl& d = *impl_;
  if (d.finished || !d.header_written || d.open_failed) {
    d.finished = true;
    return;
  }
  d.finished = true;
  d.check(avcodec_send_frame(d.codec.get(), nullptr), "encoding failed");
  d.drain();
  d.check(av_write_trailer(d.format), "cannot finish the mp4");
}

}  // namespace voca::encode
