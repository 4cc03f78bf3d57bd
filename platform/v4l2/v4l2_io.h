#pragma once
// The thin seam between the V4L2 code and the kernel: the six system calls capture needs,
// plus the list of device nodes. The system implementation calls the kernel; tests put an
// in-process fake device behind the same interface that speaks the real <linux/videodev2.h>
// protocol. Every call reports failure as the system call does: -1 (MAP_FAILED for mmap) and errno.

#include <poll.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace voca::platform {

class V4l2Io {
 public:
  virtual ~V4l2Io() = default;

  // The /dev/video* nodes present, sorted by number (/dev/video2 before /dev/video10).
  virtual std::vector<std::string> deviceNodes() = 0;

  virtual int open(const std::string& path, int flags) = 0;
  virtual int close(int fd) = 0;
  virtual int ioctl(int fd, unsigned long request, void* argument) = 0;
  virtual void* mmap(std::size_t length, int fd, std::int64_t offset) = 0;  // shared, read/write
  virtual int munmap(void* address, std::size_t length) = 0;
  virtual int poll(pollfd* fds, nfds_t count, int timeout_ms) = 0;
};

// The kernel.
V4l2Io& systemV4l2Io();

// ioctl retried while it is interrupted by a signal (EINTR), as V4L2 applications must.
int xioctl(V4l2Io& io, int fd, unsigned long request, void* argument);

// "YUYV" for V4L2_PIX_FMT_YUYV: the four characters of a fourcc code.
std::string fourccName(std::uint32_t fourcc);

// The fourcc code of four characters ("H264", "MPG4", "MPG2"): fourccName's inverse.
std::uint32_t fourcc(const char (&code)[5]);

}  // namespace voca::platform
