// `voca live`: the stereo VO on live V4L2 cameras through the staged pipeline, with the live policy
// (a stage that falls behind drops the oldest frame and counts it), until Ctrl-C or --frames.

#include <fmt/core.h>

#include <memory>
#include <string>

#include "platform/realtime/stop_signal.h"
#include "tools/voca/camera_cli.h"
#include "tools/voca/command.h"
#include "tools/voca/pipeline_cli.h"
#include "tools/voca/ros2_cli.h"
#include "tools/voca/view_cli.h"
#include "voca/core/error.h"
#include "voca_rt/run.h"

namespace {

using voca::cli::Runner;

struct LiveOptions {
  voca::cli::CameraCli camera;
  std::string calib, config, mode, out, format = "tum";
  int max_points = 1000;
  bool track_only = false;
  voca::cli::PipelineCli pipeline;
  voca::cli::Ros2Cli ros2;
  voca::cli::ViewCli view;
};

int runLive(const LiveOptions& o) {
  if (o.pipeline.realtime) throw voca::InputError("--realtime: cameras are live already (it paces recorded input)");
  voca_rt::Options options = voca::cli::apiOptions(o.pipeline);
  options.calibration_file = o.calib;
  options.config = o.config;
  options.mode = o.mode;
  options.max_points = o.max_points;
  options.estimate = !o.track_only;
  options.trajectory_file = o.out;
  options.trajectory_format = o.format;
  if (o.ros2.enabled && o.track_only) throw voca::InputError("--ros2 publishes poses; --track-only estimates none");
  voca::cli::applyRos2Options(o.ros2, options);
  voca::cli::applyViewOptions(o.view, options);
  voca_rt::CameraInput cameras;
  cameras.devices = o.camera.devices;
  cameras.size = o.camera.size;
  cameras.pixel_format = o.camera.pixel_format;
  cameras.fps = o.camera.fps;
  cameras.exposure = o.camera.exposure;
  cameras.gain = o.camera.gain;
  cameras.pair_tolerance_ms = o.camera.pair_tolerance_ms;
  cameras.buffers = o.camera.buffers;
  cameras.max_frames = o.camera.frames;
  voca::platform::installStopHandlers();
  const voca_rt::Summary summary = voca_rt::runCameras(cameras, options);
  std::fputs(summary.report.c_str(), stdout);
  voca::cli::printRos2Summary(summary);
  if (!o.out.empty()) fmt::print("trajectory: {} ({}, body frame of the calibration)\n", o.out, o.format);
  return voca::cli::reportRunEnd(summary, o.pipeline, "live");
}

const bool live_command_registered = voca::cli::registerCommand({
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
      voca::cli::addRos2Options(app, o->ros2);
      voca::cli::addViewOptions(app, o->view);
      app.footer(voca::cli::cameraHelpFooter() + "\n\n" +
                 "Live input always runs with the live policy: when a stage falls behind, the oldest waiting frame\n"
                 "is dropped and counted (--profile lists drops per stage). Timestamps are the cameras' kernel\n"
                 "timestamps, so the trajectory lines up with other sensors on CLOCK_MONOTONIC.\n\n" +
                 voca::cli::pipelineHelpFooter() + "\n\n" + voca::cli::ros2HelpFooter() + "\n\n" +
                 voca::cli::viewHelpFooter());
      return [o] { return runLive(*o); };
    },
});

}  // namespace
