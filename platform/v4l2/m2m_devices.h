#pragma once
// V4L2 memory-to-memory codec nodes. A webcam, a capture card or an ISP node is also a
// /dev/video*, so a hardware codec is recognised by what the node says it is (VIDIOC_QUERYCAP:
// memory-to-memory) and by the compressed format on the right queue (VIDIOC_ENUM_FMT): a decoder
// takes H.264 on its OUTPUT queue (what the application writes), an encoder gives H.264 on its
// CAPTURE queue.

#include <cstdint>
#include <string>
#include <vector>

#include "platform/v4l2/v4l2_io.h"
#include "platform/v4l2/v4l2_nodes.h"

namespace voca::platform {

enum class M2mRole { kDecoder, kEncoder };

// What one node reported: QUERYCAP, and its compressed formats (single- and multi-planar queues).
struct V4l2NodeCaps : V4l2NodeInfo {
  std::vector<std::uint32_t> output_formats;   // compressed formats accepted on the OUTPUT queue
  std::vector<std::uint32_t> capture_formats;  // compressed formats given on the CAPTURE queue
};

// True when the node is a memory-to-memory device (single- or multi-planar) that decodes or
// encodes `format` as asked. Pure, so the rule is testable without devices.
bool isM2mCodec(const V4l2NodeCaps& node, M2mRole role, std::uint32_t format);

// Asks one node (open, VIDIOC_QUERYCAP, VIDIOC_ENUM_FMT on both queues, close). False when the
// node cannot be opened or is not a V4L2 device.
bool queryV4l2Node(const std::string& path, V4l2NodeCaps& caps, V4l2Io& io = systemV4l2Io());

// Every /dev/video* node that is a memory-to-memory codec for `format` in `role`, in node number
// order (found with forEachV4l2Node, as the cameras are).
std::vector<std::string> findM2mCodecNodes(M2mRole role, std::uint32_t format, V4l2Io& io = systemV4l2Io());

}  // namespace voca::platform
