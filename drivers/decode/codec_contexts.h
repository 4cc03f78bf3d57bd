#pragma once
// Opening a libavcodec decoder context for one stream, one function per backend: software (pictures
// from our pool), VAAPI and V4L2 M2M. VideoDecoder chooses the backend; not a public header.

#include <string>

#include "drivers/decode/demuxer.h"
#include "drivers/decode/video_decoder.h"
#include "drivers/ffmpeg/av_objects.h"

namespace voca::decode {

class PicturePool;

namespace detail {

// The names a decoder opens with: the stream, how to decode it, and the source named in errors.
struct DecoderSetup {
  const StreamInfo& stream;
  const DecoderOptions& options;
  const std::string& source;
};

// Software decoding, on the calling thread. motion_only: parse for the motion vectors alone (loop
// filter skipped). The context takes its pictures from `pool`, which must outlive it.
ffmpeg::CodecContextPtr openSoftwareDecoder(const DecoderSetup& setup, bool motion_only, PicturePool& pool);
// VAAPI on options.vaapi_device; hw_device receives the device, which the context references.
ffmpeg::CodecContextPtr openVaapiDecoder(const DecoderSetup& setup, ffmpeg::BufferPtr& hw_device);
// libavcodec's V4L2 memory-to-memory decoder for the stream's codec.
ffmpeg::CodecContextPtr openV4l2m2mDecoder(const DecoderSetup& setup);

}  // namespace detail
}  // namespace voca::decode
