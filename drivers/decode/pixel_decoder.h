#pragma once
// The decoder that makes a stream's pixels, as VideoDecoder sees it: libavcodec's send/receive
// protocol. The real ones are libavcodec contexts (software, VAAPI, V4L2 M2M); a test puts a
// stand-in behind the same interface to exercise how hardware pixels are paired with the software
// motion-vector parse (frames out of order, frames the device never returns).

struct AVFrame;
struct AVPacket;

namespace voca::decode {

class PixelDecoder {
 public:
  virtual ~PixelDecoder() = default;
  // One packet in decode order; nullptr signals the end of the stream. Returns 0, AVERROR(EAGAIN)
  // (frames must be received first) or an AVERROR code, as avcodec_send_packet does.
  virtual int send(const AVPacket* packet) = 0;
  // The next picture, its pts taken from the packet it came from. Returns 0, AVERROR(EAGAIN),
  // AVERROR_EOF or an AVERROR code, as avcodec_receive_frame does.
  virtual int receive(AVFrame* frame) = 0;
};

}  // namespace voca::decode
