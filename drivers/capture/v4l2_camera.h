#pragma once
// One V4L2 camera streaming into memory-mapped kernel buffers: opens the node, negotiates a format
// the gray converter reads, sets the frame rate and exposure/gain controls, and hands out filled
// buffers with their kernel timestamps (CLOCK_MONOTONIC) and sequence numbers. Buffers are mapped
// once at construction; streaming allocates nothing.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "platform/v4l2/v4l2_io.h"

namespace voca::capture {

// Sensor controls passed to the device when it has them (VIDIOC_QUERYCTRL / VIDIOC_S_CTRL), in the
// device's own units (UVC: exposure in 100 us steps).
struct CaptureControls {
  std::optional<int> exposure;  // switches automatic exposure off
  std::optional<int> gain;
};

// What to ask the device for; zeros take the device's current setting.
struct CameraRequest {
  int width = 0, height = 0;
  std::uint32_t fourcc = 0;  // 0: the first of GREY, Y10, Y16, YUYV, NV12 the device offers
  double rate_hz = 0.0;
  int buffers = 4;  // kernel buffers: enough to ride out one slow frame, few enough for low latency
  CaptureControls controls;
};

// The format the device agreed to.
struct CameraFormat {
  int width = 0, height = 0;
  std::uint32_t fourcc = 0;
  std::size_t bytes_per_line = 0;
  std::size_t image_bytes = 0;
  double rate_hz = 0.0;  // 0 when the device does not report one
};

// A filled buffer, owned by the caller until requeue().
struct CapturedBuffer {
  const std::uint8_t* data = nullptr;
  std::size_t bytes_used = 0;
  std::int64_t t_ns = 0;       // CLOCK_MONOTONIC (kernel timestamp, or dequeue time; see monotonicTimestamps())
  std::uint32_t sequence = 0;  // the driver's frame counter; a gap means the driver dropped frames
  int index = -1;
};

class V4l2Camera {
 public:
  // Opens path (non-blocking) and prepares streaming. Throws InputError for a missing node or one
  // that is not a camera (naming the cameras that exist), an unsupported format or size, or a
  // control the device lacks or a value outside its range; RuntimeFailure when the kernel refuses.
  V4l2Camera(platform::V4l2Io& io, std::string path, const CameraRequest& request);
  ~V4l2Camera();
  V4l2Camera(const V4l2Camera&) = delete;
  V4l2Camera& operator=(const V4l2Camera&) = delete;

  void start();  // queues every buffer and turns streaming on
  void stop();   // streaming off (idempotent; a vanished device is not an error here)

  int fd() const { return fd_; }
  const std::string& path() const { return path_; }
  const CameraFormat& format() const { return format_; }
  const std::string& driver() const { return driver_; }
  const std::string& card() const { return card_; }
  // False when the driver stamps buffers with another clock: t_ns is then the dequeue time.
  bool monotonicTimestamps() const { return monotonic_; }
  // Frames the driver dropped (gaps in the sequence numbers) since start().
  std::int64_t framesLost() const { return frames_lost_; }
  std::int64_t framesDequeued() const { return dequeued_; }
  // Problems that did not stop the camera (rate not settable, timestamps not monotonic).
  const std::vector<std::string>& warnings() const { return warnings_; }
  // One line: "/dev/video0 (uvcvideo, HD Webcam) 640x480 YUYV 30 fps".
  std::string description() const;

  // Takes a filled buffer if one is ready: false when none is (EAGAIN). Throws RuntimeFailure when
  // the device reports an error, naming ENODEV as the device having disappeared.
  bool dequeue(CapturedBuffer& buffer);
  // Gives a buffer back to the driver.
  void requeue(const CapturedBuffer& buffer);

 private:
  struct Mapping {
    void* address = nullptr;
    std::size_t length = 0;
  };
  void negotiateFormat(const CameraRequest& request);
  void setRate(double rate_hz);
  void applyControls(const CaptureControls& controls);
  void setControl(std::uint32_t id, int value, const char* what);
  [[noreturn]] void fail(const std::string& call) const;

  platform::V4l2Io& io_;
  std::string path_;
  int fd_ = -1;
  std::string driver_, card_;
  CameraFormat format_;
  std::vector<Mapping> mappings_;
  bool streaming_ = false;
  bool monotonic_ = true;
  bool warned_clock_ = false;
  bool have_sequence_ = false;
  std::uint32_t last_sequence_ = 0;
  std::int64_t frames_lost_ = 0;
  std::int64_t dequeued_ = 0;
  std::vector<std::string> warnings_;
};

}  // namespace voca::capture
