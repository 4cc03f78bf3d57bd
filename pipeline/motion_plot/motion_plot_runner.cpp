#include "pipeline/motion_plot/motion_plot_runner.h"

#include <memory>
#include <optional>
#include <span>
#include <vector>

#include <fmt/core.h>

#include "drivers/decode/video_reader.h"
#include "drivers/encode/rgb_video_writer.h"
#include "formats/dataset/dataset.h"
#include "formats/image/png_io.h"
#include "pipeline/sinks/overlay_sink.h"
#include "platform/filesystem/output_paths.h"
#include "platform/terminal/progress_line.h"
#include "voca/core/error.h"

namespace voca::pipeline {
namespace {

namespace fs = std::filesystem;

void validate(const MotionPlotOptions& options) {
  if (options.format != "png" && options.format != "mp4") {
    throw InputError("--format '" + options.format + "': expected png or mp4");
  }
  if (options.camera < 0 || options.camera > 1) {
    throw InputError("--camera " + std::to_string(options.camera) + ": expected 0 or 1");
  }
  // A negative radius or threshold flagged more vectors instead of failing; a scale of 0 or less hides
  // or flips the arrows.
  if (!(options.arrow_scale > 0.0)) {
    throw InputError(fmt::format("--arrow-scale {}: expected a positive factor", options.arrow_scale));
  }
  if (options.outliers.radius_px <= 0) {
    throw InputError(fmt::format("--outlier-radius {}: expected a positive radius (px)", options.outliers.radius_px));
  }
  const auto require_nonnegative = [](const char* name, double value) {
    if (!(value >= 0.0)) throw InputError(fmt::format("{} {}: expected 0 or more", name, value));
  };
  require_nonnegative("--outlier-threshold", options.outliers.abs_threshold_px);
  require_nonnegative("--outlier-relative", options.outliers.rel_threshold);
  if (options.first_frame < 0 || options.end_frame <= options.first_frame) {
    throw InputError(fmt::format("frames {}:{}: expected 0 <= first < end", options.first_frame, options.end_frame));
  }
}

// The reader of the video to draw, after checking that the output stays apart from what it reads.
std::unique_ptr<decode::VideoReader> openVideo(const MotionPlotOptions& options,
                                               const decode::DecoderOptions& decoder_options) {
  using decode::VideoReader;
  const NamedPath output{"the output folder", options.out};
  // A folder of one camera (`voca encode --cameras N`) is no stereo dataset, but its video draws as well.
  const fs::path camera_video = options.input / "mav0" / fmt::format("cam{}", options.camera) / "data.mp4";
  const fs::path other_video = options.input / "mav0" / fmt::format("cam{}", 1 - options.camera) / "data.mp4";
  if (fs::is_regular_file(camera_video) && !fs::exists(other_video)) {
    const NamedPath folder{"the dataset's mav0 folder", options.input / "mav0"};
    requireOutputsApart(std::span(&output, 1), std::span(&folder, 1));
    return std::make_unique<VideoReader>(camera_video, std::vector<std::int64_t>{}, decoder_options);
  }
  if (fs::is_directory(options.input)) {
    const Dataset dataset = openDataset(options.input);
    if (dataset.layout != DatasetLayout::kVocaVideo) {
      throw InputError(options.input.string() + ": a " + std::string(layoutName(dataset.layout)) +
                       " image dataset, not a video; expected mav0/camN/data.mp4 or a video file");
    }
    // The pictures would land among the dataset's files (mav0/cam0/mv_000000.png).
    requireOutputsApart(std::span(&output, 1), datasetReadPaths(dataset));
    if (options.progress) {
      for (const std::string& warning : dataset.warnings) fmt::print(stderr, "warning: {}\n", warning);
    }
    return std::make_unique<VideoReader>(options.camera == 0 ? dataset.video_left : dataset.video_right,
                                         decode::datasetTimestamps(dataset), decoder_options);
  }
  const NamedPath video{"the video", options.input};
  requireOutputsApart(std::span(&output, 1), std::span(&video, 1));
  return std::make_unique<VideoReader>(options.input, std::vector<std::int64_t>{}, decoder_options);
}

}  // namespace

MotionPlotResult plotMotionVectors(const MotionPlotOptions& options) {
  validate(options);
  decode::DecoderOptions decoder_options;
  decoder_options.kind = decode::parseDecoderKind(options.decoder);
  decoder_options.strict = options.strict;
  const std::unique_ptr<decode::VideoReader> reader = openVideo(options, decoder_options);
  const decode::StreamInfo& stream = reader->stream();

  MotionPlotResult result;
  result.video = reader->path();
  fs::create_directories(options.out);
  std::unique_ptr<encode::RgbVideoWriter> video;
  if (options.format == "mp4") {
    result.written = options.out / "mv.mp4";
    video =
        std::make_unique<encode::RgbVideoWriter>(result.written, stream.frame_rate_num > 0 ? stream.frame_rate_num : 30,
                                                 stream.frame_rate_num > 0 ? stream.frame_rate_den : 1);
  } else {
    result.written = options.out;
  }

  decode::DecodedFrame frame;
  frame.reserve(stream.width, stream.height);
  RgbImage canvas(stream.width, stream.height);
  const std::int64_t expected = reader->expectedFrames();
  std::optional<platform::ProgressLine> progress;
  if (options.progress) progress.emplace();
  while (reader->next(frame)) {
    if (options.stop_requested && options.stop_requested()) {
      result.stopped = true;
      break;
    }
    if (frame.frame_index < options.first_frame) continue;  // decoded anyway: later P-frames refer to it
    if (frame.frame_index >= options.end_frame) break;
    if (frame.damaged) {
      // Drawn all the same: what the decoder concealed is what a damaged stream gives the tracker.
      ++result.damaged;
      if (progress) {
        progress->message("warning: frame {} is damaged (missing or corrupt data, concealed by the decoder)",
                          frame.frame_index);
      }
    }
    const int outliers = frame.motion.flagOutliers(options.outliers);
    result.vectors += static_cast<std::int64_t>(frame.motion.blocks().size());
    result.outliers += outliers;
    renderMotionOverlay(frame.luma, frame.motion, options.arrow_scale, canvas);
    if (video) {
      video->write(canvas.view());
    } else {
      writePngRgb(options.out / fmt::format("mv_{:06d}.png", frame.frame_index), canvas.view());
    }
    ++result.frames;
    if (progress) {
      progress->update("frame {}{} ({}): {} vectors, {} flagged", frame.frame_index,
                       expected > 0 ? fmt::format("/{}", expected) : std::string(),
                       pictureTypeName(frame.motion.pictureType()), frame.motion.blocks().size(), outliers);
    }
  }
  if (video) video->finish();
  if (progress) progress->end();
  return result;
}

}  // namespace voca::pipeline
