// `voca live`: the stereo VO on live V4L2 cameras through the staged pipeline, with the live policy
// (a stage that falls behind drops the oldest frame and counts it), until Ctrl-C or --frames.

#include <fmt/core.h>

#include <memory>
#include <string>

#include "pipeline/vo/camera_runner.h"
#include "platform/realtime/stop_signal.h"
#include "tools/voca/camera_cli.h"
#include "tools/voca/command.h"
#include "tools/voca/pipeline_cli.h"
#include "tools/voca/view_cli.h"
#include "voca/core/error.h"

namespace {

using voca::cli::Runner;

struct LiveOptions {
  voca::cli::CameraCli camera;
  std::string calib, config, mode, out, format = "tum";
  int max_points = 1000;
  bool track_only = false;
  voca::cli::PipelineCli pipeline;
  voca::cli::ViewCli view;
};

int runLive(const LiveOptions& o) {
  voca::pipeline::CameraRunOptions options;
  options.cameras = voca::cli::applyCameraOptions(o.camera);
  options.calibration = o.calib;
  if (!o.config.empty()) options.config = o.config;
  voca::pipeline::VoRunOptions& run = options.run;
  if (!o.mode.empty()) run.mode = voca::requirePriorMode(o.mode, "--mode");
  run.max_points = o.max_points;
  run.estimate = !o.track_only;
  const auto format = voca::parseTrajectoryFormat(o.format);
  if (!format) throw voca::InputError(fmt::format("--format: expected tum, euroc or kitti, got \"{}\"", o.format));
  run.trajectory_file = o.out;
  run.trajectory_format = *format;
  voca::cli::applyPipelineOptions(o.pipeline, run);
  if (run.realtime) throw voca::InputError("--realtime: cameras are live already (it paces recorded input)");
  // Bound before the cameras open: a port in use fails at once, with nothing written.
  const std::unique_ptr<voca::view::FoxgloveServer> view = voca::cli::startView(o.view);
  run.view.server = view.get();
  run.mcap = voca::cli::mcapRunOptions(o.view);
  voca::platform::installStopHandlers();
  const voca::pipeline::VoRunResult result = voca::pipeline::runVisualOdometryOnCameras(options);
  voca::pipeline::printRunSummary(result, stdout);
  if (!o.out.empty()) fmt::print("trajectory: {} ({}, body frame of the calibration)\n", o.out, o.format);
  return voca::cli::reportRunEnd(result, o.pipeline, "live");
}

const bool registered = voca::cli::registerCommand({
    .name = "live",
    .summary = "Run the stereo VO live on cameras (V4L2, libcamera), writing the trajectory as it is estimated",
    .order = 52,
    .configure = [](CLI::App& app) -> Runner {
      auto o = std::make_shared<LiveOptions>();
      voca::cli::addCameraOptions(app, o->camera);
      app.add_option("--calib", o->calib, "Stereo calibration of the cameras (Basalt JSON, Kalibr YAML, ...)")
          ->required();
      app.add_option("--config", o->config,
                     "Config JSON file, or a shipped config by name: euroc, tumvi, kitti (default: euroc)");
      app.add_option("--mode", o->mode,
                     "Prior mode: " + voca::priorModeList() + " (raw cameras have no motion vectors)");
      app.add_option("--out,-o", o->out, "Trajectory file to write (one row per frame, flushed as estimated)");
      app.add_option("--format", o->format, "Trajectory format: tum, euroc or kitti")->capture_default_str();
      app.add_option("--max-points", o->max_points, "Frontend points per camera (capacity)")->capture_default_str();
      app.add_flag("--track-only", o->track_only, "Frontend only: track features, estimate no poses");
      voca::cli::addPipelineOptions(app, o->pipeline);
      voca::cli::addViewOptions(app, o->view);
      app.footer(voca::cli::cameraHelpFooter() + "\n\n" +
                 "Live input always runs with the live policy: when a stage falls behind, the oldest waiting frame\n"
                 "is dropped and counted (--profile lists drops per stage). Timestamps are the cameras' kernel\n"
                 "timestamps, so the trajectory lines up with other sensors on CLOCK_MONOTONIC.\n\n" +
                 voca::cli::pipelineHelpFooter() + "\n\n" + voca::cli::viewHelpFooter());
      return [o] { return runLive(*o); };
    },
});

}  // namespace
