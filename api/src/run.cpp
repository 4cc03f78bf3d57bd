#include "voca_rt/run.h"

#include <fmt/core.h>

#include "api/src/api_internal.h"
#include "drivers/capture/camera_source.h"
#include "drivers/encode/video_encoder.h"
#include "pipeline/sinks/view_sink.h"
#include "pipeline/vo/camera_runner.h"
#include "pipeline/vo/vo_runner.h"

namespace voca_rt {

namespace pl = voca::pipeline;

namespace {

void requireFileCalibration(const Options& options, const char* call) {
  if (!options.calibration.cameras.empty()) {
    throw voca::InputError(fmt::format(
        "{}: give the calibration as a file (Options::calibration_file); a calibration value is for pushed frames",
        call));
  }
}

// The view's server for the whole call, started before the input opens.
std::unique_ptr<voca::view::FoxgloveServer> startView(pl::VoRunOptions& run) {
  if (run.view.address.empty()) return nullptr;
  std::unique_ptr<voca::view::FoxgloveServer> server =
      pl::startViewServer(run.view.address, run.view.image_rate_hz, stderr);
  run.view.server = server.get();
  return server;
}

}  // namespace

Summary run(const Input& input, const Options& options, const PoseCallback& on_pose) {
  return detail::translated([&] {
    requireFileCalibration(options, "run()");
    pl::VoRunOptions run = detail::runOptions(options, input.realtime, input.speed);
    run.input = input.path;
    if (!options.calibration_file.empty()) run.calibration = options.calibration_file;
    if (!input.ground_truth.empty()) run.ground_truth = input.ground_truth;
    if (input.first_frame < 0) {
      throw voca::InputError("--start-frame: expected 0 (the first frame) or a positive index");
    }
    if (input.max_frames < 0) throw voca::InputError("--frames: expected 0 (all) or a positive count");
    run.first_frame = input.first_frame;
    run.max_frames = input.max_frames;
    if (!input.encode_bitrate.empty()) run.encode_bitrate_bps = voca::encode::parseBitrate(input.encode_bitrate);
    // A day at most: a deadline of inf or 1e300 s overflowed and ended the wait at once.
    constexpr double kMaxWaitS = 86400.0;
    if (!(input.stream_timeout_s > 0.0 && input.stream_timeout_s <= kMaxWaitS) ||
        !(input.stream_wait_s > 0.0 && input.stream_wait_s <= kMaxWaitS)) {
      throw voca::InputError("--stream-timeout and --stream-wait: expected seconds above 0 and at most 86400 (a day)");
    }
    run.stream_timeout_s = input.stream_timeout_s;
    run.stream_start_timeout_s = input.stream_wait_s;
    // Bound before the input is opened or encoded: a port in use fails at once, with nothing written.
    const std::unique_ptr<voca::view::FoxgloveServer> view = startView(run);
    detail::PoseSink sink(on_pose, 0);
    run.extra_sinks = {&sink};
    return detail::summary(pl::runVisualOdometry(run), options.estimate);
  });
}

Summary runCameras(const CameraInput& cameras, const Options& options, const PoseCallback& on_pose) {
  return detail::translated([&] {
    requireFileCalibration(options, "runCameras()");
    pl::CameraRunOptions camera;
    voca::capture::CameraSettings settings;
    settings.devices = cameras.devices;
    settings.size = cameras.size;
    settings.pixel_format = cameras.pixel_format;
    settings.fps = cameras.fps;
    settings.exposure = cameras.exposure;
    settings.gain = cameras.gain;
    settings.pair_tolerance_ms = cameras.pair_tolerance_ms;
    settings.buffers = cameras.buffers;
    settings.frames = cameras.max_frames;
    camera.cameras = voca::capture::stereoCameraOptions(settings);
    if (options.calibration_file.empty()) {
      throw voca::InputError("--calib: live cameras need their stereo calibration");
    }
    camera.calibration = options.calibration_file;
    if (!options.config.empty()) camera.config = options.config;
    camera.run = detail::runOptions(options);
    const std::unique_ptr<voca::view::FoxgloveServer> view = startView(camera.run);
    detail::PoseSink sink(on_pose, 0);
    camera.run.extra_sinks = {&sink};
    return detail::summary(pl::runVisualOdometryOnCameras(camera), options.estimate);
  });
}

}  // namespace voca_rt
