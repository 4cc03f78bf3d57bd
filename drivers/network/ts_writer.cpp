#include "drivers/network/ts_writer.h"

#include <array>
#include <utility>

#include <fmt/core.h>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/error.h>
}

#include "drivers/ffmpeg/av_objects.h"
#include "drivers/network/open_error.h"
#include "drivers/network/stream_url.h"
#include "voca/core/error.h"

namespace voca::network {

namespace {

using ffmpeg::avErrorText;

constexpr AVRational kTsClock{1, 90000};

}  // namespace

struct StereoTsWriter::Impl {
  std::string url;
  std::function<bool()> stop_requested;
  AVFormatContext* format = nullptr;
  AVPacket* packet = nullptr;
  std::array<AVStream*, 2> streams{};
  std::int64_t t0_ns = 0;
  bool started = false;
  bool finished = false;
  std::int64_t bytes = 0;

  void close() {
    if (format != nullptr) {
      if (format->pb != nullptr) avio_closep(&format->pb);
      avformat_free_context(format);
      format = nullptr;
    }
    av_packet_free(&packet);
  }
};

StereoTsWriter::StereoTsWriter(const std::string& url, int width, int height, std::function<bool()> stop_requested)
    : impl_(std::make_unique<Impl>()) {
  impl_->stop_requested = std::move(stop_requested);
  Impl& w = *impl_;
  requireStreamPort(url);
  w.url = url;
  if (url.rfind("udp://", 0) == 0 && url.find("pkt_size=") == std::string::npos) {
    w.url += url.find('?') == std::string::npos ? "?pkt_size=1316" : "&pkt_size=1316";
  }
  if (const int r = avformat_alloc_output_context2(&w.format, nullptr, "mpegts", w.url.c_str()); r < 0) {
    throw RuntimeFailure(fmt::format("cannot create an MPEG-TS muxer: {}", avErrorText(r)));
  }
  w.packet = av_packet_alloc();
  if (w.packet == nullptr) {
    w.close();
    throw RuntimeFailure("out of memory allocating a packet");
  }
  for (int c = 0; c < 2; ++c) {
    AVStream* stream = avformat_new_stream(w.format, nullptr);
    if (stream == nullptr) {
      w.close();
      throw RuntimeFailure("out of memory adding a stream");
    }
    stream->id = c;
    stream->time_base = kTsClock;
    stream->codecpar->codec_type = AVMEDIA_TYPE_VIDEO;
    stream->codecpar->codec_id = AV_CODEC_ID_H264;
    stream->codecpar->width = width;
    stream->codecpar->height = height;
    av_dict_set(&stream->metadata, "title", c == 0 ? "cam0" : "cam1", 0);
    w.streams[static_cast<std::size_t>(c)] = stream;
  }
  // Hand every packet to the network at once.
  w.format->flags |= AVFMT_FLAG_FLUSH_PACKETS;
  // libavformat polls this while it blocks (a listening tcp:// waits in accept()).
  const AVIOInterruptCB interrupt{[](void* opaque) {
                                    const auto& stop = *static_cast<const std::function<bool()>*>(opaque);
                                    return stop && stop() ? 1 : 0;
                                  },
                                  &w.stop_requested};
  network::OpenErrorCapture open_error;
  if (const int r = avio_open2(&w.format->pb, w.url.c_str(), AVIO_FLAG_WRITE, &interrupt, nullptr); r < 0) {
    w.close();
    if (w.stop_requested && w.stop_requested()) throw InputError(fmt::format("stopped while opening {}", url));
    throw InputError(fmt::format("cannot open {} for sending: {}", url, open_error.reason(r)));
  }
  AVDictionary* options = nullptr;
  // PES packets with their length, so the demuxer emits each one when complete (see the header).
  av_dict_set(&options, "omit_video_pes_length", "0", 0);
  av_dict_set(&options, "flush_packets", "1", 0);
  const int r = avformat_write_header(w.format, &options);
  av_dict_free(&options);
  if (r < 0) {
    w.close();
    throw RuntimeFailure(fmt::format("cannot start the MPEG-TS stream to {}: {}", url, avErrorText(r)));
  }
}

StereoTsWriter::~StereoTsWriter() {
  try {
    finish();
  } catch (...) {  // the destructor of a failed stream: the error was reported by write()
  }
  impl_->close();
}

void StereoTsWriter::write(int camera, std::span<const std::uint8_t> access_unit, std::int64_t t_ns, bool keyframe) {
  Impl& w = *impl_;
  if (w.finished || w.format == nullptr) throw RuntimeFailure("StereoTsWriter::write after finish()");
  if (camera < 0 || camera > 1) throw InputError(fmt::format("camera {}: expected 0 or 1", camera));
  if (!w.started) {
    w.t0_ns = t_ns;
    w.started = true;
  }
  AVStream* stream = w.streams[static_cast<std::size_t>(camera)];
  AVPacket* pkt = w.packet;
  av_packet_unref(pkt);
  // Not reference-counted: the muxer copies what it keeps.
  pkt->data = const_cast<std::uint8_t*>(access_unit.data());
  pkt->size = static_cast<int>(access_unit.size());
  pkt->stream_index = stream->index;
  pkt->pts = av_rescale_q(t_ns - w.t0_ns, AVRational{1, 1000000000}, stream->time_base);
  pkt->dts = pkt->pts;
  pkt->flags = keyframe ? AV_PKT_FLAG_KEY : 0;
  // av_write_frame, not the interleaving variant: the caller writes in capture order already, and
  // interleaving would hold a packet back until the other camera's next one arrives.
  const int r = av_write_frame(w.format, pkt);
  pkt->data = nullptr;
  pkt->size = 0;
  if (r < 0) throw RuntimeFailure(fmt::format("sending to {} failed: {}", w.url, avErrorText(r)));
  w.bytes += static_cast<std::int64_t>(access_unit.size());
}

void StereoTsWriter::finish() {
  Impl& w = *impl_;
  if (w.finished || w.format == nullptr) return;
  w.finished = true;
  if (const int r = av_write_trailer(w.format); r < 0) {
    throw RuntimeFailure(fmt::format("ending the stream to {} failed: {}", w.url, avErrorText(r)));
  }
  avio_flush(w.format->pb);
}

std::int64_t StereoTsWriter::bytesWritten() const { return impl_->bytes; }
const std::string& StereoTsWriter::url() const { return impl_->url; }

}  // namespace voca::network
