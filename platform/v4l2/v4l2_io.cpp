#include "platform/v4l2/v4l2_io.h"

#include <fcntl.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <string_view>

namespace voca::platform {

namespace {

// The number after "video" in a node name; -1 for other names (video-codec links and the like).
int nodeNumber(std::string_view name) {
  constexpr std::string_view kPrefix = "video";
  if (name.substr(0, kPrefix.size()) != kPrefix || name.size() == kPrefix.size()) return -1;
  int number = 0;
  for (const char c : name.substr(kPrefix.size())) {
    if (c < '0' || c > '9') return -1;
    number = number * 10 + (c - '0');
  }
  return number;
}

class SystemV4l2Io final : public V4l2Io {
 public:
  std::vector<std::string> deviceNodes() override {
    std::vector<std::pair<int, std::string>> numbered;
    std::error_code error;
    for (const auto& entry : std::filesystem::directory_iterator("/dev", error)) {
      const int number = nodeNumber(entry.path().filename().string());
      if (number >= 0) numbered.emplace_back(number, entry.path().string());
    }
    std::sort(numbered.begin(), numbered.end());
    std::vector<std::string> nodes;
    for (auto& [number, path] : numbered) nodes.push_back(std::move(path));
    return nodes;
  }
  int open(const std::string& path, int flags) override { return ::open(path.c_str(), flags); }
  int close(int fd) override { return ::close(fd); }
  int ioctl(int fd, unsigned long request, void* argument) override { return ::ioctl(fd, request, argument); }
  void* mmap(std::size_t length, int fd, std::int64_t offset) override {
    return ::mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, static_cast<off_t>(offset));
  }
  int munmap(void* address, std::size_t length) override { return ::munmap(address, length); }
  int poll(pollfd* fds, nfds_t count, int timeout_ms) override { return ::poll(fds, count, timeout_ms); }
};

}  // namespace

V4l2Io& systemV4l2Io() {
  static SystemV4l2Io io;
  return io;
}

int xioctl(V4l2Io& io, int fd, unsigned long request, void* argument) {
  int result = 0;
  do {
    result = io.ioctl(fd, request, argument);
  } while (result == -1 && errno == EINTR);
  return result;
}

std::string fourccName(std::uint32_t fourcc) {
  std::string name(4, ' ');
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((fourcc >> (8 * i)) & 0xff);
    name[static_cast<std::size_t>(i)] = (c >= 32 && c < 127) ? c : '?';
  }
  while (!name.empty() && name.back() == ' ') name.pop_back();
  return name;
}

std::uint32_t fourcc(const char (&code)[5]) {
  return static_cast<std::uint32_t>(static_cast<unsigned char>(code[0])) |
         static_cast<std::uint32_t>(static_cast<unsigned char>(code[1])) << 8 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(code[2])) << 16 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(code[3])) << 24;
}

}  // namespace voca::platform
