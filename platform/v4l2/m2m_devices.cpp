#include "platform/v4l2/m2m_devices.h"

#include <fcntl.h>
#include <linux/videodev2.h>

#include <algorithm>

namespace voca::platform {

namespace {

// The compressed formats of the node's queues of both buffer types (single- and multi-planar).
std::vector<std::uint32_t> compressedFormats(V4l2Io& io, int fd, std::uint32_t type, std::uint32_t mplane_type) {
  std::vector<std::uint32_t> formats;
  for (const std::uint32_t t : {type, mplane_type}) {
    for (const V4l2FormatDesc& format : enumerateFormats(io, fd, t)) {
      if (format.compressed && std::find(formats.begin(), formats.end(), format.fourcc) == formats.end()) {
        formats.push_back(format.fourcc);
      }
    }
  }
  return formats;
}

void readCodecFormats(V4l2Io& io, int fd, V4l2NodeCaps& caps) {
  caps.output_formats = compressedFormats(io, fd, V4L2_BUF_TYPE_VIDEO_OUTPUT, V4L2_BUF_TYPE_VIDEO_OUTPUT_MPLANE);
  caps.capture_formats = compressedFormats(io, fd, V4L2_BUF_TYPE_VIDEO_CAPTURE, V4L2_BUF_TYPE_VIDEO_CAPTURE_MPLANE);
}

}  // namespace

bool isM2mCodec(const V4l2NodeCaps& node, M2mRole role, std::uint32_t format) {
  if (!isMemoryToMemory(node.capabilities)) return false;
  const auto& formats = role == M2mRole::kDecoder ? node.output_formats : node.capture_formats;
  return std::find(formats.begin(), formats.end(), format) != formats.end();
}

bool queryV4l2Node(const std::string& path, V4l2NodeCaps& caps, V4l2Io& io) {
  const int fd = io.open(path, O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return false;
  caps.path = path;
  const bool ok = queryCapabilities(io, fd, caps);
  if (ok) readCodecFormats(io, fd, caps);
  io.close(fd);
  return ok;
}

std::vector<std::string> findM2mCodecNodes(M2mRole role, std::uint32_t format, V4l2Io& io) {
  std::vector<std::string> nodes;
  forEachV4l2Node(io, [&](int fd, const V4l2NodeInfo& info) {
    if (!isMemoryToMemory(info.capabilities)) return;  // cameras and the like: no need to list their formats
    V4l2NodeCaps caps;
    static_cast<V4l2NodeInfo&>(caps) = info;
    readCodecFormats(io, fd, caps);
    if (isM2mCodec(caps, role, format)) nodes.push_back(caps.path);
  });
  return nodes;
}

}  // namespace voca::platform
