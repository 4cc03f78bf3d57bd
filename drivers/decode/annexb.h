#pragma once
// H.264 access units from an MP4's form (length-prefixed NAL units, parameter sets in the stream's
// avcC header) into the Annex B byte stream an encoder on a robot hands over (start codes, the
// parameter sets in band before each keyframe): FFmpeg's h264_mp4toannexb bitstream filter.

#include <cstdint>
#include <memory>
#include <vector>

#include "drivers/decode/demuxer.h"

namespace voca::decode {

class AnnexBConverter {
 public:
  // stream: the H.264 stream the packets come from (its extradata holds the avcC header; a stream
  // without one is Annex B already and passes through). Throws InputError for another codec.
  explicit AnnexBConverter(const StreamInfo& stream);
  ~AnnexBConverter();
  AnnexBConverter(const AnnexBConverter&) = delete;
  AnnexBConverter& operator=(const AnnexBConverter&) = delete;

  // The packet's access unit as Annex B into out (replaced). Throws InputError for a packet the
  // filter cannot read.
  void convert(const Packet& packet, std::vector<std::uint8_t>& out);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace voca::decode
