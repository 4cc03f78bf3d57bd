#pragma once
// Live stereo cameras as a StereoSource (raw, live): two V4L2 devices paired by timestamp, or one
// side-by-side stereo device split into its left and right halves. Frames are converted to gray
// straight from the kernel's buffers into the caller's images (the pipeline's preallocated slots),
// so capture allocates nothing per frame.

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/capture/v4l2_camera.h"
#include "drivers/source/stereo_source.h"
#include "platform/v4l2/v4l2_io.h"

namespace voca::capture {

struct StereoCameraOptions {
  std::vector<std::string> devices;    // two (left, right), or one side-by-side stereo device
  CameraRequest request;               // for each device (side-by-side: the full width)
  std::int64_t pair_tolerance_ns = 0;  // 0: defaultPairTolerance() of the cameras' rate
  int frame_timeout_ms = 3000;         // no frame for this long is a failure (a stalled camera)
  std::int64_t max_frames = 0;         // stereo frames to deliver before next() returns false; 0: until stopped
};

// The cameras as people and programs name them (`voca live --camera ... --size ...`, the library's
// CameraInput).
struct CameraSettings {
  std::string devices;       // "LEFT,RIGHT" or one side-by-side device
  std::string size;          // "640x480"; empty: the device's current size
  std::string pixel_format;  // GREY, Y10, Y16, YUYV or NV12; empty: the first the device offers
  double fps = 0.0;          // 0: the device's current rate
  int exposure = -1;         // -1: automatic
  int gain = -1;             // -1: automatic
  double pair_tolerance_ms = 0.0;
  int buffers = 4;
  std::int64_t frames = 0;  // 0: until stopped
};

// Checks the settings (InputError naming the command-line option) and turns them into options.
StereoCameraOptions stereoCameraOptions(const CameraSettings& settings);

// Parses "640x480" (--size). InputError naming the option otherwise.
void parseFrameSize(std::string_view text, int& width, int& height);

// Parses a device list: "/dev/video0,/dev/video2" or "/dev/video0". InputError for empty entries
// or more than two devices.
std::vector<std::string> parseDeviceList(std::string_view text);

class CameraStereoSource : public StereoSource {
 public:
  // Opens the devices (nothing streams until the first next()). Throws InputError for a missing
  // device (naming those available), a format problem, two cameras of different sizes, or a
  // side-by-side device of odd width.
  explicit CameraStereoSource(const StereoCameraOptions& options, platform::V4l2Io& io = platform::systemV4l2Io());
  ~CameraStereoSource() override;

  const SourceInfo& info() const override { return info_; }
  // Waits for the next stereo pair. Throws RuntimeFailure when a device disappears, fails or
  // stalls for frame_timeout_ms; false after interrupt().
  bool next(RawStereoFrame& frame) override;
  void interrupt() override { interrupted_ = true; }
  SourceCounters counters() const override;

  // Problems that did not stop the capture (from the devices), for the user.
  std::vector<std::string> warnings() const override;
  std::int64_t pairToleranceNs() const { return tolerance_ns_; }

 private:
  bool fillPending(int timeout_ms);

  StereoCameraOptions options_;
  platform::V4l2Io& io_;
  std::vector<std::unique_ptr<V4l2Camera>> cameras_;
  bool side_by_side_ = false;
  SourceInfo info_;
  std::int64_t tolerance_ns_ = 0;
  std::array<CapturedBuffer, 2> pending_{};
  std::array<bool, 2> has_pending_{};
  bool started_ = false;
  bool have_first_sequence_ = false;
  std::uint32_t first_sequence_ = 0;
  std::int64_t delivered_ = 0;
  std::atomic<bool> interrupted_{false};
  std::atomic<std::int64_t> unpaired_{0};
  std::atomic<std::int64_t> frames_lost_{0};
};

}  // namespace voca::capture
