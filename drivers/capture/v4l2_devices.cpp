#include "drivers/capture/v4l2_devices.h"

#include <fmt/core.h>
#include <linux/videodev2.h>

#include <algorithm>

#include "drivers/capture/pixel_format.h"

namespace voca::capture {

namespace {

double rateOf(const v4l2_fract& interval) {
  return interval.numerator > 0 ? static_cast<double>(interval.denominator) / interval.numerator : 0.0;
}

void enumerateRates(platform::V4l2Io& io, int fd, std::uint32_t fourcc, FrameSizeInfo& size) {
  v4l2_frmivalenum interval{};
  interval.pixel_format = fourcc;
  interval.width = static_cast<std::uint32_t>(size.width);
  interval.height = static_cast<std::uint32_t>(size.height);
  for (interval.index = 0; platform::xioctl(io, fd, VIDIOC_ENUM_FRAMEINTERVALS, &interval) == 0; ++interval.index) {
    if (interval.type == V4L2_FRMIVAL_TYPE_DISCRETE) {
      size.rates_hz.push_back(rateOf(interval.discrete));
      continue;
    }
    // Stepwise or continuous: the shortest interval is the fastest rate.
    size.rate_range = true;
    size.rates_hz = {rateOf(interval.stepwise.min), rateOf(interval.stepwise.max)};
    break;
  }
  if (!size.rate_range) std::sort(size.rates_hz.rbegin(), size.rates_hz.rend());
}

void enumerateSizes(platform::V4l2Io& io, int fd, PixelFormatInfo& format) {
  v4l2_frmsizeenum frame_size{};
  frame_size.pixel_format = format.fourcc;
  for (frame_size.index = 0; platform::xioctl(io, fd, VIDIOC_ENUM_FRAMESIZES, &frame_size) == 0; ++frame_size.index) {
    FrameSizeInfo size;
    if (frame_size.type == V4L2_FRMSIZE_TYPE_DISCRETE) {
      size.width = static_cast<int>(frame_size.discrete.width);
      size.height = static_cast<int>(frame_size.discrete.height);
    } else {
      const v4l2_frmsize_stepwise& s = frame_size.stepwise;
      size.stepwise = true;
      size.width = static_cast<int>(s.max_width);
      size.height = static_cast<int>(s.max_height);
      size.min_width = static_cast<int>(s.min_width);
      size.min_height = static_cast<int>(s.min_height);
      size.step_width = static_cast<int>(s.step_width);
      size.step_height = static_cast<int>(s.step_height);
    }
    enumerateRates(io, fd, format.fourcc, size);
    format.sizes.push_back(std::move(size));
    if (frame_size.type != V4L2_FRMSIZE_TYPE_DISCRETE) break;  // one range describes them all
  }
}

void enumerateFormats(platform::V4l2Io& io, int fd, V4l2DeviceInfo& info) {
  for (const platform::V4l2FormatDesc& description : platform::enumerateFormats(io, fd, V4L2_BUF_TYPE_VIDEO_CAPTURE)) {
    PixelFormatInfo format;
    format.fourcc = description.fourcc;
    format.description = description.description;
    format.gray_convertible = isGrayConvertible(format.fourcc);
    enumerateSizes(io, fd, format);
    info.formats.push_back(std::move(format));
  }
}

std::string formatRates(const FrameSizeInfo& size) {
  if (size.rates_hz.empty()) return "rate not reported";
  if (size.rate_range) return fmt::format("{:g}-{:g} fps", size.rates_hz[1], size.rates_hz[0]);
  std::string rates;
  for (const double rate : size.rates_hz) rates += fmt::format("{}{:g}", rates.empty() ? "" : " ", rate);
  return rates + " fps";
}

}  // namespace

bool isCameraNode(std::uint32_t capabilities) {
  const bool captures = (capabilities & V4L2_CAP_VIDEO_CAPTURE) != 0;
  return captures && !platform::isMemoryToMemory(capabilities) && (capabilities & V4L2_CAP_STREAMING) != 0;
}

std::vector<V4l2DeviceInfo> listCameras(platform::V4l2Io& io, std::vector<std::string>* skipped) {
  std::vector<V4l2DeviceInfo> cameras;
  platform::forEachV4l2Node(
      io,
      [&](int fd, const platform::V4l2NodeInfo& node) {
        if (!isCameraNode(node.capabilities)) return;
        V4l2DeviceInfo info;
        static_cast<platform::V4l2NodeInfo&>(info) = node;
        enumerateFormats(io, fd, info);
        cameras.push_back(std::move(info));
      },
      skipped);
  return cameras;
}

std::string unavailableDeviceMessage(platform::V4l2Io& io, const std::string& path, const std::string& reason) {
  std::string available;
  for (const V4l2DeviceInfo& camera : listCameras(io)) {
    if (camera.path == path) continue;
    available += fmt::format("{}{} ({}, {})", available.empty() ? "" : ", ", camera.path, camera.driver, camera.card);
  }
  return fmt::format("{}: {}; available: {}", path, reason, available.empty() ? "none found" : available);
}

std::string formatCameraList(const std::vector<V4l2DeviceInfo>& cameras) {
  std::string text;
  for (const V4l2DeviceInfo& camera : cameras) {
    text += fmt::format("{}: {} ({}, {})\n", camera.path, camera.card, camera.driver, camera.bus);
    for (const PixelFormatInfo& format : camera.formats) {
      text += fmt::format("  {} \"{}\"{}\n", platform::fourccName(format.fourcc), format.description,
                          format.gray_convertible ? "" : " (not usable: voca reads " + grayConvertibleList() + ")");
      for (const FrameSizeInfo& size : format.sizes) {
        if (size.stepwise) {
          text += fmt::format("    {}x{} to {}x{} in steps of {}x{}: {}\n", size.min_width, size.min_height, size.width,
                              size.height, size.step_width, size.step_height, formatRates(size));
        } else {
          text += fmt::format("    {}x{}: {}\n", size.width, size.height, formatRates(size));
        }
      }
    }
  }
  return text;
}

}  // namespace voca::capture
