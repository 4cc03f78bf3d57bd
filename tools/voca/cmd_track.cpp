// `voca track`: the KLT frontend alone (the pipeline without the backend) on a raw dataset or a VOCA
// video folder; prints what it did (tracks, survival, prior rescues, consensus rejections, guess
// distances, time) and optionally writes an overlay video of the tracks.

#include <fmt/core.h>

#include <memory>
#include <string>

#include "drivers/encode/video_encoder.h"
#include "platform/realtime/stop_signal.h"
#include "tools/voca/command.h"
#include "tools/voca/pipeline_cli.h"
#include "voca/core/error.h"

namespace {

using voca::cli::Runner;

struct TrackOptions {
  std::string input;
  std::string calib;
  std::string config;
  std::string mode;
  std::string overlay;
  std::string encode;
  int frames = 0;
  int max_points = 1000;
  bool per_frame = false;
  voca::cli::PipelineCli pipeline;
};

int runTrack(const TrackOptions& opts) {
  voca::pipeline::VoRunOptions options;
  options.input = opts.input;
  options.estimate = false;
  if (!opts.calib.empty()) options.calibration = opts.calib;
  if (!opts.config.empty()) options.config = opts.config;
  if (!opts.mode.empty()) options.mode = voca::requirePriorMode(opts.mode, "--mode");
  if (opts.frames < 0) throw voca::InputError("--frames: expected 0 (all) or a positive count");
  options.max_frames = opts.frames;
  options.max_points = opts.max_points;
  if (!opts.encode.empty()) options.encode_bitrate_bps = voca::encode::parseBitrate(opts.encode);
  options.overlay_file = opts.overlay;
  voca::cli::applyPipelineOptions(opts.pipeline, options);
  voca::platform::installStopHandlers();
  const voca::pipeline::VoRunResult result = voca::pipeline::runVisualOdometry(options);

  if (opts.per_frame) {
    fmt::print("{:>5} {:>4} {:>5} {:>5} {:>5} {:>5} {:>6} {:>7} {:>6} {:>7}\n", "frame", "type", "left", "right",
               "kept", "lost", "new", "rescued", "reject", "ms");
    for (const voca::pipeline::FrameRecord& r : result.rows) {
      fmt::print("{:5} {:>4} {:5} {:5} {:5} {:5} {:6} {:7} {:6} {:7.2f}\n", r.frame_index, r.picture_type, r.left,
                 r.right, r.kept, r.lost, r.detected, r.rescued, r.consensus_rejections, r.frontend_ms);
    }
  }
  voca::pipeline::printTrackSummary(result, result.config.frontend, stdout);
  if (!opts.overlay.empty() && result.started && !result.pipeline_report.error)
    fmt::print("overlay: {}\n", opts.overlay);
  return voca::cli::reportRunEnd(result, opts.pipeline, "track");
}

const bool track_command_registered = voca::cli::registerCommand({
    .name = "track",
    .summary = "Run the KLT frontend alone on a dataset or video and summarise its tracks",
    .order = 40,
    .configure = [](CLI::App& app) -> Runner {
      auto opts = std::make_shared<TrackOptions>();
      app.add_option("input", opts->input, "Raw dataset (EuRoC/TUM-VI/KITTI folder) or VOCA video folder")->required();
      app.add_option("--calib", opts->calib, "Calibration file (default: the one found with the dataset)");
      app.add_option("--config", opts->config,
                     "Config JSON file, or a shipped config by name: euroc, tumvi, kitti (default: euroc)");
      app.add_option("--mode", opts->mode, "Prior mode: " + voca::priorModeList() + " (overrides the config)");
      app.add_option("--overlay", opts->overlay, "Write the left video with the tracks drawn to this .mp4");
      app.add_option("--frames", opts->frames, "Track only the first N frames (0 = all)")->capture_default_str();
      app.add_option("--encode", opts->encode,
                     "Raw datasets: encode at this bitrate (e.g. 500k) and decode first, to track with motion vectors");
      app.add_option("--max-points", opts->max_points, "Points per camera (capacity)")->capture_default_str();
      app.add_flag("--per-frame", opts->per_frame, "Print one line per frame");
      voca::cli::addPipelineOptions(app, opts->pipeline);
      app.footer(
          "Overlay colours: blue = previous position, yellow = motion-vector prior, green = converged\n"
          "position (red = rejected), cyan = new detection. Raw images carry no motion vectors, so the\n"
          "MV modes behave like `none` unless --encode is given.\n\n" +
          voca::cli::pipelineHelpFooter());
      return [opts] { return runTrack(*opts); };
    },
});

}  // namespace
