// `voca run`: the full VO on a dataset or VOCA video folder through the staged pipeline, writing the
// causal trajectory as it is estimated and printing frames, keyframes, resets, timings and ATE/RTE.

#include <fmt/core.h>

#include <memory>
#include <string>

#include "drivers/encode/video_encoder.h"
#include "platform/realtime/stop_signal.h"
#include "tools/voca/command.h"
#include "tools/voca/pipeline_cli.h"
#include "tools/voca/view_cli.h"
#include "voca/core/error.h"

namespace {

using voca::cli::Runner;

struct RunOptions {
  std::string input, calib, config, mode, bridge, encode, out, gt, format = "tum";
  int frames = 0;
  int start_frame = 0;
  int max_points = 1000;
  double stream_timeout = 3.0, stream_wait = 30.0;
  voca::cli::PipelineCli pipeline;
  voca::cli::ViewCli view;
};

int runRun(const RunOptions& o) {
  voca::pipeline::VoRunOptions options;
  options.input = o.input;
  if (!o.calib.empty()) options.calibration = o.calib;
  if (!o.config.empty()) options.config = o.config;
  if (!o.gt.empty()) options.ground_truth = o.gt;
  if (!o.mode.empty()) options.mode = voca::requirePriorMode(o.mode, "--mode");
  if (!o.bridge.empty()) options.bridge_iframes = o.bridge == "on";
  if (!o.encode.empty()) options.encode_bitrate_bps = voca::encode::parseBitrate(o.encode);
  if (o.frames < 0) throw voca::InputError("--frames: expected 0 (all) or a positive count");
  options.max_frames = o.frames;
  if (o.start_frame < 0) throw voca::InputError("--start-frame: expected 0 (the first frame) or a positive index");
  options.first_frame = o.start_frame;
  options.max_points = o.max_points;
  // A day at most: a deadline of inf or 1e300 s overflowed and ended the wait at once.
  constexpr double kMaxWaitS = 86400.0;
  if (!(o.stream_timeout > 0.0 && o.stream_timeout <= kMaxWaitS) ||
      !(o.stream_wait > 0.0 && o.stream_wait <= kMaxWaitS)) {
    throw voca::InputError("--stream-timeout and --stream-wait: expected seconds above 0 and at most 86400 (a day)");
  }
  options.stream_timeout_s = o.stream_timeout;
  options.stream_start_timeout_s = o.stream_wait;
  const auto format = voca::parseTrajectoryFormat(o.format);
  if (!format) throw voca::InputError(fmt::format("--format: expected tum, euroc or kitti, got \"{}\"", o.format));
  if (o.out.empty()) throw voca::InputError("--out: an empty path; name the trajectory file to write");
  options.trajectory_file = o.out;
  options.trajectory_format = *format;
  voca::cli::applyPipelineOptions(o.pipeline, options);
  // Bound before the input is opened or encoded: a port in use fails at once, with nothing written.
  const std::unique_ptr<voca::view::FoxgloveServer> view = voca::cli::startView(o.view);
  options.view.server = view.get();
  options.mcap = voca::cli::mcapRunOptions(o.view);
  voca::platform::installStopHandlers();
  const voca::pipeline::VoRunResult result = voca::pipeline::runVisualOdometry(options);
  voca::pipeline::printRunSummary(result, stdout);
  if (result.started) {
    fmt::print("trajectory: {} ({}, {})\n", o.out, o.format,
               *format == voca::TrajectoryFormat::kKitti ? "left camera's poses" : "body frame of the calibration");
  } else {
    fmt::print("trajectory: none written (stopped before the first frame)\n");
  }
  return voca::cli::reportRunEnd(result, o.pipeline, "run");
}

const bool registered = voca::cli::registerCommand({
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
          voca::cli::pipelineHelpFooter() + "\n\n" + voca::cli::viewHelpFooter());
      return [o] { return runRun(*o); };
    },
});

}  // namespace
