// `voca mv`: renders what the codec saw: each frame with its block partitions, the motion vectors as
// arrows (forward flow) and the vectors that median thresholding flags as likely outliers (the VOCA
// paper's Fig. 3), as PNGs or an .mp4.

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include <fmt/core.h>

#include "drivers/decode/video_reader.h"
#include "drivers/encode/rgb_video_writer.h"
#include "formats/dataset/dataset.h"
#include "formats/image/png_io.h"
#include "pipeline/sinks/overlay_sink.h"
#include "platform/filesystem/output_paths.h"
#include "platform/realtime/stop_signal.h"
#include "platform/terminal/progress_line.h"
#include "tools/voca/command.h"
#include "voca/core/error.h"
#include "voca/motion/motion_field.h"

namespace {

namespace fs = std::filesystem;
using voca::RgbImage;

struct MvOptions {
  std::string input;
  std::string out;
  int camera = 0;
  std::string frames;
  std::string format = "png";
  std::string decoder = "auto";
  float arrow_scale = 1.0f;
  voca::OutlierParams outliers;
  bool strict = false;
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
  using namespace voca::decode;
  using voca::encode::RgbVideoWriter;
  if (opts.format != "png" && opts.format != "mp4") {
    throw voca::InputError("--format '" + opts.format + "': expected png or mp4");
  }
  if (opts.camera < 0 || opts.camera > 1) {
    throw voca::InputError("--camera " + std::to_string(opts.camera) + ": expected 0 or 1");
  }
  // A negative radius or threshold flagged more vectors instead of failing; a scale of 0 or less hides
  // or flips the arrows.
  const auto require_nonnegative = [](const char* name, double value) {
    if (!(value >= 0.0)) throw voca::InputError(fmt::format("{} {}: expected 0 or more", name, value));
  };
  if (!(opts.arrow_scale > 0.0)) {
    throw voca::InputError(fmt::format("--arrow-scale {}: expected a positive factor", opts.arrow_scale));
  }
  if (opts.outliers.radius_px <= 0) {
    throw voca::InputError(
        fmt::format("--outlier-radius {}: expected a positive radius (px)", opts.outliers.radius_px));
  }
  require_nonnegative("--outlier-threshold", opts.outliers.abs_threshold_px);
  require_nonnegative("--outlier-relative", opts.outliers.rel_threshold);
  const FrameRange range = parseFrameRange(opts.frames);
  DecoderOptions decoder_options;
  decoder_options.kind = parseDecoderKind(opts.decoder);
  decoder_options.strict = opts.strict;

  std::unique_ptr<VideoReader> reader;
  const voca::NamedPath output{"the output folder", opts.out};
  // A folder of one camera (`voca encode --cameras N`) is no stereo dataset, but its video draws as well.
  const fs::path camera_video = fs::path(opts.input) / "mav0" / fmt::format("cam{}", opts.camera) / "data.mp4";
  const fs::path other_video = fs::path(opts.input) / "mav0" / fmt::format("cam{}", 1 - opts.camera) / "data.mp4";
  const bool one_camera = fs::is_regular_file(camera_video) && !fs::exists(other_video);
  if (one_camera) {
    const voca::NamedPath folder{"the dataset's mav0 folder", fs::path(opts.input) / "mav0"};
    voca::requireOutputsApart(std::span(&output, 1), std::span(&folder, 1));
    reader = std::make_unique<VideoReader>(camera_video, std::vector<std::int64_t>{}, decoder_options);
  } else if (fs::is_directory(opts.input)) {
    const voca::Dataset dataset = voca::openDataset(opts.input);
    if (dataset.layout != voca::DatasetLayout::kVocaVideo) {
      throw voca::InputError(opts.input + ": a " + std::string(voca::layoutName(dataset.layout)) +
                             " image dataset, not a video; expected mav0/camN/data.mp4 or a video file");
    }
    // The pictures would land among the dataset's files (mav0/cam0/mv_000000.png).
    voca::requireOutputsApart(std::span(&output, 1), voca::datasetReadPaths(dataset));
    for (const std::string& warning : dataset.warnings) fmt::print(stderr, "warning: {}\n", warning);
    reader = std::make_unique<VideoReader>(opts.camera == 0 ? dataset.video_left : dataset.video_right,
                                           datasetTimestamps(dataset), decoder_options);
  } else {
    const voca::NamedPath video{"the video", opts.input};
    voca::requireOutputsApart(std::span(&output, 1), std::span(&video, 1));
    reader = std::make_unique<VideoReader>(opts.input, std::vector<std::int64_t>{}, decoder_options);
  }

  fs::create_directories(opts.out);
  std::unique_ptr<RgbVideoWriter> video;
  if (opts.format == "mp4") {
    const StreamInfo& info = reader->stream();
    video = std::make_unique<RgbVideoWriter>(fs::path(opts.out) / "mv.mp4",
                                             info.frame_rate_num > 0 ? info.frame_rate_num : 30,
                                             info.frame_rate_num > 0 ? info.frame_rate_den : 1);
  }

  DecodedFrame frame;
  frame.reserve(reader->stream().width, reader->stream().height);
  RgbImage canvas(reader->stream().width, reader->stream().height);
  int written = 0, damaged = 0;
  std::int64_t total_vectors = 0, total_outliers = 0;
  const std::int64_t expected = reader->expectedFrames();
  voca::platform::ProgressLine progress;
  // A signal ends the drawing after the current frame; the mp4 is then closed properly (its index
  // written), so it plays.
  voca::platform::installStopHandlers();
  bool stopped = false;
  while (reader->next(frame)) {
    if (voca::platform::stopRequested()) {
      stopped = true;
      break;
    }
    if (frame.frame_index < range.first) continue;  // decoded anyway: later P-frames refer to it
    if (frame.frame_index >= range.end) break;
    if (frame.damaged) {
      // Drawn all the same: what the decoder concealed is what a damaged stream gives the tracker.
      ++damaged;
      progress.message("warning: frame {} is damaged (missing or corrupt data, concealed by the decoder)",
                       frame.frame_index);
    }
    const int outliers = frame.motion.flagOutliers(opts.outliers);
    total_vectors += static_cast<std::int64_t>(frame.motion.blocks().size());
    total_outliers += outliers;
    voca::pipeline::renderMotionOverlay(frame.luma, frame.motion, opts.arrow_scale, canvas);
    if (video) {
      video->write(canvas.view());
    } else {
      voca::writePngRgb(fs::path(opts.out) / fmt::format("mv_{:06d}.png", frame.frame_index), canvas.view());
    }
    ++written;
    progress.update("frame {}{} ({}): {} vectors, {} flagged", frame.frame_index,
                    expected > 0 ? fmt::format("/{}", expected) : std::string(),
                    voca::pictureTypeName(frame.motion.pictureType()), frame.motion.blocks().size(), outliers);
  }
  if (video) video->finish();
  progress.end();
  if (written == 0 && !stopped)
    throw voca::InputError("--frames '" + opts.frames + "': no frame of the video is in this range");
  fmt::print("{}: wrote {} frame(s) to {} ({} vectors, {} flagged as likely outliers{})\n", reader->path().string(),
             written, opts.format == "mp4" ? (fs::path(opts.out) / "mv.mp4").string() : opts.out, total_vectors,
             total_outliers, damaged > 0 ? fmt::format("; {} damaged", damaged) : std::string());
  if (stopped) {
    fmt::print(stderr, "voca mv: stopped by a signal after {} frame(s)\n", written);
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
      app.add_option("input", opts->input, "A video file, or a VOCA video dataset folder (mav0/camN/data.mp4)")
          ->required();
      app.add_option("--out,-o", opts->out, "Output folder (created)")->required();
      app.add_option("--camera", opts->camera, "Camera of a dataset folder: 0 or 1")->capture_default_str();
      app.add_option("--frames", opts->frames, "Frame range a:b (a inclusive, b exclusive; either may be omitted)");
      app.add_option("--format", opts->format, "png (one mv_<frame>.png per frame) or mp4 (mv.mp4)")
          ->capture_default_str();
      app.add_option("--decoder", opts->decoder, "Decoder: auto, software, vaapi, v4l2m2m")->capture_default_str();
      app.add_option("--arrow-scale", opts->arrow_scale, "Multiply arrow lengths by this for visibility")
          ->capture_default_str();
      app.add_option("--outlier-radius", opts->outliers.radius_px,
                     "Neighbourhood (box radius, px) whose median a vector is compared with")
          ->capture_default_str();
      app.add_option("--outlier-threshold", opts->outliers.abs_threshold_px,
                     "Flag a vector deviating from the median by more than this many px ...")
          ->capture_default_str();
      app.add_option("--outlier-relative", opts->outliers.rel_threshold,
                     "... or by more than this fraction of the median's length, whichever is larger")
          ->capture_default_str();
      app.add_flag("--strict", opts->strict,
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
