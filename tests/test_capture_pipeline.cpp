// Live cameras through the staged VO pipeline: the fake device paced in real time feeds
// runVisualOdometryOnCameras, a deliberately slow sink makes the live policy drop frames, and
// every frame the cameras delivered is either completed or counted as dropped.

#include <doctest/doctest.h>

#include <chrono>
#include <thread>

#include "formats/calib/calibration_io.h"
#include "pipeline/vo/camera_runner.h"
#include "platform/filesystem/temp_dir.h"
#include "tests/fake_v4l2.h"
#include "tests/test_frontend_support.h"
#include "tests/test_support.h"
#include "voca/core/error.h"

using namespace voca;
using namespace voca::pipeline;

namespace {

constexpr int kWidth = 160, kHeight = 120;

// Takes longer per frame than the cameras' interval, as an overloaded board would.
class SlowSink final : public FrameSink {
 public:
  void consume(const FrameSlot& /*slot*/) override { std::this_thread::sleep_for(std::chrono::milliseconds(25)); }
};

// Two paced cameras at 100 Hz.
void addPacedCameras(test::FakeV4l2& io) {
  test::FakeCameraSpec left, right;
  left.path = "/dev/video0";
  right.path = "/dev/video2";
  left.sizes = right.sizes = {{kWidth, kHeight}};
  left.formats = right.formats = {V4L2_PIX_FMT_YUYV};
  left.rates_hz = right.rates_hz = {100.0};
  left.paced = right.paced = true;
  io.add(left);
  io.add(right);
}

}  // namespace

TEST_CASE("live cameras run through the pipeline with the live policy: nothing waits, every frame is accounted") {
  test::FakeV4l2 io;
  test::FakeCameraSpec spec;  // one side-by-side device, so the driver's sequence counts every frame made
  spec.sizes = {{2 * kWidth, kHeight}};
  spec.formats = {V4L2_PIX_FMT_YUYV};
  spec.rates_hz = {100.0};
  spec.paced = true;
  io.add(spec);
  TempDir dir("voca-capture-test");
  const auto calibration = dir.path() / "calib.json";
  saveBasaltCalibration(test::pinholeRig(kWidth, kHeight, 150.0, 0.1), calibration);

  CameraRunOptions options;
  options.cameras.devices = {"/dev/video0"};
  options.cameras.max_frames = 30;
  options.calibration = calibration;
  options.run.estimate = false;  // the frontend is enough to exercise the live path; the fake scene has no depth
  options.run.progress = false;
  options.run.pipeline_options.stop_requested = [] { return false; };
  SlowSink slow;
  options.run.extra_sinks = {&slow};
  const VoRunResult result = runVisualOdometryOnCameras(options, io);

  REQUIRE_FALSE(result.pipeline_report.error.has_value());
  CHECK(result.pipeline_report.produced == 30);
  CHECK(result.pipeline_report.completed + result.pipeline_report.dropped == result.pipeline_report.produced);
  CHECK(result.frames == result.pipeline_report.completed);
  // 25 ms per frame against 10 ms between frames: the camera outruns the pipeline. The frames it made
  // that the pipeline never took were lost in the driver (its buffers were full), none queued up:
  // every sequence number is a frame produced or a frame counted lost.
  CHECK(result.source.frames_lost > 15);
  CHECK(static_cast<std::int64_t>(io.lastSequence("/dev/video0")) + 1 ==
        result.pipeline_report.produced + result.source.frames_lost);
  CHECK(result.description.find("side-by-side stereo camera /dev/video0") != std::string::npos);
  CHECK(io.openHandles() == 0);
  CHECK(io.mappedBuffers() == 0);
}

TEST_CASE("a camera size that differs from the calibration is rejected before streaming") {
  test::FakeV4l2 io;
  addPacedCameras(io);
  TempDir dir("voca-capture-test");
  const auto calibration = dir.path() / "calib.json";
  saveBasaltCalibration(test::pinholeRig(320, 240, 150.0, 0.1), calibration);
  CameraRunOptions options;
  options.cameras.devices = {"/dev/video0", "/dev/video2"};
  options.calibration = calibration;
  options.run.progress = false;
  test::expectError(test::inputErrorOf([&] { runVisualOdometryOnCameras(options, io); }),
                    "images are 160x120 but the calibration");
  CHECK(io.openHandles() == 0);
}

TEST_CASE("a camera that disappears mid-run ends the run with the error and everything estimated so far") {
  test::FakeV4l2 io;
  test::FakeCameraSpec spec;
  spec.sizes = {{2 * kWidth, kHeight}};
  spec.rates_hz = {100.0};
  spec.paced = true;
  spec.vanish_after_frames = 15;
  io.add(spec);
  TempDir dir("voca-capture-test");
  const auto calibration = dir.path() / "calib.json";
  saveBasaltCalibration(test::pinholeRig(kWidth, kHeight, 150.0, 0.1), calibration);
  CameraRunOptions options;
  options.cameras.devices = {"/dev/video0"};
  options.calibration = calibration;
  options.run.estimate = false;
  options.run.progress = false;
  options.run.pipeline_options.stop_requested = [] { return false; };
  const VoRunResult result = runVisualOdometryOnCameras(options, io);
  REQUIRE(result.pipeline_report.error.has_value());
  test::expectError(result.pipeline_report.error->message, "/dev/video0: the device disappeared after 15 frames");
  CHECK(result.pipeline_report.produced == 15);
  // The live policy may drop a waiting frame when the frontend falls behind (a loaded machine); every
  // frame taken before the device vanished is estimated or counted dropped, none silently discarded.
  INFO("completed " << result.pipeline_report.completed << ", dropped " << result.pipeline_report.dropped);
  CHECK(result.frames == result.pipeline_report.completed);
  CHECK(result.pipeline_report.completed + result.pipeline_report.dropped == 15);
}
