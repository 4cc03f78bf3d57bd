// `voca run`: the full VO on a dataset or VOCA video folder through the staged pipeline, writing the
// causal trajectory as it is estimated and printing frames, keyframes, resets, timings and ATE/RTE.

#include <fmt/core.h>

#include <memory>
#include <string>

#include "platform/realtime/stop_signal.h"
#include "tools/voca/command.h"
#include "tools/voca/pipeline_cli.h"
#include "tools/voca/ros2_cli.h"
#include "tools/voca/view_cli.h"
#include "voca/core/error.h"
#include "voca_rt/run.h"

namespace {

using voca::cli::Runner;

struct RunOptions {
  std::string input, calib, config, mode, bridge, encode, out, gt, format = "tum";
  int frames = 0;
  int start_frame = 0;
  int max_points = 1000;
  double stream_timeout = 3.0, stream_wait = 30.0;
  voca::cli::PipelineCli pipeline;
  voca::cli::Ros2Cli ros2;
  voca::cli::ViewCli view;
};

int runRun(const RunOptions& o) {
  voca_rt::Options options = voca::cli::apiOptions(o.pipeline);
  options.calibration_file = o.calib;
  options.config = o.config;
  options.mode = o.mode;
  if (!o.bridge.empty()) options.bridge_iframes = o.bridge == "on";
  options.max_points = o.max_points;
  if (o.out.empty()) throw voca::InputError("--out: an empty path; name the trajectory file to write");
  options.trajectory_file = o.out;
  options.trajectory_format = o.format;
  voca::cli::applyRos2Options(o.ros2, options);
  voca::cli::applyViewOptions(o.view, options);
  voca_rt::Input input;
  input.path = o.input;
  input.ground_truth = o.gt;
  input.encode_bitrate = o.encode;
  input.first_frame = o.start_frame;
  input.max_frames = o.frames;
  input.realtime = o.pipeline.realtime;
  input.speed = o.pipeline.speed;
  input.stream_wait_s = o.stream_wait;
  input.stream_timeout_s = o.stream_timeout;
  voca::platform::installStopHandlers();
  const voca_rt::Summary summary = voca_rt::run(input, options);
  std::fputs(summary.report.c_str(), stdout);
  voca::cli::printRos2Summary(summary);
  if (summary.started) {
    fmt::print("trajectory: {} ({}, {})\n", o.out, o.format,
               o.format == "kitti" ? "left camera's poses" : "body frame of the calibration");
  } else {
    fmt::print("trajectory: none written (stopped before the first frame)\n");
  }
  return voca::cli::reportRunEnd(summary, o.pipeline, "run");
}

const bool run_command_registered = voca::cli::registerCommand({
    .name = "run",
    .summary = "Run the stereo VO (frontend + backend) on a dataset or video and write the trajectory",
    .order = 50,
    .configure = [](CLI::App& app) -> Runner {
      auto o = std::make_shared<RunOptions>();
      app.add_option("input", o->input,
                     "Raw dataset (EuRoC/TUM-VI/KITTI folder), VOCA video folder, a stream URL that `voca stream` "
                     "sends to (udp://127.0.0.1:5000), or a stream it recorded to a file (out.ts)")
          ->required();
      app.add_option("--calib", o->calib,
                     "Calibration file (default: the one found with the dataset; required for a stream URL or file)");
      app.add_option("--config", o->config,
                     "Config JSON file, or a shipped config by name: euroc, tumvi, kitti (default: euroc; kitti for "
                     "KITTI folders)");
      app.add_option("--mode", o->mode, "Prior mode: " + voca::priorModeList() + " (overrides the config)");
      app.add_option("--bridge", o->bridge,
                     "I-frame bridging: on (reuse the last P-frame's motion on I-frames) or off (overrides the config)")
          ->check(CLI::IsMember({"on", "off"}));
      app.add_option("--encode", o->encode,
                     "Raw datasets: encode at this bitrate (e.g. 500k) to a temporary VOCA folder first");
      app.add_option("--out,-o", o->out, "Trajectory file to write (one row per frame, flushed as estimated)")
          ->required();
      app.add_option(
             "--format", o->format,
             "Trajectory format: tum, euroc (body poses) or kitti (3x4 rows of the left camera's pose, as the KITTI "
             "benchmark has them; no timestamps)")
          ->capture_default_str();
      app.add_option("--gt", o->gt,
                     "Ground truth for ATE/RTE (TUM/EuRoC/KITTI; default: the dataset's own, when it has one)");
      app.add_option("--frames", o->frames, "Process only the first N frames (0 = all)")->capture_default_str();
      app.add_option("--start-frame", o->start_frame,
                     "Track from this frame of the dataset on (videos are still decoded from their start); "
                     "--frames then counts from it")
          ->capture_default_str();
      app.add_option("--max-points", o->max_points, "Frontend points per camera (capacity)")->capture_default_str();
      app.add_option("--stream-wait", o->stream_wait, "Stream URL: seconds to wait for the stream to begin")
          ->capture_default_str();
      app.add_option("--stream-timeout", o->stream_timeout,
                     "Stream URL: seconds without data that end the run (the sender has stopped)")
          ->capture_default_str();
      voca::cli::addPipelineOptions(app, o->pipeline);
      voca::cli::addRos2Options(app, o->ros2);
      voca::cli::addViewOptions(app, o->view);
      app.footer(
          "Each frame is tracked, then estimated, and its pose written as it was estimated then (causal; later\n"
          "window refinements never rewrite it). Poses are in the calibration's body frame (T_world_body =\n"
          "T_world_cam0 T_body_cam0^-1), so they compare directly with the dataset's ground truth; the world\n"
          "frame is the body pose of the first frame. Resets (tracking failure, re-initialised at the last\n"
          "good pose) are reported on stderr and counted.\n"
          "A stream URL is decoded and estimated as frames arrive (live policy: a stage that falls behind\n"
          "drops the oldest waiting frame); frames lost on the network are skipped and counted, the VO goes\n"
          "on. Ctrl-C or --stream-timeout seconds of silence end the run cleanly. A stream recorded to a file\n"
          "(`voca stream seq out.ts`, or file:///path/out.ts) replays like a dataset: every frame, as fast as\n"
          "the pipeline goes (--realtime paces it at its stamps).\n\n" +
          voca::cli::pipelineHelpFooter() + "\n\n" + voca::cli::ros2HelpFooter() + "\n\n" +
          voca::cli::viewHelpFooter());
      return [o] { return runRun(*o); };
    },
});

}  // namespace
