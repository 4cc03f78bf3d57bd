#pragma once
// The decoders' libav* lookups (codec ids, hardware decoders) used inside drivers/decode; not a public header.

#include "drivers/decode/demuxer.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
}

namespace voca::decode::detail {

// Name of libavcodec's V4L2 memory-to-memory decoder for a codec (nullptr if none).
const char* v4l2m2mDecoderName(VideoCodec codec);
AVCodecID avCodecId(VideoCodec codec);
// The decoder can use a VAAPI device context.
bool codecSupportsVaapi(const AVCodec* codec);

}  // namespace voca::decode::detail
