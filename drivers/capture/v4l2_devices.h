#pragma once
// V4L2 cameras: which of the nodes platform/v4l2/v4l2_nodes.h discovers are cameras (video capture,
// not memory-to-memory codecs or metadata nodes), and the formats, frame sizes and frame rates
// they offer (ENUM_FRAMESIZES, ENUM_FRAMEINTERVALS on top of the shared QUERYCAP and ENUM_FMT).

#include <cstdint>
#include <string>
#include <vector>

#include "platform/v4l2/v4l2_io.h"
#include "platform/v4l2/v4l2_nodes.h"

namespace voca::capture {

struct FrameSizeInfo {
  int width = 0, height = 0;  // a discrete size, or the largest of a stepwise range
  bool stepwise = false;      // any size from min to the above in steps
  int min_width = 0, min_height = 0, step_width = 0, step_height = 0;
  std::vector<double> rates_hz;  // discrete rates, fastest first; a range as {max, min} when rate_range
  bool rate_range = false;
};

struct PixelFormatInfo {
  std::uint32_t fourcc = 0;
  std::string description;  // the driver's, e.g. "YUYV 4:2:2"
  bool gray_convertible = false;
  std::vector<FrameSizeInfo> sizes;
};

// A camera node: what QUERYCAP says, and its capture formats.
struct V4l2DeviceInfo : platform::V4l2NodeInfo {
  std::vector<PixelFormatInfo> formats;
};

// True for a node that captures video: V4L2_CAP_VIDEO_CAPTURE and not a memory-to-memory device.
bool isCameraNode(std::uint32_t capabilities);

// Every camera node with its formats, sizes and rates. Nodes that cannot be opened (busy, no
// permission) are listed in skipped as "path: reason".
std::vector<V4l2DeviceInfo> listCameras(platform::V4l2Io& io, std::vector<std::string>* skipped = nullptr);

// The message for a device that cannot be used as a camera, with what can:
// "/dev/video2: no such device; available: /dev/video0 (uvcvideo, HD Webcam)" or "...; none found".
std::string unavailableDeviceMessage(platform::V4l2Io& io, const std::string& path, const std::string& reason);

// `voca devices`' listing: one block per camera, formats with sizes and rates.
std::string formatCameraList(const std::vector<V4l2DeviceInfo>& cameras);

}  // namespace voca::capture
