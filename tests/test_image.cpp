// PNG IO: round trips, conversions of other PNG flavours to 8-bit gray, and clear errors for bad files.

#include <png.h>

#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "formats/image/png_io.h"
#include "tests/test_support.h"
#include "voca/core/error.h"

namespace {

using voca::GrayImage;
using voca::Rgb8;
using voca::RgbImage;

GrayImage makeGradient(int width, int height) {
  GrayImage image(width, height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) image(x, y) = static_cast<std::uint8_t>((x * 7 + y * 13) & 0xff);
  }
  return image;
}

// Writes a PNG with libpng's simplified API in a format our writer never produces.
void writeWithLibpng(const std::filesystem::path& path, int width, int height, std::uint32_t format, const void* pixels,
                     const void* colormap = nullptr, int colormap_entries = 0) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  image.width = static_cast<png_uint_32>(width);
  image.height = static_cast<png_uint_32>(height);
  image.format = format;
  image.colormap_entries = static_cast<png_uint_32>(colormap_entries);
  REQUIRE(png_image_write_to_file(&image, path.c_str(), 0, pixels, 0, colormap) != 0);
}

std::string errorOf(const std::filesystem::path& path) {
  return voca::test::inputErrorOf([&] { voca::readPngGray(path); });
}

}  // namespace

TEST_CASE("gray PNG round trip is lossless, including strided views") {
  voca::test::ScratchDir dir("png-gray");
  const GrayImage image = makeGradient(37, 23);
  voca::writePngGray(dir / "a.png", image.view());
  const GrayImage back = voca::readPngGray(dir / "a.png");
  REQUIRE(back.width() == 37);
  REQUIRE(back.height() == 23);
  for (int y = 0; y < 23; ++y) {
    for (int x = 0; x < 37; ++x) REQUIRE(back(x, y) == image(x, y));
  }

  // A crop of the image is written from its strided view.
  voca::GrayView crop{&image(5, 3), 10, 8, image.stride()};
  voca::writePngGray(dir / "crop.png", crop);
  GrayImage reused(100, 100);  // the reader reuses a larger buffer
  voca::readPngGray(dir / "crop.png", reused);
  REQUIRE(reused.width() == 10);
  REQUIRE(reused.height() == 8);
  CHECK(reused(0, 0) == image(5, 3));
  CHECK(reused(9, 7) == image(14, 10));
}

TEST_CASE("RGB PNG round trip, read back as luma") {
  voca::test::ScratchDir dir("png-rgb");
  RgbImage image(4, 2);
  image(0, 0) = Rgb8{255, 0, 0};
  image(1, 0) = Rgb8{0, 255, 0};
  image(2, 0) = Rgb8{0, 0, 255};
  image(3, 0) = Rgb8{255, 255, 255};
  for (int x = 0; x < 4; ++x)
    image(x, 1) =
        Rgb8{static_cast<std::uint8_t>(60 * x), static_cast<std::uint8_t>(60 * x), static_cast<std::uint8_t>(60 * x)};
  voca::writePngRgb(dir / "rgb.png", image.view());

  // The file really is RGB: libpng's simplified reader returns the exact colours.
  png_image check{};
  check.version = PNG_IMAGE_VERSION;
  REQUIRE(png_image_begin_read_from_file(&check, (dir / "rgb.png").c_str()) != 0);
  CHECK((check.format & PNG_FORMAT_FLAG_COLOR) != 0);
  check.format = PNG_FORMAT_RGB;
  std::vector<std::uint8_t> rgb(PNG_IMAGE_SIZE(check));
  REQUIRE(png_image_finish_read(&check, nullptr, rgb.data(), 0, nullptr) != 0);
  CHECK(rgb[0] == 255);
  CHECK(rgb[1] == 0);
  CHECK(rgb[4] == 255);
  CHECK(rgb[8] == 255);

  // Luma with Rec. 709 weights (libpng's default: 0.2126 R + 0.7152 G + 0.0722 B); 1 grey level
  // allows for libpng's fixed-point rounding.
  const GrayImage gray = voca::readPngGray(dir / "rgb.png");
  CHECK(std::abs(gray(0, 0) - 54) <= 1);
  CHECK(std::abs(gray(1, 0) - 182) <= 1);
  CHECK(std::abs(gray(2, 0) - 18) <= 1);
  CHECK(gray(3, 0) == 255);
  for (int x = 0; x < 4; ++x) CHECK(gray(x, 1) == 60 * x);  // grey stays grey exactly
}

TEST_CASE("readPngRgb returns RGB files exactly and expands gray files") {
  voca::test::ScratchDir dir("png-read-rgb");
  RgbImage image(5, 3);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 5; ++x) {
      image(x, y) = Rgb8{static_cast<std::uint8_t>(50 * x), static_cast<std::uint8_t>(80 * y),
                         static_cast<std::uint8_t>(255 - 40 * x - y)};
    }
  }
  voca::writePngRgb(dir / "rgb.png", image.view());
  RgbImage back;
  voca::readPngRgb(dir / "rgb.png", back);
  REQUIRE(back.width() == 5);
  REQUIRE(back.height() == 3);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 5; ++x) {
      CHECK(back(x, y).r == image(x, y).r);
      CHECK(back(x, y).g == image(x, y).g);
      CHECK(back(x, y).b == image(x, y).b);
    }
  }

  GrayImage gray(3, 2);
  for (int i = 0; i < 6; ++i) gray.data()[i] = static_cast<std::uint8_t>(40 * i + 7);
  voca::writePngGray(dir / "gray.png", gray.view());
  voca::readPngRgb(dir / "gray.png", back);
  REQUIRE(back.width() == 3);
  for (int i = 0; i < 6; ++i) {
    const Rgb8 p = back.data()[i];
    CHECK((p.r == gray.data()[i] && p.g == gray.data()[i] && p.b == gray.data()[i]));
  }
  CHECK(voca::test::inputErrorOf([&] { voca::readPngRgb(dir / "missing.png", back); }).find("missing.png") !=
        std::string::npos);
}

TEST_CASE("16-bit, palette and RGBA PNGs are converted to 8-bit gray") {
  voca::test::ScratchDir dir("png-formats");
  SUBCASE("16-bit gray keeps the high byte") {
    const std::vector<std::uint16_t> pixels = {0, 255, 256, 0x1234, 0x80ff, 0xffff};
    writeWithLibpng(dir / "g16.png", 3, 2, PNG_FORMAT_LINEAR_Y, pixels.data());
    const GrayImage gray = voca::readPngGray(dir / "g16.png");
    REQUIRE(gray.width() == 3);
    for (int i = 0; i < 6; ++i) CHECK(gray(i % 3, i / 3) == (pixels[static_cast<std::size_t>(i)] >> 8));
  }
  SUBCASE("palette") {
    const std::uint8_t colormap[] = {0, 0, 0, 100, 100, 100, 255, 255, 255};
    const std::uint8_t indices[] = {0, 1, 2, 2, 1, 0};
    writeWithLibpng(dir / "pal.png", 3, 2, PNG_FORMAT_RGB | PNG_FORMAT_FLAG_COLORMAP, indices, colormap, 3);
    const GrayImage gray = voca::readPngGray(dir / "pal.png");
    const int expected[] = {0, 100, 255, 255, 100, 0};
    for (int i = 0; i < 6; ++i) CHECK(gray(i % 3, i / 3) == expected[i]);
  }
  SUBCASE("RGBA drops alpha") {
    const std::uint8_t rgba[] = {10, 10, 10, 0, 200, 200, 200, 255};
    writeWithLibpng(dir / "rgba.png", 2, 1, PNG_FORMAT_RGBA, rgba);
    const GrayImage gray = voca::readPngGray(dir / "rgba.png");
    CHECK(gray(0, 0) == 10);
    CHECK(gray(1, 0) == 200);
  }
}

TEST_CASE("missing and corrupt PNG files give errors naming the file") {
  voca::test::ScratchDir dir("png-bad");
  CHECK(errorOf(dir / "missing.png").find("missing.png") != std::string::npos);
  CHECK(errorOf(dir / "missing.png").find("cannot open") != std::string::npos);

  std::ofstream(dir / "text.png") << "this is not a png";
  CHECK(errorOf(dir / "text.png").find("text.png: not a PNG file") != std::string::npos);

  std::ofstream(dir / "empty.png").close();
  CHECK(errorOf(dir / "empty.png").find("empty.png: not a PNG file") != std::string::npos);

  // A valid file cut in the middle of the pixel data, and one with a damaged header chunk.
  const GrayImage image = makeGradient(64, 64);
  voca::writePngGray(dir / "good.png", image.view());
  std::ifstream in(dir / "good.png", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  REQUIRE(bytes.size() > 100);
  std::ofstream(dir / "truncated.png", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  CHECK(errorOf(dir / "truncated.png").find("truncated.png: corrupt PNG") != std::string::npos);
  std::string damaged = bytes;
  damaged[18] = static_cast<char>(damaged[18] ^ 0x5a);  // inside IHDR's width: the CRC no longer matches
  std::ofstream(dir / "damaged.png", std::ios::binary) << damaged;
  CHECK(errorOf(dir / "damaged.png").find("damaged.png: corrupt PNG") != std::string::npos);

  // Writing into a folder that does not exist names the file too.
  try {
    voca::writePngGray(dir / "no" / "such" / "dir.png", image.view());
    FAIL("expected an error");
  } catch (const voca::InputError& e) {
    CHECK(std::string(e.what()).find("dir.png") != std::string::npos);
  }
}
