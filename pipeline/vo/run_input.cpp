#include "pipeline/vo/run_input.h"

#include <fmt/core.h>

#include <system_error>
#include <utility>

#include "drivers/encode/dataset_encoder.h"
#include "drivers/source/dataset_source.h"
#include "drivers/source/network_source.h"
#include "formats/calib/calibration_io.h"
#include "formats/dataset/dataset.h"
#include "pipeline/vo/output_checks.h"
#include "platform/realtime/stop_signal.h"
#include "voca/core/error.h"
#include "voca/frontend/frontend.h"

namespace voca::pipeline {

namespace {

// What the input makes of the options that do nothing for it: said, instead of silently ignored.
// layout: the dataset's, or nullopt for a stream.
std::vector<std::string> ignoredOptionWarnings(const VoRunOptions& options, std::optional<DatasetLayout> layout) {
  const bool stream = !layout;
  const VoRunOptions defaults;
  std::vector<std::string> warnings;
  if (!options.realtime && options.speed != defaults.speed) {
    warnings.push_back(fmt::format("--speed {} has no effect without --realtime", options.speed));
  }
  if (!stream && (options.stream_start_timeout_s != defaults.stream_start_timeout_s ||
                  options.stream_timeout_s != defaults.stream_timeout_s)) {
    warnings.push_back("--stream-wait and --stream-timeout apply to stream URLs only; ignored");
  }
  if (stream) return warnings;
  if (*layout == DatasetLayout::kVocaVideo && options.encode_bitrate_bps > 0) {
    warnings.push_back(
        fmt::format("--encode: {} is encoded video already; it was replayed as it is", options.input.string()));
  }
  const bool decoded = *layout == DatasetLayout::kVocaVideo || options.encode_bitrate_bps > 0;
  if (!decoded && (options.decoder != defaults.decoder || options.skip_deblock)) {
    warnings.push_back(
        fmt::format("--decoder and --skip-deblock apply to video; {} holds images (--encode "
                    "encodes them first)",
                    options.input.string()));
  }
  return warnings;
}

// The result of a run that ended before its first frame.
VoRunResult stoppedBeforeFrames(std::string description, const RunConfig& config) {
  VoRunResult stopped;
  stopped.description = std::move(description);
  stopped.stop_signal = platform::stopSignal();
  stopped.config = config.config;
  stopped.config_name = config.name;
  return stopped;
}

// `voca run udp://...`: a stream carries no calibration or ground truth, so both come from options.
// A stream URL, or a recording of one (`url` is then its file:// URL).
RunInput openStream(const VoRunOptions& options, const std::string& url) {
  const bool recording = isRecordedStreamUrl(url);
  if (!options.calibration) {
    throw InputError(fmt::format("{}: a stream carries no calibration; pass the cameras' with --calib", url));
  }
  if (options.encode_bitrate_bps > 0) throw InputError(fmt::format("{}: --encode applies to raw datasets only", url));
  if (options.first_frame > 0 && !recording) {
    throw InputError(fmt::format("{}: --start-frame applies to recordings only (folders, recorded .ts files)", url));
  }
  const std::optional<std::filesystem::path> recording_file =
      recording ? std::optional<std::filesystem::path>(recordedStreamFile(url)) : std::nullopt;
  requireOutputsApartFromInputs(options, nullptr, options.calibration, recording_file);
  RunInput input;
  input.rig = loadCalibration(*options.calibration);
  input.rig.requireStereo();
  input.config = resolveRunConfig(options.config);
  if (options.ground_truth) {
    input.ground_truth = loadTrajectory(*options.ground_truth);
    input.ground_truth_name = options.ground_truth->string();
  }
  input.warnings = ignoredOptionWarnings(options, std::nullopt);
  NetworkSourceOptions network;
  network.start_timeout_s = options.stream_start_timeout_s;
  network.timeout_s = options.stream_timeout_s;
  network.max_frames = options.max_frames;
  network.strict = options.strict;
  network.first_frame = options.first_frame;
  network.stop_requested = stopRequest(options);
  if (options.progress && !recording) {
    fmt::print(stderr, "waiting for the stream on {} (up to {} s)\n", url, options.stream_start_timeout_s);
  }
  try {
    auto source = std::make_unique<NetworkStereoSource>(url, network);
    input.stream = source.get();
    input.source = std::move(source);
  } catch (const InputError&) {
    if (!network.stop_requested()) throw;
    // Ctrl-C while waiting for the stream: a clean stop, nothing estimated.
    input.stopped = stoppedBeforeFrames(fmt::format("{} (stopped while waiting for the stream)", url), input.config);
  }
  return input;
}

RunInput openDatasetInput(const VoRunOptions& options) {
  if (std::error_code error; std::filesystem::is_regular_file(options.input, error)) {
    // A file that is no recording: openDataset would only say that it is not a folder.
    const bool empty = std::filesystem::file_size(options.input, error) == 0;
    throw InputError(
        fmt::format("{}: {}, not an MPEG-TS recording of `voca stream`; the input is a dataset or VOCA "
                    "video folder, a stream URL (udp://...) or such a recording",
                    options.input.string(), empty ? "an empty file" : "a file"));
  }
  RunInput input;
  const Dataset raw = openDataset(options.input);
  input.warnings = raw.warnings;
  for (std::string& warning : ignoredOptionWarnings(options, raw.layout)) input.warnings.push_back(std::move(warning));
  input.config = resolveRunConfig(options.config, raw.layout == DatasetLayout::kKitti);
  const std::optional<std::filesystem::path> calibration = options.calibration ? options.calibration : raw.calibration;
  requireOutputsApartFromInputs(options, &raw, calibration);
  if (!calibration) {
    throw InputError(
        fmt::format("{}: no calibration found beside the dataset; pass one with --calib", options.input.string()));
  }
  input.rig = loadCalibration(*calibration);
  input.rig.requireStereo();

  // Encoding first, the paper's way (two passes need the whole sequence), into a folder that is
  // removed however the run ends.
  Dataset dataset = raw;
  if (options.encode_bitrate_bps > 0 && raw.layout != DatasetLayout::kVocaVideo) {
    input.encoding = std::make_unique<TempDir>("voca-run");
    if (!encode::encodeForReplay(options.input, input.encoding->path(), options.encode_bitrate_bps, options.calibration,
                                 options.progress, stopRequest(options))) {
      input.stopped =
          stoppedBeforeFrames(fmt::format("{} (stopped while encoding)", options.input.string()), input.config);
      return input;
    }
    input.encoding_description =
        fmt::format("{} encoded at {} kbit/s", options.input.string(), options.encode_bitrate_bps / 1000);
    dataset = openDataset(input.encoding->path());
  }

  ReplayOptions replay;
  replay.first_frame = options.first_frame;
  replay.max_frames = options.max_frames;
  replay.strict = options.strict;
  input.source = openDatasetSource(dataset, replay);
  // Ground truth belongs to the recording, not to the temporary encoding of it.
  input.ground_truth = loadGroundTruth(raw, options.ground_truth);
  if (input.ground_truth) {
    input.ground_truth_name = (options.ground_truth ? *options.ground_truth : *raw.ground_truth).string();
  }
  return input;
}

}  // namespace

RunInput openRunInput(const VoRunOptions& options) {
  // Before the input is opened (the frontend would refuse it only after the decoder started).
  if (options.max_points < 1 || options.max_points > FrontendCapacities::kMaxPointsBound) {
    throw InputError(fmt::format("--max-points {}: expected 1 to {} points per camera", options.max_points,
                                 FrontendCapacities::kMaxPointsBound));
  }
  if (isStreamUrl(options.input.string())) return openStream(options, options.input.string());
  if (const std::optional<std::string> recording = recordedStreamUrl(options.input)) {
    return openStream(options, *recording);
  }
  return openDatasetInput(options);
}

void addInputToResult(RunInput& input, VoRunResult& result) {
  result.config_name = input.config.name;
  if (!input.encoding_description.empty()) {
    result.description = fmt::format("{}: {}", input.encoding_description, result.description);
  }
  result.warnings.insert(result.warnings.begin(), input.warnings.begin(), input.warnings.end());
  if (input.source) {
    for (const std::string& warning : input.source->warnings()) result.warnings.push_back(warning);
  }
  if (input.stream != nullptr) result.source_end = input.stream->endReason();
}

}  // namespace voca::pipeline
