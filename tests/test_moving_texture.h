#pragma once
// A test video's frames: a smooth texture moving 1.5 px right and 0.5 px down per frame, so an
// encoder's P-frames carry motion vectors.

#include <cmath>
#include <cstdint>

#include "voca/core/image.h"

namespace voca::test {

inline GrayImage movingTexture(int width, int height, int frame) {
  GrayImage image(width, height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const double u = x - 1.5 * frame, v = y - 0.5 * frame;
      image(x, y) = static_cast<std::uint8_t>(128.0 + 60.0 * std::sin(0.31 * u + 0.11 * v) +
                                              50.0 * std::cos(0.07 * u - 0.23 * v));
    }
  return image;
}

}  // namespace voca::test
