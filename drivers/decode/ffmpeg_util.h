#pragma once
// Small RAII and error helpers around libav* used inside drivers/ (decode, and the RGB writer in encode; not a public
// header).

#include <string>

#include "drivers/decode/demuxer.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/buffer.h>
#include <libavutil/error.h>
#include <libavutil/frame.h>
}

namespace voca::decode::detail {

// Name of libavcodec's V4L2 memory-to-memory decoder for a codec (nullptr if none).
const char* v4l2m2mDecoderName(VideoCodec codec);
AVCodecID avCodecId(VideoCodec codec);
// The decoder can use a VAAPI device context.
bool codecSupportsVaapi(const AVCodec* codec);

inline std::string avErrorText(int code) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(code, text, sizeof(text));
  return text;
}

struct CodecContextDeleter {
  void operator()(AVCodecContext* ctx) const { avcodec_free_context(&ctx); }
};
struct FrameDeleter {
  void operator()(AVFrame* frame) const { av_frame_free(&frame); }
};
struct PacketDeleter {
  void operator()(AVPacket* packet) const { av_packet_free(&packet); }
};
struct BufferDeleter {
  void operator()(AVBufferRef* buffer) const { av_buffer_unref(&buffer); }
};

}  // namespace voca::decode::detail
