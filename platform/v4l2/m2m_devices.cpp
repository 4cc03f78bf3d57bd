#include "platform/v4l2/m2m_devices.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>

namespace voca::platform {

namespace {

int retryIoctl(int fd, unsigned long request, void* arg) {
  int rc = 0;
  do {
    rc = ::ioctl(fd, request, arg);
  } while (rc < 0 && errno == EINTR);
  return rc;
}

// The compressed formats a queue lists.
std::vector<std::uint32_t> compressedFormats(int fd, std::uint32_t type) {
  std::vector<std::uint32_t> formats;
  for (std::uint32_t index = 0; index < 256; ++index) {
    v4l2_fmtdesc desc{};
    desc.index = index;
    desc.type = type;
    if (retryIoctl(fd, VIDIOC_ENUM_FMT, &desc) < 0) break;
    if ((desc.flags & V4L2_FMT_FLAG_COMPRESSED) != 0) formats.push_back(desc.pixelformat);
  }
  return formats;
}

void appendUnique(std::vector<std::uint32_t>& to, const std::vector<std::uint32_t>& from) {
  for (std::uint32_t f : from) {
    if (std::find(to.begin(), to.end(), f) == to.end()) to.push_back(f);
  }
}

}  // namespace

std::uint32_t fourcc(const char (&code)[5]) {
  return static_cast<std::uint32_t>(static_cast<unsigned char>(code[0])) |
         static_cast<std::uint32_t>(static_cast<unsigned char>(code[1])) << 8 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(code[2])) << 16 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(code[3])) << 24;
}

bool isM2mCodec(const V4l2NodeCaps& node, M2mRole role, std::uint32_t format) {
  if ((node.capabilities & (V4L2_CAP_VIDEO_M2M | V4L2_CAP_VIDEO_M2M_MPLANE)) == 0) return false;
  const auto& formats = role == M2mRole::kDecoder ? node.output_formats : node.capture_formats;
  return std::find(formats.begin(), formats.end(), format) != formats.end();
}

bool queryV4l2Node(const std::string& path, V4l2NodeCaps& caps) {
  const int fd = ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return false;
  v4l2_capability cap{};
  const bool ok = retryIoctl(fd, VIDIOC_QUERYCAP, &cap) == 0;
  if (ok) {
    caps.path = path;
    caps.driver.assign(reinterpret_cast<const char*>(cap.driver),
                       strnlen(reinterpret_cast<const char*>(cap.driver), sizeof(cap.driver)));
    // capabilities describes the whole physical device; device_caps this node.
    caps.capabilities = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
    caps.output_formats = compressedFormats(fd, V4L2_BUF_TYPE_VIDEO_OUTPUT);
    appendUnique(caps.output_formats, compressedFormats(fd, V4L2_BUF_TYPE_VIDEO_OUTPUT_MPLANE));
    caps.capture_formats = compressedFormats(fd, V4L2_BUF_TYPE_VIDEO_CAPTURE);
    appendUnique(caps.capture_formats, compressedFormats(fd, V4L2_BUF_TYPE_VIDEO_CAPTURE_MPLANE));
  }
  ::close(fd);
  return ok;
}

std::vector<std::string> findM2mCodecNodes(M2mRole role, std::uint32_t format) {
  std::vector<std::string> nodes;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/dev", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("video", 0) != 0) continue;
    V4l2NodeCaps caps;
    if (queryV4l2Node(entry.path().string(), caps) && isM2mCodec(caps, role, format)) nodes.push_back(caps.path);
  }
  std::sort(nodes.begin(), nodes.end());
  return nodes;
}

}  // namespace voca::platform
