#pragma once
// V4L2 memory-to-memory codec nodes. A webcam, a capture card or an ISP node is also a
// /dev/video*, so a hardware codec is recognised by what the node says it is (VIDIOC_QUERYCAP:
// memory-to-memory) and by the compressed format on the right queue (VIDIOC_ENUM_FMT): a decoder
// takes H.264 on its OUTPUT queue (what the application writes), an encoder gives H.264 on its
// CAPTURE queue.

#include <cstdint>
#include <string>
#include <vector>

namespace voca::platform {

enum class M2mRole { kDecoder, kEncoder };

// What one node reported.
struct V4l2NodeCaps {
  std::string path;
  std::string driver;
  std::uint32_t capabilities = 0;              // the node's own (device_caps when the driver has them)
  std::vector<std::uint32_t> output_formats;   // compressed formats accepted on the OUTPUT queue
  std::vector<std::uint32_t> capture_formats;  // compressed formats given on the CAPTURE queue
};

// The V4L2 four-character code of a compressed format ("H264", "MPG4", "MPG2").
std::uint32_t fourcc(const char (&code)[5]);

// True when the node is a memory-to-memory device (single- or multi-planar) that decodes or
// encodes `format` as asked. Pure, so the rule is testable without devices.
bool isM2mCodec(const V4l2NodeCaps& node, M2mRole role, std::uint32_t format);

// Asks one node (open, VIDIOC_QUERYCAP, VIDIOC_ENUM_FMT on both queues, close). False when the
// node cannot be opened or is not a V4L2 device.
bool queryV4l2Node(const std::string& path, V4l2NodeCaps& caps);

// Every /dev/video* node that is a memory-to-memory codec for `format` in `role`, sorted by path.
std::vector<std::string> findM2mCodecNodes(M2mRole role, std::uint32_t format);

}  // namespace voca::platform
