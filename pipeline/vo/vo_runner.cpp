#include "pipeline/vo/vo_runner.h"

#include <fmt/core.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>

#include "drivers/encode/dataset_encoder.h"
#include "drivers/encode/video_encoder.h"
#include "drivers/source/dataset_source.h"
#include "drivers/source/network_source.h"
#include "formats/calib/calibration_io.h"
#include "formats/dataset/dataset.h"
#include "formats/eval/eval_report_json.h"
#include "pipeline/sinks/mcap_sink.h"
#include "pipeline/sinks/overlay_sink.h"
#include "pipeline/sinks/trajectory_sink.h"
#include "pipeline/sinks/view_sink.h"
#include "pipeline/stages/decode_stage.h"
#include "pipeline/stages/estimation_stages.h"
#include "pipeline/stages/source_stage.h"
#include "platform/filesystem/output_paths.h"
#include "platform/filesystem/temp_dir.h"
#include "platform/realtime/stop_signal.h"
#include "platform/realtime/thread_control.h"
#include "platform/terminal/progress_line.h"
#include "voca/core/error.h"
#include "voca/frontend/detector.h"
#include "voca/frontend/frontend.h"

namespace voca::pipeline {

namespace {

// The looser end of the stereo round trip (squared px) that the starved-right-camera hint suggests;
// a config already at or above it gets no hint.
constexpr double kHintedStereoRoundTripDist2 = 0.5;

// Progress on stderr: a line every few frames, and one per frame that was not tracked.
class ProgressSink final : public FrameSink {
 public:
  // suggest_flow_retry: retry_previous_flow does not act on this input, so a failure where the
  // temporal step lost most points gets a hint at that key, once. suggest_stereo_tolerance: the
  // left-right match's round trip is tighter than the hint suggests (kHintedStereoRoundTripDist2), so a failure where
  // the right camera holds few of the left camera's points gets a hint at stereo_max_recovered_dist2_px2, once.
  ProgressSink(std::int64_t total, bool estimate, int frontend_stage, int backend_stage, bool suggest_flow_retry,
               bool suggest_stereo_tolerance)
      : total_(total),
        estimate_(estimate),
        frontend_stage_(frontend_stage),
        backend_stage_(backend_stage),
        suggest_flow_retry_(suggest_flow_retry),
        suggest_stereo_tolerance_(suggest_stereo_tolerance) {}
  void consume(const FrameSlot& slot) override {
    ++frames_;
    if (estimate_ && slot.pose.state != TrackingState::kTracking) {
      line_.message("frame {}: {} ({})", slot.frame.frame_index, trackingStateName(slot.pose.state),
                    untrackedCause(slot.pose));
      hintAtFlowRetry(slot);
      hintAtStereoTolerance(slot);
    }
    if (frames_ % 20 != 0 && frames_ != total_) return;
    const auto ms = [&](int stage) {
      const StageTiming& t = slot.timing[static_cast<std::size_t>(stage)];
      return static_cast<double>(t.end_ns - t.start_ns) * 1e-6;
    };
    if (estimate_) {
      line_.update("frame {}: {} landmarks, {} keyframes in the window, {:.1f} + {:.1f} ms", count(),
                   slot.pose.num_landmarks, slot.pose.num_keyframes, ms(frontend_stage_), ms(backend_stage_));
    } else {
      line_.update("tracked {} frames", count());
    }
  }
  void finish() override { line_.end(); }

 private:
  // Most points lost in one step is image motion beyond the pyramid's reach more often than not
  // (a low frame rate, a fast turn): configs/README.md, "Faster than the pyramid reaches".
  void hintAtFlowRetry(const FrameSlot& slot) {
    constexpr int kMinPoints = 20;
    const TemporalStats& t = slot.frontend_stats.temporal[0];
    if (!suggest_flow_retry_ || slot.pose.failure != FailureReason::kTooFewInliers || t.previous < kMinPoints ||
        4 * t.kept >= t.previous)
      return;
    suggest_flow_retry_ = false;
    line_.message(
        "hint: the tracker lost {} of {} points from the previous frame: the image may move faster than the KLT "
        "pyramid reaches (a low frame rate, a fast turn). Set \"retry_previous_flow\": \"always\" in the "
        "config's frontend section (configs/README.md), or track a video with motion vectors in a prior mode.",
        t.previous - t.kept, t.previous);
  }

  // A right camera with few of the left camera's points: on strongly compressed video the stereo
  // matches fail their round trip (configs/README.md, "The left-right match's round trip").
  void hintAtStereoTolerance(const FrameSlot& slot) {
    constexpr int kMinPoints = 20;
    const FrontendStats& f = slot.frontend_stats;
    const bool starved =
        slot.pose.failure == FailureReason::kTooFewInliers || slot.pose.failure == FailureReason::kTooFewStereoPoints;
    if (!suggest_stereo_tolerance_ || !starved || f.num_left < kMinPoints || 4 * f.num_right >= f.num_left) return;
    suggest_stereo_tolerance_ = false;
    line_.message(
        "hint: the right camera holds {} of the left camera's {} points. On strongly compressed video the stereo "
        "matches fail their round trip (each camera's stream has its own artefacts): set "
        "\"stereo_max_recovered_dist2_px2\" to {}-1 in the config's frontend section (configs/README.md). A "
        "stereo calibration that is off, or \"matching_default_depth_m\" far from the scene's depth, loses them "
        "too.",
        f.num_right, f.num_left, kHintedStereoRoundTripDist2);
  }

  // "12/300", or "12" for live input of unknown length.
  std::string count() const { return total_ > 0 ? fmt::format("{}/{}", frames_, total_) : fmt::format("{}", frames_); }

  std::int64_t total_;
  bool estimate_;
  int frontend_stage_, backend_stage_;
  bool suggest_flow_retry_;
  bool suggest_stereo_tolerance_;
  std::int64_t frames_ = 0;
  platform::ProgressLine line_;
};

// VoRunResult::failure for a run whose every frame was lost, with the likeliest cause: a tracker
// capacity or images too small for the detection grid to give a frame the points the estimator
// needs, else calibration or config (the per-frame messages name each frame's reason).
std::string noEstimateReason(const VoRunResult& result, int max_points) {
  const FrontendConfig& tracker = result.config.frontend;
  const int cells = detectionCells(result.width, result.height, tracker.grid_size_px, tracker.detection_border_px);
  std::string reason = fmt::format("no pose was estimated: all {} frames were lost", result.frames);
  if (max_points < result.config.backend.min_inliers) {
    return reason + fmt::format(
                        ". The tracker keeps at most {} point{} per camera (--max-points), fewer than the {} a "
                        "frame needs (backend min_inliers)",
                        max_points, max_points == 1 ? "" : "s", result.config.backend.min_inliers);
  }
  if (cells < result.config.backend.min_inliers) {
    return reason + fmt::format(
                        ". The {}x{} images hold {} grid cells for corners (frontend grid_size_px {}, "
                        "detection_border_px {}), fewer than the {} points a frame needs (backend min_inliers): "
                        "lower those keys in the config",
                        result.width, result.height, cells, tracker.grid_size_px, tracker.detection_border_px,
                        result.config.backend.min_inliers);
  }
  return reason +
         ". Check the calibration (image size, intrinsics, the cameras' relative pose) and the config; the "
         "messages above give each frame's reason";
}

}  // namespace

bool encodeForReplay(const std::filesystem::path& input, const std::filesystem::path& out, std::int64_t bitrate_bps,
                     const std::optional<std::filesystem::path>& calibration, bool progress,
                     const std::function<bool()>& stop_requested) {
  encode::DatasetEncodeOptions encode_options;
  encode_options.settings.bitrate_bps = bitrate_bps;
  encode_options.calibration = calibration;
  encode_options.stop_requested = stop_requested;
  encode::silenceCodecLogs();
  // Ended by its destructor, also when an exception leaves: the caller's message starts a line.
  platform::ProgressLine line;
  const encode::DatasetEncodeReport report =
      encode::encodeDataset(input, out, encode_options, [&](int camera, int pass, int passes, int frame, int n) {
        if (progress && (frame % 50 == 0 || frame + 1 == n)) {
          line.update("encoding camera {} pass {}/{}: frame {}/{}", camera, pass, passes, frame + 1, n);
        }
      });
  return !report.stopped;
}

RunConfig resolveRunConfig(const std::optional<std::filesystem::path>& config, bool kitti_input) {
  if (config) return {loadConfig(*config), config->string()};
  // KITTI's street scenes and 0.54 m baseline put the paper's 2 m stereo guess ~190 px off.
  const std::string name = kitti_input ? "kitti" : "euroc";
  return {builtinConfig(name), name + " (built in)"};
}

namespace {

// Before anything is written: no output may be a file the run reads or lie in the dataset's data
// folders (`-o mav0/cam0/data.mp4` truncated the video it was about to decode), and no two outputs
// may be one file. dataset: nullptr for a stream; recording: the file a recorded stream is read from.
void requireOutputsApartFromInputs(const VoRunOptions& options, const Dataset* dataset,
                                   const std::optional<std::filesystem::path>& calibration,
                                   const std::optional<std::filesystem::path>& recording = std::nullopt) {
  const std::array<NamedPath, 5> outputs = {NamedPath{"the trajectory file", options.trajectory_file},
                                            NamedPath{"the statistics file", options.statistics_file},
                                            NamedPath{"the trace file", options.pipeline.trace_path},
                                            NamedPath{"the overlay video", options.overlay_file},
                                            NamedPath{"the MCAP recording", options.mcap.file}};
  std::vector<NamedPath> inputs;
  if (dataset != nullptr) inputs = datasetReadPaths(*dataset);
  if (recording) inputs.push_back({"the recorded stream", *recording});
  if (options.ground_truth) inputs.push_back({"the ground truth", *options.ground_truth});
  if (calibration) inputs.push_back({"the calibration", *calibration});
  if (options.config && std::filesystem::exists(*options.config)) inputs.push_back({"the config", *options.config});
  requireOutputsApart(outputs, inputs);
  // The statistics are written after the run: an unwritable path must not cost the whole run.
  for (const NamedPath& output : outputs) requireWritableFile(output);
}

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

// `voca run udp://...`: a stream carries no calibration or ground truth, so both come from options.
// A stream URL, or a recording of one (`url` is then its file:// URL).
VoRunResult runOnStream(const VoRunOptions& options, const std::string& url) {
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
  const StereoRig rig = loadCalibration(*options.calibration);
  if (rig.cameras.size() < 2) {
    throw InputError(fmt::format("{}: need a stereo calibration", options.calibration->string()));
  }
  const RunConfig resolved = resolveRunConfig(options.config);
  const VocaConfig& config = resolved.config;
  std::optional<Trajectory> gt;
  if (options.ground_truth) gt = loadTrajectory(*options.ground_truth);
  NetworkSourceOptions network;
  network.start_timeout_s = options.stream_start_timeout_s;
  network.timeout_s = options.stream_timeout_s;
  network.max_frames = options.max_frames;
  network.strict = options.strict;
  network.first_frame = options.first_frame;
  network.stop_requested = options.pipeline.stop_requested ? options.pipeline.stop_requested
                                                           : std::function<bool()>(platform::stopRequested);
  if (options.progress && !recording) {
    fmt::print(stderr, "waiting for the stream on {} (up to {} s)\n", url, options.stream_start_timeout_s);
  }
  std::optional<NetworkStereoSource> opened;
  try {
    opened.emplace(url, network);
  } catch (const InputError&) {
    if (!network.stop_requested()) throw;
    VoRunResult stopped;  // Ctrl-C while waiting for the stream: a clean stop, nothing estimated
    stopped.description = fmt::format("{} (stopped while waiting for the stream)", url);
    stopped.stop_signal = platform::stopSignal();
    stopped.config = config;
    stopped.config_name = resolved.name;
    if (!options.statistics_file.empty()) writeStatisticsJson(stopped, options.statistics_file);
    return stopped;
  }
  NetworkStereoSource& source = *opened;
  VoRunResult run = runVisualOdometryOn(source, rig, config, options, gt,
                                        options.ground_truth ? options.ground_truth->string() : std::string());
  for (std::string& warning : ignoredOptionWarnings(options, std::nullopt)) {
    run.warnings.push_back(std::move(warning));
  }
  run.config_name = resolved.name;
  run.source_end = source.endReason();
  if (!options.statistics_file.empty()) writeStatisticsJson(run, options.statistics_file);
  return run;
}

// VoRunOptions::frontend_camera_threads resolved (FrontendStage checks a value given). A helper
// thread pays only when another core is free to run it; a layout with pinned stages is the user's,
// and gets no thread it did not ask for, unless it pins the helper ("frontend.helper") too.
int frontendCameraThreads(const VoRunOptions& options) {
  if (options.frontend_camera_threads != 0) return options.frontend_camera_threads;
  const auto& pins = options.pipeline.pins;
  const std::string helper_pin = pipeline::helperPinName("frontend");
  if (std::any_of(pins.begin(), pins.end(), [&](const auto& pin) { return pin.first == helper_pin; })) return 2;
  const bool staged = options.pipeline.threads != 1;
  return staged && pins.empty() && platform::availableCores() >= 2 ? 2 : 1;
}

}  // namespace

VoRunResult runVisualOdometry(const VoRunOptions& options) {
  // Before the input is opened (the frontend would refuse it only after the decoder started).
  if (options.max_points < 1 || options.max_points > FrontendCapacities::kMaxPointsBound) {
    throw InputError(fmt::format("--max-points {}: expected 1 to {} points per camera", options.max_points,
                                 FrontendCapacities::kMaxPointsBound));
  }
  if (isStreamUrl(options.input.string())) return runOnStream(options, options.input.string());
  if (const std::optional<std::string> recording = recordedStreamUrl(options.input)) {
    return runOnStream(options, *recording);
  }
  if (std::error_code error; std::filesystem::is_regular_file(options.input, error)) {
    // A file that is no recording: openDataset would only say that it is not a folder.
    const bool empty = std::filesystem::file_size(options.input, error) == 0;
    throw InputError(
        fmt::format("{}: {}, not an MPEG-TS recording of `voca stream`; the input is a dataset or VOCA "
                    "video folder, a stream URL (udp://...) or such a recording",
                    options.input.string(), empty ? "an empty file" : "a file"));
  }
  VoRunResult result;
  const Dataset raw = openDataset(options.input);
  result.warnings = raw.warnings;
  for (std::string& warning : ignoredOptionWarnings(options, raw.layout)) {
    result.warnings.push_back(std::move(warning));
  }
  RunConfig resolved = resolveRunConfig(options.config, raw.layout == DatasetLayout::kKitti);
  result.config = std::move(resolved.config);
  result.config_name = std::move(resolved.name);
  if (options.mode) result.config.frontend.prior_mode = *options.mode;
  if (options.bridge_iframes) result.config.frontend.bridge_iframes = *options.bridge_iframes;
  const std::optional<std::filesystem::path> calibration = options.calibration ? options.calibration : raw.calibration;
  requireOutputsApartFromInputs(options, &raw, calibration);
  if (!calibration) {
    throw InputError(
        fmt::format("{}: no calibration found beside the dataset; pass one with --calib", options.input.string()));
  }
  const StereoRig rig = loadCalibration(*calibration);
  if (rig.cameras.size() < 2) throw InputError(fmt::format("{}: need a stereo calibration", calibration->string()));
  const std::function<bool()> stop_requested = options.pipeline.stop_requested
                                                   ? options.pipeline.stop_requested
                                                   : std::function<bool()>(platform::stopRequested);

  // Encoding first, the paper's way (two passes need the whole sequence), into a folder that is
  // removed however the run ends.
  std::optional<TempDir> temp;
  Dataset dataset = raw;
  if (options.encode_bitrate_bps > 0 && raw.layout != DatasetLayout::kVocaVideo) {
    temp.emplace("voca-run");
    if (!encodeForReplay(options.input, temp->path(), options.encode_bitrate_bps, options.calibration, options.progress,
                         stop_requested)) {
      result.stop_signal = platform::stopSignal();
      result.description = fmt::format("{} (stopped while encoding)", options.input.string());
      if (!options.statistics_file.empty()) writeStatisticsJson(result, options.statistics_file);
      return result;
    }
    dataset = openDataset(temp->path());
  }

  ReplayOptions replay;
  replay.first_frame = options.first_frame;
  replay.max_frames = options.max_frames;
  replay.strict = options.strict;
  std::unique_ptr<StereoSource> source = openDatasetSource(dataset, replay);
  // Ground truth belongs to the recording, not to the temporary encoding of it.
  const std::optional<Trajectory> gt = loadGroundTruth(raw, options.ground_truth);
  std::string gt_name;
  if (gt) gt_name = (options.ground_truth ? *options.ground_truth : *raw.ground_truth).string();
  VoRunResult run = runVisualOdometryOn(*source, rig, result.config, options, gt, gt_name);
  run.config_name = result.config_name;
  if (temp) {
    run.description = fmt::format("{} encoded at {} kbit/s: {}", options.input.string(),
                                  options.encode_bitrate_bps / 1000, run.description);
  }
  run.warnings.insert(run.warnings.begin(), result.warnings.begin(), result.warnings.end());
  for (const std::string& warning : source->warnings()) run.warnings.push_back(warning);
  if (!options.statistics_file.empty()) writeStatisticsJson(run, options.statistics_file);
  return run;
}

VoRunResult runVisualOdometryOn(StereoSource& source, const StereoRig& rig, const VocaConfig& config,
                                const VoRunOptions& options, const std::optional<Trajectory>& ground_truth,
                                const std::string& ground_truth_name) {
  VoRunResult result;
  result.config = config;
  result.rig = rig;
  if (options.mode) result.config.frontend.prior_mode = *options.mode;
  if (options.bridge_iframes) result.config.frontend.bridge_iframes = *options.bridge_iframes;
  const std::function<bool()> stop_requested = options.pipeline.stop_requested
                                                   ? options.pipeline.stop_requested
                                                   : std::function<bool()>(platform::stopRequested);
  const SourceInfo& info = source.info();
  result.description = info.description;
  result.width = info.width;
  result.height = info.height;
  for (int c = 0; c < 2; ++c) {
    const CameraCalibration& camera = rig.cameras[static_cast<std::size_t>(c)];
    if (info.width != camera.width || info.height != camera.height) {
      throw InputError(fmt::format("{}: images are {}x{} but the calibration {} says {}x{} for camera {}",
                                   info.description, info.width, info.height, rig.source, camera.width, camera.height,
                                   c));
    }
  }
  // Decoded frames carry motion vectors; the decode stage marks every frame it hands on.
  result.has_motion = info.kind == SourceKind::kEncoded;

  // The live view, before any output is opened: an address that cannot be bound stops the run here.
  std::unique_ptr<view::FoxgloveServer> own_view_server;
  view::FoxgloveServer* view_server = options.view.server;
  if (view_server == nullptr && !options.view.address.empty()) {
    own_view_server = startViewServer(options.view.address, options.view.image_rate_hz, stderr);
    view_server = own_view_server.get();
  }
  // What sinks read beyond the basics, so the stages copy it only then.
  FrameSinkNeeds needs;
  for (const FrameSink* extra : options.extra_sinks) {
    needs.left_traces = needs.left_traces || extra->needs().left_traces;
    needs.landmarks = needs.landmarks || extra->needs().landmarks;
  }
  if (view_server != nullptr || !options.mcap.file.empty()) needs = {.left_traces = true, .landmarks = true};

  // The stages, in data-flow order; positions count the source as 0.
  SourceStageOptions source_options;
  source_options.realtime = options.realtime;
  source_options.speed = options.speed;
  SourceStageAdapter source_stage(source, source_options);
  std::vector<Stage*> chain;
  std::unique_ptr<DecodeStage> decode_stage;
  int decode_position = -1;
  if (info.kind == SourceKind::kEncoded) {
    DecodeStageOptions decode_options;
    decode_options.decoder.kind = options.decoder;
    decode_options.decoder.strict = options.strict;
    decode_options.decoder.skip_loop_filter = options.skip_deblock;
    decode_options.decoder.export_qp = config.frontend.prior_max_qp > 0;  // only the QP check reads them
    decode_options.decoder.log_choice = false;
    decode_options.first_tracked_frame = info.first_tracked_frame;
    for (std::size_t c = 0; c < 2; ++c) {
      decode_options.names[c] = info.stream_names[c].empty() ? fmt::format("cam{}", c) : info.stream_names[c];
    }
    decode_stage = std::make_unique<DecodeStage>(info.streams, decode_options);
    result.decoder_description = decode_stage->description();
    if (options.progress) fmt::print(stderr, "{}\n", result.decoder_description);  // the choice, logged once
    chain.push_back(decode_stage.get());
    decode_position = static_cast<int>(chain.size());
  }
  const bool uses_depth = options.estimate && result.config.frontend.matching_guess == StereoGuess::kAverageDepth;
  DepthHintChannel hints;
  result.frontend_camera_threads = frontendCameraThreads(options);
  FrontendStage frontend(result.config.frontend, rig, {.max_points = options.max_points}, uses_depth ? &hints : nullptr,
                         !options.overlay_file.empty() || needs.left_traces, result.frontend_camera_threads);
  chain.push_back(&frontend);
  const int frontend_position = static_cast<int>(chain.size());
  std::unique_ptr<BackendStage> backend;
  int backend_position = -1;
  if (options.estimate) {
    backend =
        std::make_unique<BackendStage>(result.config.backend, rig, uses_depth ? &hints : nullptr, needs.landmarks);
    chain.push_back(backend.get());
    backend_position = static_cast<int>(chain.size());
  }

  const int max_landmarks = backend && needs.landmarks ? backend->landmarkCapacity() : 0;
  // The recording first among the outputs: a file that cannot be created leaves no other behind.
  std::unique_ptr<McapSink> recording;
  if (!options.mcap.file.empty()) {
    recording = std::make_unique<McapSink>(McapSinkOptions{.file = options.mcap.file,
                                                           .width = info.width,
                                                           .height = info.height,
                                                           .max_points = options.max_points,
                                                           .max_landmarks = max_landmarks,
                                                           .stages = {.decode = decode_position,
                                                                      .frontend = frontend_position,
                                                                      .backend = backend_position,
                                                                      .sink = static_cast<int>(chain.size()) + 1},
                                                           .ground_truth = ground_truth ? &*ground_truth : nullptr,
                                                           .image_rate_hz = options.mcap.image_rate_hz});
  }

  const auto expected = static_cast<std::size_t>(std::max<std::int64_t>(info.expected_frames, 0));
  // Live input has no known length: keep an hour of rows at 30 Hz in memory and count the rest.
  const std::size_t capacity = expected > 0 ? expected : 30 * 3600;
  std::vector<FrameSink*> sinks;
  std::unique_ptr<TrajectorySink> trajectory;
  if (options.estimate) {
    trajectory = std::make_unique<TrajectorySink>(
        options.trajectory_file.empty() ? std::nullopt : std::optional<std::filesystem::path>(options.trajectory_file),
        options.trajectory_format, options.keep_trajectory ? capacity : 0, rig.cameras[0].T_body_cam);
    sinks.push_back(trajectory.get());
  }
  StatisticsSink statistics(capacity, decode_position, frontend_position, backend_position);
  sinks.push_back(&statistics);
  std::unique_ptr<OverlaySink> overlay;
  if (!options.overlay_file.empty()) {
    encode::silenceCodecLogs();  // libavcodec prints x264's settings at info level otherwise
    const int fps = info.nominal_rate_hz > 0.0 ? static_cast<int>(std::lround(info.nominal_rate_hz)) : 20;
    overlay = std::make_unique<OverlaySink>(options.overlay_file, fps, info.width, info.height);
    sinks.push_back(overlay.get());
  }
  std::unique_ptr<ProgressSink> progress;
  if (options.progress) {
    const FrontendConfig& tracker = result.config.frontend;
    progress =
        std::make_unique<ProgressSink>(info.expected_frames, options.estimate, frontend_position, backend_position,
                                       !appliesTo(tracker.retry_previous_flow, result.has_motion),
                                       tracker.stereoRoundTripDist2() < kHintedStereoRoundTripDist2);
    sinks.push_back(progress.get());
  }
  std::unique_ptr<ViewSink> view;
  if (view_server != nullptr) {
    view = std::make_unique<ViewSink>(*view_server,
                                      ViewSinkOptions{.width = info.width,
                                                      .height = info.height,
                                                      .max_points = options.max_points,
                                                      .max_landmarks = max_landmarks,
                                                      .stages = {.decode = decode_position,
                                                                 .frontend = frontend_position,
                                                                 .backend = backend_position,
                                                                 .sink = static_cast<int>(chain.size()) + 1},
                                                      .ground_truth = ground_truth ? &*ground_truth : nullptr});
    view->start();
    sinks.push_back(view.get());
  }
  if (recording) {
    recording->start();
    sinks.push_back(recording.get());
  }
  sinks.insert(sinks.end(), options.extra_sinks.begin(), options.extra_sinks.end());
  SinkStage sink(sinks);
  chain.push_back(&sink);

  PipelineOptions pipeline_options = options.pipeline;
  pipeline_options.live_policy = options.pipeline.live_policy || options.realtime || info.live;
  pipeline_options.slot_shape = {info.width, info.height, options.max_points, max_landmarks};
  pipeline_options.stop_requested = stop_requested;
  Pipeline pipeline(source_stage, chain, pipeline_options);
  result.started = true;
  result.pipeline = pipeline.run();
  if (result.pipeline.stopped) result.stop_signal = platform::stopSignal();
  result.source = source.counters();

  result.frames = statistics.frames();
  result.frontend = statistics.frontend();
  result.backend = statistics.backend();
  result.rows = statistics.rows();
  if (trajectory) result.trajectory = trajectory->trajectory();
  for (const std::string& warning : result.pipeline.warnings) result.warnings.push_back(warning);
  if (recording) {
    recording->finish();  // done by the sink stage already, unless the run failed before it
    if (!recording->failure().empty()) result.warnings.push_back(recording->failure());
    if (recording->dropped() > 0 || recording->imagesSkipped() > 0) {
      result.warnings.push_back(fmt::format(
          "MCAP recording {}: the recorder fell behind: {} frames not recorded, {} recorded without their image",
          options.mcap.file.string(), recording->dropped(), recording->imagesSkipped()));
    }
  }
  if (options.estimate && !result.pipeline.stopped && !result.pipeline.error && result.frames > 0 &&
      result.backend.keyframes == 0 && result.backend.lost >= result.frames) {
    result.failure = noEstimateReason(result, options.max_points);
  }

  if (options.estimate && options.keep_trajectory && ground_truth && !result.trajectory.poses.empty()) {
    result.ground_truth = ground_truth_name;
    EvalOptions eval_options;
    eval_options.expected_frames = static_cast<std::size_t>(std::max<std::int64_t>(info.expected_frames, 0));
    // Every row of a run that estimated nothing is the start pose held: its ATE and RTE would measure
    // the ground truth's own motion, not an estimate.
    if (result.failure.empty()) {
      try {
        result.eval = evaluateTrajectory(result.trajectory, *ground_truth, eval_options);
      } catch (const InputError& e) {
        result.warnings.push_back(fmt::format("cannot evaluate against {}: {}", ground_truth_name, e.what()));
      }
    }
  }
  return result;
}

namespace {

double ms(std::int64_t ns) { return static_cast<double>(ns) * 1e-6; }

const StageReport* findStage(const RunReport& report, std::string_view name) {
  for (const StageReport& s : report.stages) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

double pct(std::int64_t a, std::int64_t b) {
  return b > 0 ? 100.0 * static_cast<double>(a) / static_cast<double>(b) : 0.0;
}

}  // namespace

void printRunSummary(const VoRunResult& r, std::FILE* out) {
  fmt::print(out, "input: {}\n", r.description);
  fmt::print(out, "mode: {}{}\n", priorModeName(r.config.frontend.prior_mode),
             r.has_motion ? "" : " (raw images: no motion vectors)");
  fmt::print(out, "frames: {}, keyframes: {}, resets: {}, lost: {}\n", r.frames, r.backend.keyframes, r.backend.resets,
             r.backend.lost);
  const StageReport* frontend = findStage(r.pipeline, "frontend");
  const StageReport* backend = findStage(r.pipeline, "backend");
  if (frontend != nullptr && backend != nullptr) {
    fmt::print(out,
               "ms per frame: frontend median {:.2f} (mean {:.2f}, p99 {:.2f}), backend median {:.2f} (mean {:.2f}, "
               "p99 {:.2f})\n",
               ms(frontend->service.quantileNs(0.5)), frontend->service.meanNs() * 1e-6,
               ms(frontend->service.quantileNs(0.99)), ms(backend->service.quantileNs(0.5)),
               backend->service.meanNs() * 1e-6, ms(backend->service.quantileNs(0.99)));
  }
  if (r.started) {
    fmt::print(out, "pipeline: {} thread{}{}, {:.1f} frames/s ({:.2f} s)\n", r.pipeline.threads,
               r.pipeline.threads == 1 ? "" : "s",
               r.frontend_camera_threads > 1 ? " (and a frontend helper sharing the tracking)" : "",
               r.pipeline.wall_s > 0.0 ? static_cast<double>(r.pipeline.completed) / r.pipeline.wall_s : 0.0,
               r.pipeline.wall_s);
  }
  if (r.pipeline.dropped > 0 || r.pipeline.damaged > 0) {
    fmt::print(out, "skipped frames: {} dropped (live policy), {} damaged:", r.pipeline.dropped, r.pipeline.damaged);
    int listed = 0;
    for (const ReleasedFrame& f : r.pipeline.released) {
      if (f.reason != ReleaseReason::kDropped && f.reason != ReleaseReason::kDamaged) continue;
      if (listed++ == 20) {
        fmt::print(out, " ...");
        break;
      }
      fmt::print(out, " {}{}", f.frame_index, f.reason == ReleaseReason::kDamaged ? "(damaged)" : "");
    }
    fmt::print(out, "\n");
  }
  if (r.source.frames_lost > 0 || r.source.unpaired > 0 || !r.source_end.empty()) {
    fmt::print(out, "source: {} frames lost before capture (driver or network), {} unpaired stereo frames{}\n",
               r.source.frames_lost, r.source.unpaired,
               r.source_end.empty() ? "" : fmt::format("; ended: {}", r.source_end));
  }
  if (r.eval) {
    fmt::print(out, "ground truth: {} ({} poses associated)\n", r.ground_truth, r.eval->ate.stats.count);
    fmt::print(out, "ATE: {:.4f} m RMSE{}\n", r.eval->ate.stats.rmse, r.eval->ate_divergent ? " (divergent)" : "");
    if (r.eval->rte) {
      fmt::print(out, "RTE (6 frames): {:.4f} m RMSE{}\n", r.eval->rte->stats.rmse,
                 r.eval->rte_divergent ? " (divergent)" : "");
    }
  } else if (!r.started) {
    fmt::print(out, "ATE/RTE: not computed (stopped before the first frame)\n");
  } else if (!r.ground_truth.empty()) {
    fmt::print(out, "ground truth: {}, not evaluated ({})\n", r.ground_truth,
               r.failure.empty() ? "see the warning" : "no pose was estimated");
  } else {
    fmt::print(out, "no ground truth with the dataset: ATE/RTE not computed\n");
  }
}

void printTrackSummary(const VoRunResult& r, const FrontendConfig& config, std::FILE* out) {
  const FrontendTotals& t = r.frontend;
  const double frames = static_cast<double>(std::max<std::int64_t>(r.frames, 1));
  fmt::print(out, "input: {}\n", r.description);
  fmt::print(out, "mode: {}{}, pattern {}, levels {}, grid {} px\n", priorModeName(config.prior_mode),
             r.has_motion ? "" : " (raw images: no motion vectors, priors inactive)", config.pattern,
             config.pyramid_levels, config.grid_size_px);
  fmt::print(out, "tracks per frame: left mean {:.1f} (min {}, max {}), right mean {:.1f}\n",
             static_cast<double>(t.left_points) / frames, t.min_left, t.max_left,
             static_cast<double>(t.right_points) / frames);
  fmt::print(out, "survival frame to frame: {:.1f} % of {} temporal tracks kept (both cameras)\n",
             pct(t.kept, t.previous), t.previous);
  fmt::print(out, "with motion vector: {:.1f} %{}; tracked from previous position: {}, from MV prior: {}\n",
             pct(t.with_vector, t.previous),
             t.distrusted > 0 ? fmt::format(" ({:.1f} % of them distrusted)", pct(t.distrusted, t.with_vector))
                              : std::string(),
             t.tracked_plain, t.tracked_prior);
  if (t.prior_confirmed > 0) {
    fmt::print(out, "prior tracks not run, the vector landing within prior_agree_radius_px of the plain result: {}\n",
               t.prior_confirmed);
  }
  fmt::print(out,
             "rescued by the prior: {} ({:.2f} per frame); consensus rejections: {} ({:.2f} per frame); bridged "
             "I-frames: {}\n",
             t.rescued, static_cast<double>(t.rescued) / frames, t.consensus, static_cast<double>(t.consensus) / frames,
             t.bridged_frames);
  // r.has_motion: the frames were decoded from video (raw ones have no vectors).
  if (appliesTo(config.retry_previous_flow, r.has_motion)) {
    fmt::print(out, "kept by the retry from the previous image flow (retry_previous_flow): {} ({:.2f} per frame)\n",
               t.flow_retried, static_cast<double>(t.flow_retried) / frames);
    if (t.flow_searched > 0) {
      fmt::print(out,
                 "  retries with no flow measured yet (the run started in fast motion) started from the whole "
                 "image's shift: {} camera steps\n",
                 t.flow_searched);
    }
  }
  fmt::print(out, "new points: {:.1f} per frame, {:.1f} % matched in the right image; epipolar rejections: {}\n",
             static_cast<double>(t.detected) / frames, pct(t.stereo_matched, t.detected), t.epipolar);
  if (config.detection_nonoverlap) {
    fmt::print(out, "right-only points (detection_nonoverlap): {:.1f} new per frame\n",
               static_cast<double>(t.detected_right_only) / frames);
  }
  if (config.stereo_rematch) {
    fmt::print(out, "left tracks found again in the right image (stereo_rematch): {:.1f} per frame\n",
               static_cast<double>(t.stereo_rematched) / frames);
  }
  if (config.thin_when_full_px > 0.0) {
    fmt::print(out, "tracks dropped next to an older one (thin_when_full_px {}): {:.1f} per frame\n",
               config.thin_when_full_px, static_cast<double>(t.thinned) / frames);
  }
  if (t.guess_prior.count() > 0) {
    fmt::print(out,
               "guess to converged distance (px, {} kept tracks with a vector): previous position median {} p90 "
               "{}; MV prior median {} p90 {}\n",
               t.guess_prior.count(), t.guess_plain.formatQuantile(0.5), t.guess_plain.formatQuantile(0.9),
               t.guess_prior.formatQuantile(0.5), t.guess_prior.formatQuantile(0.9));
  }
  if (const StageReport* frontend = findStage(r.pipeline, "frontend")) {
    fmt::print(out,
               "time per stereo frame: wall median {:.2f} ms, p99 {:.2f} ms; thread CPU median {:.2f} ms, p99 {:.2f} "
               "ms\n",
               ms(frontend->service.quantileNs(0.5)), ms(frontend->service.quantileNs(0.99)),
               ms(frontend->cpu.quantileNs(0.5)), ms(frontend->cpu.quantileNs(0.99)));
  }
}

namespace {

nlohmann::json histogramJson(const LatencyHistogram& h) {
  return {{"count", h.count()},
          {"p50_ms", ms(h.quantileNs(0.5))},
          {"p90_ms", ms(h.quantileNs(0.9))},
          {"p99_ms", ms(h.quantileNs(0.99))},
          {"max_ms", ms(h.maxNs())},
          {"mean_ms", h.meanNs() * 1e-6}};
}

nlohmann::json distanceJson(const DistanceHistogram& h) {
  // Sparse: [bin start px, count] for the non-empty bins, the overflow bin as its start (16 px).
  nlohmann::json bins = nlohmann::json::array();
  for (int b = 0; b <= DistanceHistogram::kBins; ++b) {
    const std::int64_t count = h.bins()[static_cast<std::size_t>(b)];
    if (count > 0) bins.push_back({b * DistanceHistogram::kBinPx, count});
  }
  return {{"count", h.count()},
          {"median_px", h.quantile(0.5)},
          {"p90_px", h.quantile(0.9)},
          {"bin_px", DistanceHistogram::kBinPx},
          {"bins", bins}};
}

}  // namespace

void writeStatisticsJson(const VoRunResult& r, const std::filesystem::path& file) {
  nlohmann::json j;
  j["input"] = r.description;
  j["config"] = r.config_name;
  j["mode"] = std::string(priorModeName(r.config.frontend.prior_mode));
  j["bridge_iframes"] = r.config.frontend.bridge_iframes;
  j["has_motion"] = r.has_motion;
  j["decoder"] = r.decoder_description;
  j["image_size"] = {r.width, r.height};
  j["frames"] = r.frames;
  j["stopped_by_signal"] = r.stop_signal;
  j["source_ended"] = r.source_end;  // live input: why it ended; the counters are under "pipeline"
  const RunReport& p = r.pipeline;
  if (p.error) {
    j["error"] = {{"stage", p.error->stage}, {"frame", p.error->frame_index}, {"message", p.error->message}};
  }
  j["backend"] = {{"keyframes", r.backend.keyframes}, {"resets", r.backend.resets}, {"lost", r.backend.lost}};
  const FrontendTotals& t = r.frontend;
  j["frontend"] = {{"temporal_tracks", t.previous},
                   {"kept", t.kept},
                   {"rescued_by_prior", t.rescued},
                   {"consensus_rejections", t.consensus},
                   {"tracked_from_previous", t.tracked_plain},
                   {"tracked_from_prior", t.tracked_prior},
                   {"with_vector", t.with_vector},
                   {"distrusted_vectors", t.distrusted},
                   {"prior_tracks_confirmed", t.prior_confirmed},
                   {"flow_retried", t.flow_retried},
                   {"flow_searched", t.flow_searched},
                   {"detected", t.detected},
                   {"detected_right_only", t.detected_right_only},
                   {"thinned", t.thinned},
                   {"stereo_matched", t.stereo_matched},
                   {"stereo_rematched", t.stereo_rematched},
                   {"epipolar_rejections", t.epipolar},
                   {"bridged_frames", t.bridged_frames},
                   {"left_points", t.left_points},
                   {"right_points", t.right_points},
                   {"guess_distance_previous", distanceJson(t.guess_plain)},
                   {"guess_distance_prior", distanceJson(t.guess_prior)}};
  nlohmann::json stages = nlohmann::json::array();
  for (const StageReport& s : p.stages) {
    nlohmann::json stage = {{"name", s.name},
                            {"thread", s.thread},
                            {"core", s.core},
                            {"service", histogramJson(s.service)},
                            {"wait", histogramJson(s.wait)},
                            {"cpu", histogramJson(s.cpu)},
                            {"queue_high_water", s.queue_high_water},
                            {"dropped", s.dropped},
                            {"damaged", s.damaged}};
    if (s.helper_service.count() > 0) {
      stage["helper"] = {
          {"core", s.helper_core}, {"service", histogramJson(s.helper_service)}, {"cpu", histogramJson(s.helper_cpu)}};
    }
    stages.push_back(stage);
  }
  nlohmann::json released = nlohmann::json::array();
  for (const ReleasedFrame& f : p.released) {
    if (f.reason == ReleaseReason::kDropped || f.reason == ReleaseReason::kDamaged) {
      released.push_back({{"frame", f.frame_index},
                          {"stage", p.stages[static_cast<std::size_t>(f.stage)].name},
                          {"reason", f.reason == ReleaseReason::kDropped ? "dropped" : "damaged"}});
    }
  }
  j["pipeline"] = {{"threads", p.threads},
                   {"frontend_camera_threads", r.frontend_camera_threads},
                   {"wall_s", p.wall_s},
                   {"frames_per_s", p.wall_s > 0 ? static_cast<double>(p.completed) / p.wall_s : 0.0},
                   {"produced", p.produced},
                   {"source_frames_lost", r.source.frames_lost},
                   {"source_unpaired", r.source.unpaired},
                   {"completed", p.completed},
                   {"dropped", p.dropped},
                   {"damaged", p.damaged},
                   {"skipped_frames", released},
                   {"end_to_end", histogramJson(p.end_to_end)},
                   {"stages", stages}};
  if (r.eval) {
    j["eval"] = evalReportToJson(*r.eval, EvalOptions{});
    j["ground_truth"] = r.ground_truth;
  }
  nlohmann::json rows = nlohmann::json::array();
  for (const FrameRecord& f : r.rows) {
    rows.push_back({f.frame_index,
                    f.t_ns,
                    f.missing_before,
                    std::string(1, f.picture_type),
                    f.bridged,
                    f.left,
                    f.right,
                    f.kept,
                    f.lost,
                    f.rescued,
                    f.consensus_rejections,
                    f.detected,
                    std::string(trackingStateName(static_cast<TrackingState>(f.state))),
                    f.keyframe,
                    f.landmarks,
                    f.inliers,
                    f.decode_ms,
                    f.frontend_ms,
                    f.backend_ms,
                    f.frontend_cpu_ms,
                    f.backend_cpu_ms});
  }
  j["frame_columns"] = {"frame",
                        "t_ns",
                        "missing_before",
                        "picture",
                        "bridged",
                        "left",
                        "right",
                        "kept",
                        "lost",
                        "rescued",
                        "consensus_rejections",
                        "detected",
                        "state",
                        "keyframe",
                        "landmarks",
                        "inliers",
                        "decode_ms",
                        "frontend_ms",
                        "backend_ms",
                        "frontend_cpu_ms",
                        "backend_cpu_ms"};
  j["frame_rows"] = rows;
  j["frame_rows_truncated"] = r.frames > static_cast<std::int64_t>(r.rows.size());
  std::ofstream file_out(file);
  file_out << j.dump(1) << "\n";
  if (!file_out) throw InputError(fmt::format("cannot write statistics file {}", file.string()));
}

}  // namespace voca::pipeline
