#include "voca/image/draw.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace voca {

namespace {

int nearestPixel(float v) { return static_cast<int>(std::lround(v)); }

}  // namespace

void grayToRgb(const GrayImage& gray, RgbImage& out) {
  out.resize(gray.width(), gray.height());
  for (int y = 0; y < gray.height(); ++y) {
    for (int x = 0; x < gray.width(); ++x) {
      const std::uint8_t v = gray(x, y);
      out(x, y) = Rgb8{v, v, v};
    }
  }
}

void putPixel(RgbImage& image, int x, int y, Rgb8 colour) {
  if (x >= 0 && y >= 0 && x < image.width() && y < image.height()) image(x, y) = colour;
}

void drawLine(RgbImage& image, Eigen::Vector2f a, Eigen::Vector2f b, Rgb8 colour) {
  if (!a.allFinite() || !b.allFinite()) return;
  if ((b - a).norm() > 4.0f * static_cast<float>(image.width() + image.height())) return;
  int x = nearestPixel(a.x()), y = nearestPixel(a.y());
  const int x_end = nearestPixel(b.x()), y_end = nearestPixel(b.y());
  const int dx = std::abs(x_end - x), dy = -std::abs(y_end - y);
  const int step_x = x < x_end ? 1 : -1, step_y = y < y_end ? 1 : -1;
  int err = dx + dy;
  while (true) {
    putPixel(image, x, y, colour);
    if (x == x_end && y == y_end) break;
    const int twice_err = 2 * err;
    if (twice_err >= dy) {
      err += dy;
      x += step_x;
    }
    if (twice_err <= dx) {
      err += dx;
      y += step_y;
    }
  }
}

void drawArrow(RgbImage& image, Eigen::Vector2f from, Eigen::Vector2f to, Rgb8 colour) {
  drawLine(image, from, to, colour);
  const float length = (to - from).norm();
  if (!(length >= 1.5f)) return;
  const float head = std::min(4.0f, 0.4f * length);
  const Eigen::Vector2f back = (from - to) / length;
  constexpr float kCos = 0.866f, kSin = 0.5f;  // 30 degree barbs
  drawLine(image, to, to + head * Eigen::Vector2f(kCos * back.x() - kSin * back.y(), kSin * back.x() + kCos * back.y()),
           colour);
  drawLine(image, to,
           to + head * Eigen::Vector2f(kCos * back.x() + kSin * back.y(), -kSin * back.x() + kCos * back.y()), colour);
}

void drawCross(RgbImage& image, Eigen::Vector2f p, int r, Rgb8 colour) {
  const int x = nearestPixel(p.x()), y = nearestPixel(p.y());
  for (int d = -r; d <= r; ++d) {
    putPixel(image, x + d, y + d, colour);
    putPixel(image, x + d, y - d, colour);
  }
}

void drawCircle(RgbImage& image, Eigen::Vector2f p, float r, Rgb8 colour) {
  constexpr float kTwoPi = 6.28318531f;
  const int n = static_cast<int>(std::ceil(kTwoPi * r));
  for (int i = 0; i < n; ++i) {
    const float angle = kTwoPi * static_cast<float>(i) / static_cast<float>(n);
    putPixel(image, nearestPixel(p.x() + r * std::cos(angle)), nearestPixel(p.y() + r * std::sin(angle)), colour);
  }
}

}  // namespace voca
