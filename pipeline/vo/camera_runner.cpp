#include "pipeline/vo/camera_runner.h"

#include <fmt/core.h>

#include <string_view>

#ifdef VOCA_HAVE_LIBCAMERA
#include "drivers/capture/libcamera_source.h"
#endif
#include "formats/calib/calibration_io.h"
#include "voca/core/error.h"

namespace voca::pipeline {

namespace {

constexpr std::string_view kLibcameraPrefix = "libcamera:";

}  // namespace

std::unique_ptr<StereoSource> openCameras(const capture::StereoCameraOptions& options, platform::V4l2Io& io) {
  std::size_t libcamera = 0;
  for (const std::string& device : options.devices) libcamera += device.starts_with(kLibcameraPrefix) ? 1 : 0;
  if (libcamera == 0) return std::make_unique<capture::CameraStereoSource>(options, io);
  if (libcamera != options.devices.size()) {
    throw InputError("--camera: use either V4L2 devices or libcamera cameras for both sides, not one of each");
  }
#ifdef VOCA_HAVE_LIBCAMERA
  capture::LibcameraStereoOptions lc;
  for (const std::string& device : options.devices) lc.cameras.push_back(device.substr(kLibcameraPrefix.size()));
  lc.width = options.request.width;
  lc.height = options.request.height;
  lc.rate_hz = options.request.rate_hz;
  lc.controls = options.request.controls;
  lc.buffers = options.request.buffers;
  lc.pair_tolerance_ns = options.pair_tolerance_ns;
  lc.frame_timeout_ms = options.frame_timeout_ms;
  lc.max_frames = options.max_frames;
  if (options.request.fourcc != 0) throw InputError("--pixel-format: libcamera cameras choose their own format");
  return std::make_unique<capture::LibcameraStereoSource>(lc);
#else
  throw InputError(
      fmt::format("{}: this voca was built without libcamera (VOCA_WITH_LIBCAMERA=OFF; install "
                  "libcamera-dev and rebuild)",
                  options.devices[0]));
#endif
}

VoRunResult runVisualOdometryOnCameras(const CameraRunOptions& options, platform::V4l2Io& io) {
  // Calibration and config first: a typo there should not wait for the cameras to open.
  const StereoRig rig = loadCalibration(options.calibration);
  rig.requireStereo();
  const RunConfig config = resolveRunConfig(options.config);
  const std::unique_ptr<StereoSource> source = openCameras(options.cameras, io);
  VoRunResult result = runVisualOdometryOn(*source, rig, config.config, options.run);
  result.config_name = config.name;
  const std::vector<std::string> warnings = source->warnings();
  result.warnings.insert(result.warnings.begin(), warnings.begin(), warnings.end());
  if (!options.run.statistics_file.empty()) writeStatisticsJson(result, options.run.statistics_file);
  return result;
}

CameraRecordResult recordFromCameras(const CameraRecordOptions& options, platform::V4l2Io& io) {
  const std::unique_ptr<StereoSource> source = openCameras(options.cameras, io);
  const double fps = options.fps > 0.0                      ? options.fps
                     : source->info().nominal_rate_hz > 0.0 ? source->info().nominal_rate_hz
                                                            : 30.0;
  encode::RecordOptions record;
  record.encoder = options.encoder;
  encode::setFrameRate(record.encoder, fps);
  record.calibration = options.calibration;
  record.stop_requested = options.stop_requested;
  record.progress = options.progress;
  encode::silenceCodecLogs();  // libx264 prints its settings at info level otherwise
  CameraRecordResult result;
  result.description = source->info().description;
  result.report = encode::recordStereo(*source, options.out, record);
  result.warnings = source->warnings();
  return result;
}

}  // namespace voca::pipeline
