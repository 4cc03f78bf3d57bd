#pragma once
// Images: an owning buffer allocated once (Image) and a non-owning strided view (ImageView).

#include <cassert>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace voca {

// A non-owning view of a 2-D pixel array. stride is in pixels, so a view can describe a crop or
// a decoder's padded plane without copying.
template <typename Pixel>
struct ImageView {
  Pixel* data = nullptr;
  int width = 0;
  int height = 0;
  std::ptrdiff_t stride = 0;

  Pixel* row(int y) const {
    assert(y >= 0 && y < height);
    return data + static_cast<std::ptrdiff_t>(y) * stride;
  }
  Pixel& operator()(int x, int y) const {
    assert(x >= 0 && x < width);
    return row(y)[x];
  }
  bool contains(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
  bool empty() const { return width <= 0 || height <= 0; }
  operator ImageView<const Pixel>() const { return {data, width, height, stride}; }
};

// An owning, contiguous image. resize() reuses the buffer when it is large enough, so a
// per-frame resize to the same size never allocates.
template <typename Pixel>
class Image {
 public:
  Image() = default;
  Image(int width, int height) { resize(width, height); }
  Image(int width, int height, Pixel fill) {
    resize(width, height);
    setTo(fill);
  }

  void resize(int width, int height) {
    assert(width >= 0 && height >= 0);
    const std::size_t needed = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    if (needed > buffer_.size()) buffer_.resize(needed);
    width_ = width;
    height_ = height;
  }
  // Reserve room for images up to this size so later resize() calls do not allocate.
  void reserve(int max_width, int max_height) {
    buffer_.reserve(static_cast<std::size_t>(max_width) * static_cast<std::size_t>(max_height));
  }
  void setTo(Pixel value) {
    for (std::size_t i = 0, n = pixelCount(); i < n; ++i) buffer_[i] = value;
  }

  int width() const { return width_; }
  int height() const { return height_; }
  std::ptrdiff_t stride() const { return width_; }
  std::size_t pixelCount() const { return static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_); }
  bool empty() const { return width_ == 0 || height_ == 0; }

  Pixel* data() { return buffer_.data(); }
  const Pixel* data() const { return buffer_.data(); }
  Pixel* row(int y) { return buffer_.data() + static_cast<std::ptrdiff_t>(y) * width_; }
  const Pixel* row(int y) const { return buffer_.data() + static_cast<std::ptrdiff_t>(y) * width_; }
  Pixel& operator()(int x, int y) { return row(y)[x]; }
  const Pixel& operator()(int x, int y) const { return row(y)[x]; }

  ImageView<Pixel> view() { return {buffer_.data(), width_, height_, width_}; }
  ImageView<const Pixel> view() const { return {buffer_.data(), width_, height_, width_}; }

 private:
  std::vector<Pixel> buffer_;
  int width_ = 0;
  int height_ = 0;
};

// An 8-bit RGB pixel, for visualisations (overlays, motion-vector pictures).
struct Rgb8 {
  std::uint8_t r = 0, g = 0, b = 0;
};

using GrayImage = Image<std::uint8_t>;
using GrayView = ImageView<const std::uint8_t>;
using RgbImage = Image<Rgb8>;
using RgbView = ImageView<const Rgb8>;

}  // namespace voca
