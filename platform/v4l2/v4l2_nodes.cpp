#include "platform/v4l2/v4l2_nodes.h"

#include <fcntl.h>
#include <linux/videodev2.h>

#include <cerrno>
#include <cstring>

namespace voca::platform {

namespace {

std::string cString(const std::uint8_t* text, std::size_t size) {
  const auto* begin = reinterpret_cast<const char*>(text);
  return std::string(begin, strnlen(begin, size));
}

}  // namespace

bool isMemoryToMemory(std::uint32_t capabilities) {
  return (capabilities & (V4L2_CAP_VIDEO_M2M | V4L2_CAP_VIDEO_M2M_MPLANE)) != 0;
}

bool queryCapabilities(V4l2Io& io, int fd, V4l2NodeInfo& info) {
  v4l2_capability capability{};
  if (xioctl(io, fd, VIDIOC_QUERYCAP, &capability) != 0) return false;
  info.driver = cString(capability.driver, sizeof(capability.driver));
  info.card = cString(capability.card, sizeof(capability.card));
  info.bus = cString(capability.bus_info, sizeof(capability.bus_info));
  // A driver with several nodes reports the whole device in capabilities and the node's in device_caps.
  info.capabilities =
      (capability.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? capability.device_caps : capability.capabilities;
  return true;
}

std::vector<V4l2FormatDesc> enumerateFormats(V4l2Io& io, int fd, std::uint32_t buffer_type) {
  std::vector<V4l2FormatDesc> formats;
  v4l2_fmtdesc description{};
  description.type = buffer_type;
  // The bound guards against a driver that never ends the list.
  for (description.index = 0; description.index < 256 && xioctl(io, fd, VIDIOC_ENUM_FMT, &description) == 0;
       ++description.index) {
    formats.push_back({description.pixelformat, cString(description.description, sizeof(description.description)),
                       (description.flags & V4L2_FMT_FLAG_COMPRESSED) != 0});
  }
  return formats;
}

void forEachV4l2Node(V4l2Io& io, const std::function<void(int fd, const V4l2NodeInfo& info)>& visit,
                     std::vector<std::string>* skipped) {
  for (const std::string& path : io.deviceNodes()) {
    const int fd = io.open(path, O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
      if (skipped) skipped->push_back(path + ": " + std::strerror(errno));
      continue;
    }
    V4l2NodeInfo info;
    info.path = path;
    if (queryCapabilities(io, fd, info)) {
      try {
        visit(fd, info);
      } catch (...) {
        io.close(fd);
        throw;
      }
    }
    io.close(fd);
  }
}

}  // namespace voca::platform
