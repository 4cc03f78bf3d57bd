#include "drivers/decode/picture_pool.h"

#include <algorithm>
#include <climits>
#include <cstddef>

extern "C" {
#include <libavutil/imgutils.h>
#include <libavutil/pixdesc.h>
}

namespace voca::decode {

namespace {

// libavcodec's default pads each plane by 16 + STRIDE_ALIGN - 1 bytes (the decoders' SIMD edge reads);
// 64 is the widest STRIDE_ALIGN of any build.
constexpr std::size_t kPlanePadding = 16 + 64 - 1;
// The most pictures a fill takes: 16 references and 16 waiting for output, with room to spare.
constexpr int kMaxFill = 40;

}  // namespace

PicturePool::PicturePool(int held_outside) : held_outside_(std::max(held_outside, 0)) {}

PicturePool::~PicturePool() { release(); }

void PicturePool::release() {
  // Buffers still referenced (a frame outliving the decoder) are freed when they come back.
  for (AVBufferPool*& plane : planes_) av_buffer_pool_uninit(&plane);
  linesize_ = {};
  format_ = -1;
  width_ = height_ = 0;
  filled_ = 0;
}

bool PicturePool::attach(AVCodecContext* ctx) {
  if (ctx->codec == nullptr || (ctx->codec->capabilities & AV_CODEC_CAP_DR1) == 0) return false;
  ctx->opaque = this;
  ctx->get_buffer2 = &PicturePool::getBuffer;
  return true;
}

int PicturePool::h264DecoderPictures(int refs, int reorder) {
  constexpr int kMaxDpbFrames = 16;
  return std::clamp(refs, 1, kMaxDpbFrames) + std::clamp(reorder, 0, kMaxDpbFrames) + 2;
}

AVBufferRef* PicturePool::allocatePicture(void* opaque, std::size_t size) {
  // Zeroed as libavcodec's default does, which also makes the pages resident now rather than later.
  AVBufferRef* buffer = av_buffer_allocz(size);
  if (buffer != nullptr) static_cast<PicturePool*>(opaque)->allocated_.fetch_add(1, std::memory_order_relaxed);
  return buffer;
}

int PicturePool::getBuffer(AVCodecContext* ctx, AVFrame* frame, int flags) {
  return static_cast<PicturePool*>(ctx->opaque)->get(ctx, frame, flags);
}

int PicturePool::configure(AVCodecContext* ctx, const AVFrame& frame) {
  release();
  const auto format = static_cast<AVPixelFormat>(frame.format);
  int w = frame.width, h = frame.height;
  int stride_align[AV_NUM_DATA_POINTERS] = {};
  avcodec_align_dimensions2(ctx, &w, &h, stride_align);
  // As libavcodec's default: widen until every plane's linesize meets its alignment (aligning the
  // linesizes one by one would break the ratios between the planes' linesizes).
  int linesize[4] = {};
  for (bool unaligned = true; unaligned;) {
    if (const int rc = av_image_fill_linesizes(linesize, format, w); rc < 0) return rc;
    w += w & ~(w - 1);
    unaligned = false;
    for (int i = 0; i < 4; ++i) unaligned |= stride_align[i] > 0 && linesize[i] % stride_align[i] != 0;
  }
  ptrdiff_t linesize_wide[4] = {};
  std::copy(std::begin(linesize), std::end(linesize), std::begin(linesize_wide));
  std::size_t size[4] = {};
  if (const int rc = av_image_fill_plane_sizes(size, format, h, linesize_wide); rc < 0) return rc;
  for (int i = 0; i < 4 && size[i] > 0; ++i) {
    if (size[i] > static_cast<std::size_t>(INT_MAX) - kPlanePadding) return AVERROR(EINVAL);
    // Plane 0's pool counts the pictures; the other planes come with it.
    planes_[i] = i == 0 ? av_buffer_pool_init2(size[i] + kPlanePadding, this, &PicturePool::allocatePicture, nullptr)
                        : av_buffer_pool_init(size[i] + kPlanePadding, av_buffer_allocz);
    if (planes_[i] == nullptr) return AVERROR(ENOMEM);
    linesize_[i] = linesize[i];
  }
  format_ = frame.format;
  width_ = frame.width;
  height_ = frame.height;
  // Called at the decoder's first picture, once it has parsed the stream's headers.
  int pictures = 3;  // MPEG-4 Part 2, MPEG-2 without B-frames: two references and the current picture
  if (ctx->codec_id == AV_CODEC_ID_H264) pictures = h264DecoderPictures(ctx->refs, ctx->has_b_frames);
  return fill(std::min(pictures + held_outside_, kMaxFill));
}

int PicturePool::fill(int pictures) {
  // Buffers taken from a pool and given back stay in it.
  std::array<AVBufferRef*, kMaxFill> taken{};
  int rc = 0;
  for (AVBufferPool* plane : planes_) {
    if (plane == nullptr) continue;
    int n = 0;
    for (; n < pictures; ++n) {
      taken[static_cast<std::size_t>(n)] = av_buffer_pool_get(plane);
      if (taken[static_cast<std::size_t>(n)] == nullptr) {
        rc = AVERROR(ENOMEM);
        break;
      }
    }
    for (int k = 0; k < n; ++k) av_buffer_unref(&taken[static_cast<std::size_t>(k)]);
    if (rc < 0) return rc;
  }
  filled_ = pictures;
  return 0;
}

int PicturePool::get(AVCodecContext* ctx, AVFrame* frame, int flags) {
  const AVPixFmtDescriptor* desc = av_pix_fmt_desc_get(static_cast<AVPixelFormat>(frame->format));
  // Hardware frames and paletted formats: libavcodec's own allocation knows them.
  if (ctx->codec_type != AVMEDIA_TYPE_VIDEO || desc == nullptr ||
      (desc->flags & (AV_PIX_FMT_FLAG_HWACCEL | AV_PIX_FMT_FLAG_PAL)) != 0) {
    return avcodec_default_get_buffer2(ctx, frame, flags);
  }
  if (frame->format != format_ || frame->width != width_ || frame->height != height_) {
    if (const int rc = configure(ctx, *frame); rc < 0) {
      release();
      return rc;
    }
  }
  for (std::size_t i = 0; i < AV_NUM_DATA_POINTERS; ++i) {
    frame->data[i] = nullptr;
    frame->linesize[i] = 0;
  }
  for (std::size_t i = 0; i < planes_.size() && planes_[i] != nullptr; ++i) {
    frame->buf[i] = av_buffer_pool_get(planes_[i]);
    if (frame->buf[i] == nullptr) {
      for (std::size_t k = 0; k < i; ++k) {
        av_buffer_unref(&frame->buf[k]);
        frame->data[k] = nullptr;
        frame->linesize[k] = 0;
      }
      return AVERROR(ENOMEM);
    }
    frame->data[i] = frame->buf[i]->data;
    frame->linesize[i] = linesize_[i];
  }
  frame->extended_data = frame->data;
  return 0;
}

}  // namespace voca::decode
