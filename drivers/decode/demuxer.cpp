#include "drivers/decode/demuxer.h"

#include <algorithm>

#include "drivers/decode/ffmpeg_util.h"
#include "drivers/ffmpeg/av_objects.h"
#include "voca/core/error.h"

namespace voca::decode {

using ffmpeg::avErrorText;

const char* videoCodecName(VideoCodec codec) {
  switch (codec) {
    case VideoCodec::kH264:
      return "h264";
    case VideoCodec::kMpeg4:
      return "mpeg4";
    case VideoCodec::kMpeg2:
      return "mpeg2video";
    case VideoCodec::kOther:
      break;
  }
  return "other";
}

struct Demuxer::Impl {
  AVFormatContext* format = nullptr;
  AVPacket* packet = nullptr;
  int stream_index = -1;
  ~Impl() {
    av_packet_free(&packet);
    avformat_close_input(&format);
  }
};

Demuxer::Demuxer(const std::filesystem::path& path) : impl_(std::make_unique<Impl>()), path_(path) {
  const std::string name = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    const bool exists = std::filesystem::exists(path, ec);
    throw InputError(name + (!exists                                   ? ": no such video file"
                             : std::filesystem::is_directory(path, ec) ? ": a folder, not a video file"
                                                                       : ": not a regular file (a device or a pipe), "
                                                                         "not a video file"));
  }
  int rc = avformat_open_input(&impl_->format, name.c_str(), nullptr, nullptr);
  if (rc < 0) {
    throw InputError(name + ": cannot open as a video (" + avErrorText(rc) +
                     "); is it a complete .mp4/.mkv/.h264 file? A truncated .mp4 loses its index");
  }
  rc = avformat_find_stream_info(impl_->format, nullptr);
  if (rc < 0) throw InputError(name + ": cannot read stream information (" + avErrorText(rc) + ")");
  rc = av_find_best_stream(impl_->format, AVMEDIA_TYPE_VIDEO, -1, -1, nullptr, 0);
  if (rc < 0) throw InputError(name + ": contains no video stream");
  impl_->stream_index = rc;
  const AVStream* stream = impl_->format->streams[rc];
  const AVCodecParameters* par = stream->codecpar;
  if (par->width <= 0 || par->height <= 0) {
    throw InputError(name + ": video stream has no frame size (corrupt or truncated header)");
  }

  switch (par->codec_id) {
    case AV_CODEC_ID_H264:
      info_.codec = VideoCodec::kH264;
      break;
    case AV_CODEC_ID_MPEG4:
      info_.codec = VideoCodec::kMpeg4;
      break;
    case AV_CODEC_ID_MPEG2VIDEO:
    case AV_CODEC_ID_MPEG1VIDEO:
      info_.codec = VideoCodec::kMpeg2;
      break;
    default:
      info_.codec = VideoCodec::kOther;
      break;
  }
  info_.codec_name = avcodec_get_name(par->codec_id);
  if (info_.codec == VideoCodec::kOther) {
    throw InputError(name + ": video codec '" + info_.codec_name +
                     "' is not supported (use H.264, MPEG-4 Part 2 or MPEG-2: their decoders export motion vectors)");
  }
  info_.width = par->width;
  info_.height = par->height;
  if (par->extradata != nullptr && par->extradata_size > 0) {
    info_.extradata.assign(par->extradata, par->extradata + par->extradata_size);
  }
  info_.time_base_num = stream->time_base.num;
  info_.time_base_den = stream->time_base.den;
  if (stream->avg_frame_rate.num > 0 && stream->avg_frame_rate.den > 0) {
    info_.frame_rate_num = stream->avg_frame_rate.num;
    info_.frame_rate_den = stream->avg_frame_rate.den;
    info_.constant_frame_rate = av_cmp_q(stream->avg_frame_rate, stream->r_frame_rate) == 0;
  }
  info_.num_frames = std::max<std::int64_t>(0, stream->nb_frames);
  impl_->packet = av_packet_alloc();
  if (impl_->packet == nullptr) throw RuntimeFailure("out of memory allocating a packet");
}

Demuxer::~Demuxer() = default;

bool Demuxer::read(Packet& packet) {
  AVPacket* av = impl_->packet;
  for (;;) {
    const int rc = av_read_frame(impl_->format, av);
    if (rc == AVERROR_EOF) return false;
    if (rc < 0) {
      throw InputError(path_.string() + ": read error at packet " + std::to_string(next_index_) + " (" +
                       avErrorText(rc) + "); the file may be truncated or corrupt");
    }
    if (av->stream_index != impl_->stream_index) {
      av_packet_unref(av);
      continue;
    }
    packet.bytes.assign(av->data, av->data + av->size);
    packet.pts = av->pts == AV_NOPTS_VALUE ? kNoPts : av->pts;
    packet.dts = av->dts == AV_NOPTS_VALUE ? kNoPts : av->dts;
    packet.keyframe = (av->flags & AV_PKT_FLAG_KEY) != 0;
    packet.index = next_index_++;
    const bool corrupt = (av->flags & AV_PKT_FLAG_CORRUPT) != 0;
    av_packet_unref(av);
    if (corrupt) {
      throw InputError(path_.string() + ": packet " + std::to_string(packet.index) +
                       " is flagged corrupt by the container");
    }
    return true;
  }
}

std::vector<Packet> readAllPackets(Demuxer& demuxer) {
  std::vector<Packet> packets;
  Packet packet;
  while (demuxer.read(packet)) packets.push_back(packet);
  return packets;
}

}  // namespace voca::decode
