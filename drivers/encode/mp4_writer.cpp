#include "drivers/encode/mp4_writer.h"

#include <stdexcept>
#include <string>

#include <fmt/core.h>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
}

#include "drivers/ffmpeg/av_objects.h"
#include "voca/core/error.h"

namespace voca::encode {

using ffmpeg::avErrorText;
using ffmpeg::PacketPtr;

namespace {

// Writes the packets of one video stream into an .mp4 file.
class Mp4Muxer {
 public:
  // Opens the file first so an unwritable path fails before any encoding work.
  explicit Mp4Muxer(const std::filesystem::path& path) : path_(path) {
    if (const int r = avformat_alloc_output_context2(&format_, nullptr, "mp4", path.c_str()); r < 0 || !format_) {
      throw RuntimeFailure(fmt::format("cannot create an mp4 muxer: {}", avErrorText(r)));
    }
    if (const int r = avio_open(&format_->pb, path.c_str(), AVIO_FLAG_WRITE); r < 0) {
      avformat_free_context(format_);  // the destructor does not run for a throwing constructor
      format_ = nullptr;
      throw InputError(fmt::format("cannot write {}: {}", path.string(), avErrorText(r)));
    }
  }
  ~Mp4Muxer() {
    if (format_ != nullptr) {
      if (format_->pb != nullptr) avio_closep(&format_->pb);
      avformat_free_context(format_);
    }
  }
  Mp4Muxer(const Mp4Muxer&) = delete;
  Mp4Muxer& operator=(const Mp4Muxer&) = delete;

  void begin(const AVCodecContext& ctx) {
    stream_ = avformat_new_stream(format_, nullptr);
    if (stream_ == nullptr) throw RuntimeFailure("cannot add a video stream to the mp4 muxer");
    if (const int r = avcodec_parameters_from_context(stream_->codecpar, &ctx); r < 0) {
      throw RuntimeFailure(fmt::format("cannot copy codec parameters: {}", avErrorText(r)));
    }
    codec_time_base_ = ctx.time_base;
    stream_->time_base = ctx.time_base;
    stream_->avg_frame_rate = ctx.framerate;
    stream_->r_frame_rate = ctx.framerate;
    if (const int r = avformat_write_header(format_, nullptr); r < 0) {
      throw RuntimeFailure(fmt::format("cannot write the mp4 header of {}: {}", path_.string(), avErrorText(r)));
    }
    packet_.reset(av_packet_alloc());
    if (!packet_) throw RuntimeFailure("out of memory allocating a packet");
  }

  void write(const EncodedPacket& in) {
    AVPacket* packet = packet_.get();
    if (const int r = av_new_packet(packet, static_cast<int>(in.bytes.size())); r < 0) {
      throw RuntimeFailure(fmt::format("cannot allocate a packet: {}", avErrorText(r)));
    }
    std::memcpy(packet->data, in.bytes.data(), in.bytes.size());
    packet->pts = in.pts;
    packet->dts = in.dts;
    packet->duration = 1;  // one frame; lets the muxer give the last frame its length
    packet->flags = in.keyframe ? AV_PKT_FLAG_KEY : 0;
    packet->stream_index = stream_->index;
    av_packet_rescale_ts(packet, codec_time_base_, stream_->time_base);
    const int r = av_write_frame(format_, packet);
    av_packet_unref(packet);
    if (r < 0) throw RuntimeFailure(fmt::format("cannot write to {}: {}", path_.string(), avErrorText(r)));
  }

  void end() {
    if (const int r = av_write_trailer(format_); r < 0) {
      throw RuntimeFailure(fmt::format("cannot finish {}: {}", path_.string(), avErrorText(r)));
    }
    if (const int r = avio_closep(&format_->pb); r < 0) {
      throw RuntimeFailure(fmt::format("cannot close {}: {}", path_.string(), avErrorText(r)));
    }
  }

 private:
  std::filesystem::path path_;
  AVFormatContext* format_ = nullptr;
  AVStream* stream_ = nullptr;
  AVRational codec_time_base_{1, 1};
  PacketPtr packet_;
};

}  // namespace

struct Mp4Writer::Impl {
  explicit Impl(const std::filesystem::path& path) : muxer(path) {}
  Mp4Muxer muxer;
  bool begun = false, ended = false;
};

Mp4Writer::Mp4Writer(const std::filesystem::path& path) : impl_(std::make_unique<Impl>(path)) {}
Mp4Writer::~Mp4Writer() = default;

void Mp4Writer::begin(const VideoEncoder& encoder) {
  if (encoder.codecContext() == nullptr) throw std::logic_error("Mp4Writer::begin: the encoder is not open");
  impl_->muxer.begin(*encoder.codecContext());
  impl_->begun = true;
}

void Mp4Writer::write(const EncodedPacket& packet) { impl_->muxer.write(packet); }

void Mp4Writer::end() {
  if (!impl_->begun || impl_->ended) return;
  impl_->ended = true;
  impl_->muxer.end();
}

}  // namespace voca::encode
