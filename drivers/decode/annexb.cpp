#include "drivers/decode/annexb.h"

#include <fmt/core.h>

#include <cstring>

#include "drivers/ffmpeg/av_objects.h"
#include "voca/core/error.h"

extern "C" {
#include <libavcodec/bsf.h>
}

namespace voca::decode {

struct AnnexBConverter::Impl {
  AVBSFContext* filter = nullptr;
  ffmpeg::PacketPtr packet{av_packet_alloc()};
  ~Impl() { av_bsf_free(&filter); }
};

AnnexBConverter::AnnexBConverter(const StreamInfo& stream) : impl_(std::make_unique<Impl>()) {
  if (stream.codec != VideoCodec::kH264) {
    throw InputError(fmt::format("Annex B conversion: the stream is {}, not H.264", stream.codec_name));
  }
  if (stream.extradata.empty() || stream.extradata[0] != 1) return;  // no avcC header: Annex B already
  const AVBitStreamFilter* bsf = av_bsf_get_by_name("h264_mp4toannexb");
  if (bsf == nullptr) throw RuntimeFailure("libavcodec lacks the h264_mp4toannexb bitstream filter");
  int rc = av_bsf_alloc(bsf, &impl_->filter);
  if (rc < 0) throw RuntimeFailure("cannot allocate the h264_mp4toannexb filter: " + ffmpeg::avErrorText(rc));
  AVCodecParameters* par = impl_->filter->par_in;
  par->codec_type = AVMEDIA_TYPE_VIDEO;
  par->codec_id = AV_CODEC_ID_H264;
  par->width = stream.width;
  par->height = stream.height;
  par->extradata = static_cast<std::uint8_t*>(av_mallocz(stream.extradata.size() + AV_INPUT_BUFFER_PADDING_SIZE));
  if (par->extradata == nullptr) throw RuntimeFailure("out of memory for the stream header");
  std::memcpy(par->extradata, stream.extradata.data(), stream.extradata.size());
  par->extradata_size = static_cast<int>(stream.extradata.size());
  impl_->filter->time_base_in = AVRational{stream.time_base_num, stream.time_base_den};
  rc = av_bsf_init(impl_->filter);
  if (rc < 0) throw InputError("the stream's avcC header cannot be read: " + ffmpeg::avErrorText(rc));
}

AnnexBConverter::~AnnexBConverter() = default;

void AnnexBConverter::convert(const Packet& packet, std::vector<std::uint8_t>& out) {
  if (impl_->filter == nullptr) {
    out.assign(packet.bytes.begin(), packet.bytes.end());
    return;
  }
  AVPacket* p = impl_->packet.get();
  int rc = av_new_packet(p, static_cast<int>(packet.bytes.size()));
  if (rc < 0) throw RuntimeFailure("cannot allocate a packet: " + ffmpeg::avErrorText(rc));
  std::memcpy(p->data, packet.bytes.data(), packet.bytes.size());
  p->pts = packet.pts;
  p->dts = packet.dts;
  if (packet.keyframe) p->flags |= AV_PKT_FLAG_KEY;
  rc = av_bsf_send_packet(impl_->filter, p);
  if (rc < 0) {
    av_packet_unref(p);
    throw InputError(
        fmt::format("packet {}: not a length-prefixed H.264 access unit ({})", packet.index, ffmpeg::avErrorText(rc)));
  }
  out.clear();
  while ((rc = av_bsf_receive_packet(impl_->filter, p)) == 0) {
    out.insert(out.end(), p->data, p->data + p->size);
    av_packet_unref(p);
  }
  if (rc != AVERROR(EAGAIN) && rc != AVERROR_EOF) {
    throw InputError(fmt::format("packet {}: cannot convert to Annex B ({})", packet.index, ffmpeg::avErrorText(rc)));
  }
}

}  // namespace voca::decode
