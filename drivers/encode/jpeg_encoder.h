#pragma once
// RGB pictures -> JPEG (baseline, 4:2:0) with libavcodec's MJPEG encoder, for the live view's image
// channel. The encoder and its buffers are made once for one picture size.

#include <cstdint>
#include <memory>
#include <span>

#include "voca/core/image.h"

namespace voca::encode {

class JpegEncoder {
 public:
  // quality: libavcodec's quantiser scale, 2 (best, largest) to 31. Pictures must be width x height;
  // an odd last column or row is left out (4:2:0 needs even sizes). Throws RuntimeFailure when
  // libavcodec has no MJPEG encoder.
  JpegEncoder(int width, int height, int quality = 5);
  ~JpegEncoder();
  JpegEncoder(const JpegEncoder&) = delete;
  JpegEncoder& operator=(const JpegEncoder&) = delete;

  // The JPEG file of the picture; valid until the next call. Throws InputError for a picture of
  // another size, RuntimeFailure when encoding fails.
  std::span<const std::uint8_t> encode(RgbView picture);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace voca::encode
