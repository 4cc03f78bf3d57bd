#include "drivers/capture/pixel_format.h"

#include <fmt/core.h>
#include <linux/videodev2.h>

#include <cstring>

#include "platform/v4l2/v4l2_io.h"
#include "voca/core/error.h"

namespace voca::capture {

namespace {
constexpr std::uint32_t kFormats[] = {V4L2_PIX_FMT_GREY, V4L2_PIX_FMT_Y10, V4L2_PIX_FMT_Y16, V4L2_PIX_FMT_YUYV,
                                      V4L2_PIX_FMT_NV12};
}  // namespace

bool isGrayConvertible(std::uint32_t fourcc) {
  for (const std::uint32_t f : kFormats) {
    if (f == fourcc) return true;
  }
  return false;
}

const std::uint32_t* grayConvertibleFormats(std::size_t& count) {
  count = std::size(kFormats);
  return kFormats;
}

std::string grayConvertibleList() {
  std::string list;
  for (const std::uint32_t f : kFormats) list += (list.empty() ? "" : ", ") + platform::fourccName(f);
  return list;
}

std::uint32_t parseGrayConvertibleFormat(std::string_view text) {
  for (const std::uint32_t f : kFormats) {
    if (platform::fourccName(f) == text) return f;
  }
  throw InputError(fmt::format("pixel format \"{}\": expected one of {}", text, grayConvertibleList()));
}

std::size_t frameBytes(std::uint32_t fourcc, std::size_t bytes_per_line, int height) {
  const std::size_t luma = bytes_per_line * static_cast<std::size_t>(height);
  return fourcc == V4L2_PIX_FMT_NV12 ? luma + luma / 2 : luma;
}

void convertToGray(const std::uint8_t* data, std::size_t bytes_used, std::uint32_t fourcc, std::size_t bytes_per_line,
                   int x0, int width, int height, GrayImage& out) {
  if (!isGrayConvertible(fourcc)) {
    throw InputError(fmt::format("pixel format {} is not supported (expected {})", platform::fourccName(fourcc),
                                 grayConvertibleList()));
  }
  // Only the luma rows are read, so a buffer holding them is enough even for NV12.
  const std::size_t needed = bytes_per_line * static_cast<std::size_t>(height);
  if (bytes_used < needed) {
    throw InputError(fmt::format("captured {} frame holds {} bytes, {} needed for {} lines of {} bytes",
                                 platform::fourccName(fourcc), bytes_used, needed, height, bytes_per_line));
  }
  out.resize(width, height);
  const auto first = static_cast<std::size_t>(x0);
  for (int y = 0; y < height; ++y) {
    const std::uint8_t* line = data + static_cast<std::size_t>(y) * bytes_per_line;
    std::uint8_t* dst = out.row(y);
    switch (fourcc) {
      case V4L2_PIX_FMT_GREY:
      case V4L2_PIX_FMT_NV12:  // the Y plane comes first, one byte per pixel
        std::memcpy(dst, line + first, static_cast<std::size_t>(width));
        break;
      case V4L2_PIX_FMT_Y10:  // little-endian 16-bit words, 10 significant bits
        for (int x = 0; x < width; ++x) {
          const std::uint8_t* p = line + 2 * (first + static_cast<std::size_t>(x));
          dst[x] = static_cast<std::uint8_t>(((p[1] & 0x03) << 6) | (p[0] >> 2));
        }
        break;
      case V4L2_PIX_FMT_Y16:  // little-endian 16-bit words: the high byte is the top 8 bits
        for (int x = 0; x < width; ++x) dst[x] = line[2 * (first + static_cast<std::size_t>(x)) + 1];
        break;
      case V4L2_PIX_FMT_YUYV:  // Y0 U Y1 V: luma at every even byte
        for (int x = 0; x < width; ++x) dst[x] = line[2 * (first + static_cast<std::size_t>(x))];
        break;
      default:
        break;
    }
  }
}

}  // namespace voca::capture
