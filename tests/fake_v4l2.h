#pragma once
// An in-process fake of V4L2 camera devices behind the capture seam (platform/v4l2/v4l2_io.h).
// It speaks the kernel protocol with the real <linux/videodev2.h> structs: QUERYCAP, ENUM_FMT,
// ENUM_FRAMESIZES, ENUM_FRAMEINTERVALS, G/S_FMT, G/S_PARM, QUERYCTRL/S_CTRL, REQBUFS, QUERYBUF,
// mmap, QBUF/DQBUF, STREAMON/OFF and poll, rejecting calls out of protocol order as a driver does.
// Frames carry a known gray pattern (fakePixel) encoded in the device's pixel format, so a test can
// check the conversion exactly. A device can drop frames, stamp with a non-monotonic clock, pace
// frames at its rate in real time, or disappear mid-stream (ENODEV).

#include <linux/videodev2.h>

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "platform/v4l2/v4l2_io.h"

namespace voca::test {

struct FakeCameraSpec {
  std::string path = "/dev/video0";
  std::string driver = "fakecam", card = "Fake Camera", bus = "platform:fake";
  std::uint32_t capabilities = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;  // the node's device_caps
  std::vector<std::uint32_t> formats = {V4L2_PIX_FMT_GREY};
  // A memory-to-memory codec node (capabilities V4L2_CAP_VIDEO_M2M*) lists these compressed formats
  // (V4L2_FMT_FLAG_COMPRESSED) on its OUTPUT queue (a decoder's input) or after `formats` on its
  // CAPTURE queue (an encoder's output), single- and multi-planar alike.
  std::vector<std::uint32_t> compressed_output, compressed_capture;
  std::vector<std::pair<int, int>> sizes = {{64, 48}};  // offered for every format; the first is current
  std::vector<double> rates_hz = {30.0};                // offered for every size; the first is current
  std::size_t line_padding = 0;                         // bytes after each line (bytesperline > width)
  std::int64_t first_t_ns = 1'000'000'000;              // timestamp of sequence 0 (unpaced)
  std::int64_t offset_ns = 0;                           // added to every timestamp (stereo skew)
  std::vector<std::uint32_t> dropped_sequences;         // the "driver" skips these sequence numbers
  bool monotonic = true;                                // else V4L2_BUF_FLAG_TIMESTAMP_UNKNOWN
  bool paced = false;            // frames become ready at the rate in real time, stamped with CLOCK_MONOTONIC
  bool busy = false;             // open fails with EBUSY (another process holds it)
  int vanish_after_frames = -1;  // the device disappears (ENODEV) after delivering this many frames
  bool has_exposure = false, has_gain = false;
  int exposure_min = 1, exposure_max = 5000;
  int gain_min = 0, gain_max = 255;
};

// The gray value at (x, y) of frame `sequence`: textured and moving, so the tracker finds corners.
std::uint8_t fakePixel(int x, int y, std::uint32_t sequence);

class FakeV4l2 final : public platform::V4l2Io {
 public:
  FakeV4l2();
  ~FakeV4l2() override;
  void add(const FakeCameraSpec& spec);
  // Makes a device vanish now (as unplugging does): open fails, a streaming handle gets ENODEV.
  void unplug(const std::string& path);

  // What the driver side saw, for assertions.
  std::optional<int> control(const std::string& path, std::uint32_t id) const;
  int openHandles() const;
  int mappedBuffers() const;
  std::uint32_t lastSequence(const std::string& path) const;

  std::vector<std::string> deviceNodes() override;
  int open(const std::string& path, int flags) override;
  int close(int fd) override;
  int ioctl(int fd, unsigned long request, void* argument) override;
  void* mmap(std::size_t length, int fd, std::int64_t offset) override;
  int munmap(void* address, std::size_t length) override;
  int poll(pollfd* fds, nfds_t count, int timeout_ms) override;

 private:
  struct Device;
  struct Handle;
  Handle* handle(int fd);
  std::map<std::string, std::unique_ptr<Device>> devices_;
  std::map<int, std::unique_ptr<Handle>> handles_;
  int next_fd_ = 100;
};

}  // namespace voca::test
