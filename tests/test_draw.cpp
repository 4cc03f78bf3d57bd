#include <doctest/doctest.h>

#include <cmath>
#include <cstdlib>
#include <limits>

#include "voca/image/draw.h"

namespace {

constexpr voca::Rgb8 kInk{255, 0, 0};

bool inked(const voca::RgbImage& image, int x, int y) { return image(x, y).r == 255; }

int countInked(const voca::RgbImage& image) {
  int n = 0;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x) n += inked(image, x, y) ? 1 : 0;
  return n;
}

voca::RgbImage blank(int w, int h) {
  voca::RgbImage image(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) image(x, y) = {0, 0, 0};
  return image;
}

}  // namespace

TEST_CASE("drawLine: known pixels of horizontal, diagonal and steep lines") {
  voca::RgbImage image = blank(10, 10);
  voca::drawLine(image, {1.f, 2.f}, {5.f, 2.f}, kInk);
  CHECK(countInked(image) == 5);
  for (int x = 1; x <= 5; ++x) CHECK(inked(image, x, 2));

  image = blank(10, 10);
  voca::drawLine(image, {7.f, 7.f}, {3.2f, 2.8f}, kInk);  // endpoints round to (7,7) and (3,3)
  CHECK(countInked(image) == 5);
  for (int d = 3; d <= 7; ++d) CHECK(inked(image, d, d));

  // A steep line has one pixel per row, each touching the one before (8-connected).
  image = blank(10, 10);
  voca::drawLine(image, {2.f, 0.f}, {4.f, 9.f}, kInk);
  CHECK(countInked(image) == 10);
  int previous_x = 2;
  for (int y = 0; y < 10; ++y) {
    int row = 0, x_in_row = -1;
    for (int x = 0; x < 10; ++x) {
      if (inked(image, x, y)) {
        ++row;
        x_in_row = x;
      }
    }
    CHECK(row == 1);
    CHECK(std::abs(x_in_row - previous_x) <= 1);
    previous_x = x_in_row;
  }
  CHECK(inked(image, 4, 9));
}

TEST_CASE("drawLine clips to the image and skips absurd lines") {
  voca::RgbImage image = blank(8, 8);
  voca::drawLine(image, {-3.f, 4.f}, {20.f, 4.f}, kInk);  // crosses the whole image
  CHECK(countInked(image) == 8);

  image = blank(8, 8);
  voca::drawLine(image, {1.f, 1.f}, {1e7f, 1e7f}, kInk);  // a point lost far away: not drawn
  voca::drawLine(image, {1.f, 1.f}, {std::numeric_limits<float>::quiet_NaN(), 1.f}, kInk);
  CHECK(countInked(image) == 0);

  image = blank(8, 8);
  voca::drawLine(image, {3.f, 3.f}, {3.f, 3.f}, kInk);  // a point
  CHECK(countInked(image) == 1);
}

TEST_CASE("drawArrow, drawCross and drawCircle stay where they are put") {
  voca::RgbImage image = blank(20, 20);
  voca::drawArrow(image, {2.f, 10.f}, {12.f, 10.f}, kInk);
  for (int x = 2; x <= 12; ++x) CHECK(inked(image, x, 10));
  CHECK(countInked(image) > 11);  // the head adds barbs behind the tip, above and below the shaft
  CHECK(inked(image, 9, 8));
  CHECK(inked(image, 9, 12));

  image = blank(20, 20);
  voca::drawCross(image, {10.f, 10.f}, 2, kInk);
  CHECK(countInked(image) == 9);  // two diagonals of 5 sharing the centre
  CHECK(inked(image, 8, 8));
  CHECK(inked(image, 12, 8));

  image = blank(20, 20);
  voca::drawCircle(image, {10.f, 10.f}, 4.f, kInk);
  for (int y = 0; y < 20; ++y) {
    for (int x = 0; x < 20; ++x) {
      if (!inked(image, x, y)) continue;
      const double r = std::hypot(x - 10.0, y - 10.0);
      CHECK(r == doctest::Approx(4.0).epsilon(0.2));  // rounding to pixels moves a point < 0.71 px
    }
  }
  CHECK(inked(image, 14, 10));
  CHECK(inked(image, 10, 14));
}

TEST_CASE("grayToRgb: every pixel becomes its gray level in all three channels") {
  voca::GrayImage gray(5, 3);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x) gray(x, y) = static_cast<std::uint8_t>(40 * y + 7 * x);
  voca::RgbImage rgb;
  voca::grayToRgb(gray, rgb);
  REQUIRE(rgb.width() == 5);
  REQUIRE(rgb.height() == 3);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 5; ++x) {
      const std::uint8_t v = gray(x, y);
      CHECK((rgb(x, y).r == v && rgb(x, y).g == v && rgb(x, y).b == v));
    }
  }
}
