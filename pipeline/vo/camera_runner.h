#pragma once
// Live visual odometry from V4L2 cameras (`voca live`): opens the cameras, loads the calibration and
// config, and runs the staged pipeline on the live source. Live input runs with the live policy: a
// stage that falls behind drops the oldest waiting frame (counted) instead of building a backlog.

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivers/capture/camera_source.h"
#include "drivers/encode/video_folder_writer.h"
#include "pipeline/vo/vo_runner.h"
#include "platform/v4l2/v4l2_io.h"

namespace voca::pipeline {

struct CameraRunOptions {
  capture::StereoCameraOptions cameras;
  std::filesystem::path calibration;            // required: images must match its sizes
  std::optional<std::filesystem::path> config;  // file or shipped name; default: euroc
  VoRunOptions run;  // mode, capacity, outputs and pipeline settings (its input, calibration and config are unused)
};

// Opens the cameras of options.devices: V4L2 device nodes, or "libcamera:N" / "libcamera:<id>" for
// libcamera cameras (when built with VOCA_WITH_LIBCAMERA).
std::unique_ptr<StereoSource> openCameras(const capture::StereoCameraOptions& options, platform::V4l2Io& io);

// Throws InputError for bad input found before streaming (a missing camera, calibration or config,
// a capture size that differs from the calibration's). A device failing while streaming does not
// throw: the result carries it in pipeline.error, with every pose estimated until then written.
VoRunResult runVisualOdometryOnCameras(const CameraRunOptions& options,
                                       platform::V4l2Io& io = platform::systemV4l2Io());

// Recording from cameras (`voca record`): capture -> live encoder -> a VOCA video folder.
struct CameraRecordOptions {
  capture::StereoCameraOptions cameras;
  std::filesystem::path out;
  std::optional<std::filesystem::path> calibration;  // copied in as calib.json (checked against the frames)
  encode::LiveEncoderSettings encoder;               // its frame rate is set from fps
  double fps = 0.0;                                  // 0: the cameras' rate (30 when they report none)
  std::function<bool()> stop_requested;
  std::function<void(const encode::RecordReport&)> progress;
};

struct CameraRecordResult {
  encode::RecordReport report;
  std::string description;  // the cameras, one line
  std::vector<std::string> warnings;
};

// Records until the cameras end (max_frames), stop_requested() or a device fails; the folder is
// finished and playable in every case. A device failure is rethrown after the folder is finished.
CameraRecordResult recordFromCameras(const CameraRecordOptions& options,
                                     platform::V4l2Io& io = platform::systemV4l2Io());

}  // namespace voca::pipeline
