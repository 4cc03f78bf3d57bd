// `voca record`: cameras -> live H.264 encoder -> a VOCA video folder (mav0/camN/data.mp4 + data.csv
// with the capture timestamps + calib.json) that `voca run` replays later.

#include <fmt/core.h>

#include <memory>
#include <string>

#include "pipeline/vo/camera_runner.h"
#include "platform/realtime/stop_signal.h"
#include "platform/terminal/progress_line.h"
#include "tools/voca/camera_cli.h"
#include "tools/voca/command.h"
#include "tools/voca/encoder_cli.h"
#include "voca/core/error.h"

namespace {

using voca::cli::Runner;

struct RecordCli {
  voca::cli::CameraCli camera;
  voca::cli::EncoderCli encoder;
  std::string out, calib;
};

double megabytes(std::int64_t bytes) { return static_cast<double>(bytes) / 1e6; }

int runRecord(const RecordCli& o) {
  voca::pipeline::CameraRecordOptions options;
  options.cameras = voca::cli::applyCameraOptions(o.camera);
  options.out = o.out;
  if (!o.calib.empty()) options.calibration = o.calib;
  options.encoder = voca::cli::liveEncoderSettings(o.encoder);
  options.fps = o.camera.fps;
  voca::platform::installStopHandlers();
  options.stop_requested = voca::platform::stopRequested;
  voca::platform::ProgressLine progress;
  options.progress = [&progress](const voca::encode::RecordReport& r) {
    if (r.frames % 30 != 0) return;
    const double seconds = static_cast<double>(r.last_t_ns - r.first_t_ns) * 1e-9;
    progress.update("recorded {} frames, {:.1f} s, {:.2f} MB", r.frames, seconds, megabytes(r.video_bytes));
  };
  const voca::pipeline::CameraRecordResult result = voca::pipeline::recordFromCameras(options);
  const voca::encode::RecordReport& r = result.report;
  progress.end();
  for (const std::string& warning : result.warnings) fmt::print(stderr, "warning: {}\n", warning);
  if (!options.calibration) {
    fmt::print(stderr, "warning: no --calib: the folder has no calib.json; pass --calib to `voca run` later\n");
  }
  fmt::print("input: {}\n", result.description);
  if (!r.encoder.empty()) fmt::print("{}\n", r.encoder);
  fmt::print("recorded: {} stereo frames, {:.2f} s\n", r.frames,
             static_cast<double>(r.last_t_ns - r.first_t_ns) * 1e-9);
  fmt::print("video: {:.2f} MB for {:.2f} MB of raw 8-bit frames ({:.0f}x smaller)\n", megabytes(r.video_bytes),
             megabytes(r.raw_bytes), r.video_bytes > 0 ? static_cast<double>(r.raw_bytes) / r.video_bytes : 0.0);
  if (r.source.frames_lost > 0 || r.source.unpaired > 0) {
    fmt::print("source: {} frames lost by the drivers, {} unpaired stereo frames\n", r.source.frames_lost,
               r.source.unpaired);
  }
  fmt::print("folder: {} (replay: voca run {} -o trajectory.txt)\n", o.out, o.out);
  if (!r.error.empty()) {
    fmt::print(stderr, "voca record: error: {}; the {} frames before it are saved\n", r.error, r.frames);
    return 1;
  }
  return 0;
}

const bool record_command_registered = voca::cli::registerCommand({
    .name = "record",
    .summary = "Record stereo cameras as H.264 into a VOCA video folder that `voca run` replays",
    .order = 22,
    .configure = [](CLI::App& app) -> Runner {
      auto o = std::make_shared<RecordCli>();
      voca::cli::addCameraOptions(app, o->camera);
      app.add_option("--out,-o", o->out, "Folder to create (mav0/cam0, mav0/cam1, calib.json)")->required();
      app.add_option("--calib", o->calib, "Stereo calibration of the cameras, copied into the folder as calib.json");
      voca::cli::addEncoderOptions(app, o->encoder);
      app.footer(voca::cli::cameraHelpFooter() + "\n\n" +
                 "Each camera is encoded as it is captured with the causal low-latency settings (one pass, no\n"
                 "B-frames, one reference frame, no look-ahead, a keyframe every --gop frames), on the board's\n"
                 "hardware encoder when there is one (--encoder auto); data.csv keeps every\n"
                 "frame's capture timestamp. Ctrl-C (or --frames) ends the recording and leaves a complete,\n"
                 "playable folder (exit 0); a camera failing mid-recording keeps what was recorded (exit 1).");
      return [o] { return runRecord(*o); };
    },
});

}  // namespace
