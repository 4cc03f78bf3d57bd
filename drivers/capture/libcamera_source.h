#pragma once
// libcamera cameras as a live StereoSource (Raspberry Pi camera modules and other CSI sensors whose
// ISP is only reachable through libcamera): camera manager, stream configuration, a request loop
// with buffers mapped once at start, and the same output as the V4L2 source: gray frames with the
// sensor's CLOCK_MONOTONIC timestamps, two cameras paired by timestamp or one side-by-side split.
// Compiled when VOCA_WITH_LIBCAMERA is on (VOCA_HAVE_LIBCAMERA is then defined).

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "drivers/capture/v4l2_camera.h"
#include "drivers/source/stereo_source.h"

namespace voca::capture {

struct LibcameraCameraInfo {
  std::string id;     // libcamera's id, e.g. "/base/axi/pcie@120000/rp1/i2c@88000/imx708@1a"
  std::string model;  // e.g. "imx708"
};

// Starts a camera manager and lists its cameras (none on a machine without any). Throws
// RuntimeFailure when the manager cannot start.
std::vector<LibcameraCameraInfo> listLibcameraCameras();

struct LibcameraStereoOptions {
  std::vector<std::string> cameras;  // two (left, right) or one side-by-side: an index ("0") or an id
  int width = 0, height = 0;         // 0: the camera's default for video
  double rate_hz = 0.0;              // 0: the camera's default
  CaptureControls controls;          // exposure in microseconds, gain as analogue gain
  int buffers = 4;
  std::int64_t pair_tolerance_ns = 0;  // 0: defaultPairTolerance()
  int frame_timeout_ms = 3000;
  std::int64_t max_frames = 0;
};

class LibcameraStereoSource : public StereoSource {
 public:
  // Acquires and configures the cameras. InputError for a camera that does not exist (naming those
  // that do, or "none found"), a size the camera cannot deliver or cameras of different sizes.
  explicit LibcameraStereoSource(const LibcameraStereoOptions& options);
  ~LibcameraStereoSource() override;

  const SourceInfo& info() const override;
  bool next(RawStereoFrame& frame) override;
  void interrupt() override;
  SourceCounters counters() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace voca::capture
