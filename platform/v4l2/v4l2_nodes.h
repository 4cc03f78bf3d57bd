#pragma once
// V4L2 device discovery, the one place that walks the /dev/video* nodes and asks each what it is:
// VIDIOC_QUERYCAP (driver, card, bus, the node's capabilities) and VIDIOC_ENUM_FMT (the formats of
// one queue). Cameras (drivers/capture) and memory-to-memory codecs (m2m_devices.h) are both found
// through it, by the capabilities each needs. Everything goes through V4l2Io, so tests run it
// against an in-process fake device.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "platform/v4l2/v4l2_io.h"

namespace voca::platform {

// What VIDIOC_QUERYCAP says about one node.
struct V4l2NodeInfo {
  std::string path;
  std::string driver, card, bus;
  std::uint32_t capabilities = 0;  // the node's own (device_caps when the driver reports them)
};

// True for a memory-to-memory node (single- or multi-planar): a codec or a converter, never a camera.
bool isMemoryToMemory(std::uint32_t capabilities);

// One entry of VIDIOC_ENUM_FMT.
struct V4l2FormatDesc {
  std::uint32_t fourcc = 0;
  std::string description;  // the driver's, e.g. "YUYV 4:2:2"
  bool compressed = false;  // V4L2_FMT_FLAG_COMPRESSED
};

// The node's QUERYCAP names and capabilities (device_caps when V4L2_CAP_DEVICE_CAPS is set); path
// is left as it was. False, with errno set, when fd is not a V4L2 device.
bool queryCapabilities(V4l2Io& io, int fd, V4l2NodeInfo& info);

// Every format the queue of buffer_type (V4L2_BUF_TYPE_*) lists, in the driver's order; empty when
// the node has no such queue.
std::vector<V4l2FormatDesc> enumerateFormats(V4l2Io& io, int fd, std::uint32_t buffer_type);

// Opens every /dev/video* node (io.deviceNodes(), in number order) read/write and non-blocking,
// queries it and calls visit with the open descriptor for each V4L2 device, closing it afterwards.
// Nodes that cannot be opened (busy, no permission) are listed in skipped as "path: reason".
void forEachV4l2Node(V4l2Io& io, const std::function<void(int fd, const V4l2NodeInfo& info)>& visit,
                     std::vector<std::string>* skipped = nullptr);

}  // namespace voca::platform
