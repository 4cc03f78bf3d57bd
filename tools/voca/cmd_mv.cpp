// `voca mv`: renders what the codec saw: each frame with its block partitions, the motion vectors as
// arrows (forward flow) and the vectors that median thresholding flags as likely outliers (the VOCA
// paper's Fig. 3), as PNGs or an .mp4.

#include <charconv>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <string_view>

#include <fmt/core.h>

#include "pipeline/motion_plot/motion_plot_runner.h"
#include "platform/realtime/stop_signal.h"
#include "tools/voca/command.h"
#include "voca/core/error.h"

namespace {

struct MvOptions {
  voca::pipeline::MotionPlotOptions plot;
  std::string frames;  // "a:b", parsed into plot.first_frame and plot.end_frame
};

// Frame range "a:b" (a inclusive, b exclusive, either may be omitted).
struct FrameRange {
  std::int64_t first = 0;
  std::int64_t end = std::numeric_limits<std::int64_t>::max();
};

FrameRange parseFrameRange(const std::string& text) {
  FrameRange range;
  if (text.empty()) return range;
  const std::size_t colon = text.find(':');
  auto parse = [&](std::string_view part, std::int64_t& value) {
    if (part.empty()) return;
    const auto [ptr, ec] = std::from_chars(part.data(), part.data() + part.size(), value);
    if (ec != std::errc() || ptr != part.data() + part.size() || value < 0) {
      throw voca::InputError("--frames '" + text + "': expected a:b with non-negative frame indices (b exclusive)");
    }
  };
  if (colon == std::string::npos) {
    parse(text, range.first);  // a single index
    if (range.first == std::numeric_limits<std::int64_t>::max()) {
      throw voca::InputError("--frames '" + text + "': frame index out of range");
    }
    range.end = range.first + 1;
    return range;
  }
  parse(std::string_view(text).substr(0, colon), range.first);
  parse(std::string_view(text).substr(colon + 1), range.end);
  if (range.end <= range.first) throw voca::InputError("--frames '" + text + "': the range is empty");
  return range;
}

int runMv(const MvOptions& opts) {
  const FrameRange range = parseFrameRange(opts.frames);
  voca::pipeline::MotionPlotOptions options = opts.plot;
  options.first_frame = range.first;
  options.end_frame = range.end;
  // A signal ends the drawing after the current frame; the mp4 is then closed properly (its index
  // written), so it plays.
  voca::platform::installStopHandlers();
  options.stop_requested = [] { return voca::platform::stopRequested(); };
  const voca::pipeline::MotionPlotResult result = voca::pipeline::plotMotionVectors(options);
  if (result.frames == 0 && !result.stopped)
    throw voca::InputError("--frames '" + opts.frames + "': no frame of the video is in this range");
  fmt::print("{}: wrote {} frame(s) to {} ({} vectors, {} flagged as likely outliers{})\n", result.video.string(),
             result.frames, result.written.string(), result.vectors, result.outliers,
             result.damaged > 0 ? fmt::format("; {} damaged", result.damaged) : std::string());
  if (result.stopped) {
    fmt::print(stderr, "voca mv: stopped by a signal after {} frame(s)\n", result.frames);
    return voca::platform::interruptedExitCode(voca::platform::stopSignal());
  }
  return 0;
}

const bool mv_command_registered = voca::cli::registerCommand({
    .name = "mv",
    .summary = "Render the codec's motion vectors and block partitions (outliers highlighted)",
    .order = 30,
    .configure = [](CLI::App& app) -> voca::cli::Runner {
      auto opts = std::make_shared<MvOptions>();
      app.add_option("input", opts->plot.input, "A video file, or a VOCA video dataset folder (mav0/camN/data.mp4)")
          ->required();
      app.add_option("--out,-o", opts->plot.out, "Output folder (created)")->required();
      app.add_option("--camera", opts->plot.camera, "Camera of a dataset folder: 0 or 1")->capture_default_str();
      app.add_option("--frames", opts->frames, "Frame range a:b (a inclusive, b exclusive; either may be omitted)");
      app.add_option("--format", opts->plot.format, "png (one mv_<frame>.png per frame) or mp4 (mv.mp4)")
          ->capture_default_str();
      app.add_option("--decoder", opts->plot.decoder, "Decoder: auto, software, vaapi, v4l2m2m")->capture_default_str();
      app.add_option("--arrow-scale", opts->plot.arrow_scale, "Multiply arrow lengths by this for visibility")
          ->capture_default_str();
      app.add_option("--outlier-radius", opts->plot.outliers.radius_px,
                     "Neighbourhood (box radius, px) whose median a vector is compared with")
          ->capture_default_str();
      app.add_option("--outlier-threshold", opts->plot.outliers.abs_threshold_px,
                     "Flag a vector deviating from the median by more than this many px ...")
          ->capture_default_str();
      app.add_option("--outlier-relative", opts->plot.outliers.rel_threshold,
                     "... or by more than this fraction of the median's length, whichever is larger")
          ->capture_default_str();
      app.add_flag("--strict", opts->plot.strict,
                   "Stop at the first damaged picture instead of drawing what the decoder concealed");
      app.footer(
          "Gray frame as RGB; blue: block partitions of inter blocks (intra blocks and I-frames have none);\n"
          "green arrows: forward flow of each block (the codec vector negated), starting at the block centre;\n"
          "red: vectors deviating from the median of their neighbourhood (likely not true motion).\n"
          "A damaged picture (missing or corrupt data) is drawn as the decoder concealed it and named in a\n"
          "warning; --strict stops there instead.");
      return [opts] { return runMv(*opts); };
    },
});

}  // namespace
