#pragma once
// Picture memory for a software libavcodec decoder, allocated when the first picture is. libavcodec's
// default get_buffer2 keeps a pool per context that grows whenever the decoder holds one picture more
// than ever before, and keeps it: a damaged keyframe, for one, makes an H.264 decoder hold a third
// picture where a clean stream needs two, possibly hours into a run, and resident memory steps up
// then. This pool is filled at the first picture with as many pictures as the decoder can hold for
// its stream, so a decoder's picture memory reaches its peak at the start; not a public header.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/buffer.h>
}

namespace voca::decode {

class PicturePool {
 public:
  // held_outside: decoded pictures its user keeps referenced besides the decoder's own (the frame last
  // received, until the next receive).
  explicit PicturePool(int held_outside);
  ~PicturePool();
  PicturePool(const PicturePool&) = delete;
  PicturePool& operator=(const PicturePool&) = delete;

  // Makes ctx (not yet opened) take its pictures from this pool; false when its codec does not accept
  // caller-allocated pictures (no AV_CODEC_CAP_DR1), which keeps libavcodec's default. The pool must
  // outlive ctx; one pool serves one context.
  bool attach(AVCodecContext* ctx);

  // Pictures allocated so far: the fill at the first picture, plus any the decoder needed beyond it.
  std::int64_t allocated() const { return allocated_.load(std::memory_order_relaxed); }
  // Pictures the pool was filled with at the first picture of the current size (0 before it).
  int filled() const { return filled_; }

  // Pictures libavcodec's H.264 decoder can hold at once: its references (it drops any beyond the
  // SPS's count, even in a damaged stream), the pictures waiting in its reorder queue, the one being
  // decoded, and the reference it keeps across a keyframe to conceal that keyframe's damage with.
  static int h264DecoderPictures(int refs, int reorder);

 private:
  static AVBufferRef* allocatePicture(void* opaque, std::size_t size);
  static int getBuffer(AVCodecContext* ctx, AVFrame* frame, int flags);
  int get(AVCodecContext* ctx, AVFrame* frame, int flags);
  // Sets the plane layout for pictures like `frame` and fills the pool; an AVERROR code on failure.
  int configure(AVCodecContext* ctx, const AVFrame& frame);
  int fill(int pictures);
  void release();

  int held_outside_ = 0;
  int format_ = -1, width_ = 0, height_ = 0;
  std::array<AVBufferPool*, 4> planes_{};  // one pool per plane, as libavcodec's default
  std::array<int, 4> linesize_{};
  int filled_ = 0;
  std::atomic<std::int64_t> allocated_{0};
};

}  // namespace voca::decode
