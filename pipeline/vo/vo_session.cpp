#include "pipeline/vo/vo_session.h"

#include <fmt/core.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <utility>
#include <vector>

#include "drivers/encode/video_encoder.h"
#include "pipeline/sinks/mcap_sink.h"
#include "pipeline/sinks/overlay_sink.h"
#include "pipeline/sinks/progress_sink.h"
#include "pipeline/sinks/ros2_sink.h"
#include "pipeline/sinks/trajectory_sink.h"
#include "pipeline/sinks/view_sink.h"
#include "pipeline/stages/decode_stage.h"
#include "pipeline/stages/encode_stage.h"
#include "pipeline/stages/estimation_stages.h"
#include "pipeline/stages/source_stage.h"
#include "pipeline/vo/run_summary.h"
#include "platform/realtime/stop_signal.h"
#include "platform/realtime/thread_control.h"
#include "voca/core/error.h"

namespace voca::pipeline {

namespace {

// VoRunOptions::frontend_camera_threads resolved (FrontendStage checks a value given). A helper
// thread pays only when another core is free to run it; a layout with pinned stages is the user's,
// and gets no thread it did not ask for, unless it pins the helper ("frontend.helper") too.
int frontendCameraThreads(const VoRunOptions& options) {
  if (options.frontend_camera_threads != 0) return options.frontend_camera_threads;
  const auto& pins = options.pipeline_options.pins;
  const std::string helper_pin = helperPinName("frontend");
  if (std::any_of(pins.begin(), pins.end(), [&](const auto& pin) { return pin.first == helper_pin; })) return 2;
  const bool staged = options.pipeline_options.threads != 1;
  return staged && pins.empty() && platform::availableCores() >= 2 ? 2 : 1;
}

void requireImagesMatchCalibration(const SourceInfo& info, const StereoRig& rig) {
  for (int c = 0; c < 2; ++c) {
    const CameraCalibration& camera = rig.cameras[static_cast<std::size_t>(c)];
    if (info.width != camera.width || info.height != camera.height) {
      throw InputError(fmt::format("{}: images are {}x{} but the calibration {} says {}x{} for camera {}",
                                   info.description, info.width, info.height, rig.source, camera.width, camera.height,
                                   c));
    }
  }
}

}  // namespace

VocaConfig configForRun(const VocaConfig& config, const VoRunOptions& options) {
  VocaConfig run = config;
  if (options.mode) run.frontend.prior_mode = *options.mode;
  if (options.bridge_iframes) run.frontend.bridge_iframes = *options.bridge_iframes;
  return run;
}

struct VoSession::Impl {
  StereoSource& source;
  VoRunOptions options;
  VoRunResult result;
  std::optional<Trajectory> ground_truth;
  std::atomic<bool> stop{false};

  std::unique_ptr<SourceStageAdapter> source_stage;
  std::unique_ptr<EncodeStage> encode_stage;
  std::unique_ptr<DecodeStage> decode_stage;
  DepthHintChannel hints;
  std::unique_ptr<FrontendStage> frontend;
  std::unique_ptr<BackendStage> backend;
  std::unique_ptr<TrajectorySink> trajectory;
  std::unique_ptr<StatisticsSink> statistics;
  std::unique_ptr<OverlaySink> overlay;
  std::unique_ptr<ProgressSink> progress;
  std::unique_ptr<Ros2Sink> ros2;
  std::unique_ptr<view::FoxgloveServer> own_view_server;
  std::unique_ptr<ViewSink> view;
  std::unique_ptr<McapSink> recording;
  std::unique_ptr<SinkStage> sink;
  std::unique_ptr<Pipeline> pipeline;
  StagePositions positions;
  bool ran = false;

  Impl(StereoSource& s, const VoRunOptions& o) : source(s), options(o) {}
  void build(const StereoRig& rig);
  void collect();
};

VoSession::VoSession(StereoSource& source, const StereoRig& rig, const VocaConfig& config, const VoRunOptions& options,
                     std::optional<Trajectory> ground_truth, std::string ground_truth_name)
    : impl_(std::make_unique<Impl>(source, options)) {
  Impl& d = *impl_;
  d.result.config = configForRun(config, options);
  d.result.rig = rig;
  d.result.ground_truth = std::move(ground_truth_name);
  d.ground_truth = std::move(ground_truth);
  d.build(rig);
}

VoSession::~VoSession() = default;

void VoSession::Impl::build(const StereoRig& rig) {
  rig.requireStereo();
  const SourceInfo& info = source.info();
  result.description = info.description;
  result.width = info.width;
  result.height = info.height;
  requireImagesMatchCalibration(info, rig);
  const bool encode_live = options.live_encode && info.kind == SourceKind::kRaw;
  // Decoded frames carry motion vectors; the decode stage marks every frame it hands on.
  result.has_motion = info.kind == SourceKind::kEncoded || encode_live;

  // The live view, before any output is opened: an address that cannot be bound stops the run here.
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
  source_options.raw_to_frame = !encode_live;
  source_stage = std::make_unique<SourceStageAdapter>(source, source_options);
  std::vector<Stage*> chain;
  std::array<decode::StreamInfo, 2> streams = info.streams;
  std::array<std::string, 2> stream_names = info.stream_names;
  if (encode_live) {
    encode::LiveEncoderSettings live = *options.live_encode;
    if (info.nominal_rate_hz > 0.0) encode::setFrameRate(live, info.nominal_rate_hz);
    encode_stage = std::make_unique<EncodeStage>(live, info.width, info.height);
    if (options.progress) fmt::print(stderr, "{}\n", encode_stage->description());
    streams = encode_stage->streams();
    stream_names = {"cam0 (encoded live)", "cam1 (encoded live)"};
    chain.push_back(encode_stage.get());
    positions.encode = static_cast<int>(chain.size());
  }
  int decode_position = -1;
  if (info.kind == SourceKind::kEncoded || encode_live) {
    DecodeStageOptions decode_options;
    decode_options.decoder.kind = options.decoder;
    decode_options.decoder.strict = options.strict;
    decode_options.decoder.skip_loop_filter = options.skip_deblock;
    decode_options.decoder.export_qp = result.config.frontend.prior_max_qp > 0;  // only the QP check reads them
    decode_options.decoder.log_choice = false;
    decode_options.first_tracked_frame = info.first_tracked_frame;
    for (std::size_t c = 0; c < 2; ++c) {
      decode_options.names[c] = stream_names[c].empty() ? fmt::format("cam{}", c) : stream_names[c];
    }
    decode_stage = std::make_unique<DecodeStage>(streams, decode_options);
    result.decoder_description = decode_stage->description();
    if (options.progress) fmt::print(stderr, "{}\n", result.decoder_description);  // the choice, logged once
    chain.push_back(decode_stage.get());
    decode_position = static_cast<int>(chain.size());
    positions.decode = decode_position;
  }
  const bool uses_depth = options.estimate && result.config.frontend.matching_guess == StereoGuess::kAverageDepth;
  result.frontend_camera_threads = frontendCameraThreads(options);
  frontend = std::make_unique<FrontendStage>(
      result.config.frontend, rig, FrontendCapacities{.max_points = options.max_points}, uses_depth ? &hints : nullptr,
      !options.overlay_file.empty() || needs.left_traces, result.frontend_camera_threads);
  chain.push_back(frontend.get());
  const int frontend_position = static_cast<int>(chain.size());
  positions.frontend = frontend_position;
  int backend_position = -1;
  if (options.estimate) {
    backend =
        std::make_unique<BackendStage>(result.config.backend, rig, uses_depth ? &hints : nullptr, needs.landmarks);
    chain.push_back(backend.get());
    backend_position = static_cast<int>(chain.size());
    positions.backend = backend_position;
  }

  const int max_landmarks = backend && needs.landmarks ? backend->landmarkCapacity() : 0;
  // Where the write stage will sit, for the sinks that read the stages' timing.
  StagePositions sink_positions = positions;
  sink_positions.write = static_cast<int>(chain.size()) + 1;
  const Trajectory* ground_truth_poses = ground_truth ? &*ground_truth : nullptr;
  // The recording first among the outputs: a file that cannot be created leaves no other behind.
  if (!options.mcap.file.empty()) {
    recording = std::make_unique<McapSink>(McapSinkOptions{.file = options.mcap.file,
                                                           .width = info.width,
                                                           .height = info.height,
                                                           .max_points = options.max_points,
                                                           .max_landmarks = max_landmarks,
                                                           .stages = sink_positions,
                                                           .ground_truth = ground_truth_poses,
                                                           .image_rate_hz = options.mcap.image_rate_hz});
  }

  const auto expected = static_cast<std::size_t>(std::max<std::int64_t>(info.expected_frames, 0));
  // Live input has no known length: keep an hour of rows at 30 Hz in memory and count the rest.
  const std::size_t capacity = expected > 0 ? expected : 30 * 3600;
  const std::size_t statistics_rows =
      options.statistics_rows >= 0 ? static_cast<std::size_t>(options.statistics_rows) : capacity;
  std::vector<FrameSink*> sinks;
  if (options.estimate) {
    trajectory = std::make_unique<TrajectorySink>(
        options.trajectory_file.empty() ? std::nullopt : std::optional<std::filesystem::path>(options.trajectory_file),
        options.trajectory_format, options.keep_trajectory ? capacity : 0, rig.cameras[0].T_body_cam);
    sinks.push_back(trajectory.get());
  }
  statistics = std::make_unique<StatisticsSink>(statistics_rows, decode_position, frontend_position, backend_position);
  sinks.push_back(statistics.get());
  if (!options.overlay_file.empty()) {
    encode::silenceCodecLogs();  // libavcodec prints x264's settings at info level otherwise
    const int fps = info.nominal_rate_hz > 0.0 ? static_cast<int>(std::lround(info.nominal_rate_hz)) : 20;
    overlay = std::make_unique<OverlaySink>(options.overlay_file, fps, info.width, info.height);
    sinks.push_back(overlay.get());
  }
  if (options.progress) {
    const FrontendConfig& tracker = result.config.frontend;
    progress =
        std::make_unique<ProgressSink>(info.expected_frames, options.estimate, frontend_position, backend_position,
                                       !appliesTo(tracker.retry_previous_flow, result.has_motion),
                                       tracker.stereoRoundTripDist2() < kHintedStereoRoundTripDist2);
    sinks.push_back(progress.get());
  }
  if (view_server != nullptr) {
    view = std::make_unique<ViewSink>(*view_server, ViewSinkOptions{.width = info.width,
                                                                    .height = info.height,
                                                                    .max_points = options.max_points,
                                                                    .max_landmarks = max_landmarks,
                                                                    .stages = sink_positions,
                                                                    .ground_truth = ground_truth_poses});
    view->start();
    sinks.push_back(view.get());
  }
  if (recording) {
    recording->start();
    sinks.push_back(recording.get());
  }
  if (options.ros2) {
    if (!options.estimate) throw InputError("ROS 2 odometry needs poses: a tracking-only run estimates none");
    ros2 = std::make_unique<Ros2Sink>(*options.ros2);
    ros2->start();
    sinks.push_back(ros2.get());
  }
  sinks.insert(sinks.end(), options.extra_sinks.begin(), options.extra_sinks.end());
  sink = std::make_unique<SinkStage>(sinks);
  chain.push_back(sink.get());
  positions.write = static_cast<int>(chain.size());
  for (FrameSink* extra : options.extra_sinks) extra->begin(positions);

  PipelineOptions pipeline_options = options.pipeline_options;
  pipeline_options.live_policy = options.pipeline_options.live_policy || options.realtime || info.live;
  pipeline_options.slot_shape = {info.width, info.height, options.max_points, max_landmarks};
  pipeline_options.stop_requested = [this, requested = stopRequest(options)] {
    return stop.load(std::memory_order_relaxed) || requested();
  };
  pipeline = std::make_unique<Pipeline>(*source_stage, chain, pipeline_options);
}

void VoSession::run() {
  Impl& d = *impl_;
  if (d.ran) throw std::logic_error("VoSession::run: a session runs once");
  d.ran = true;
  d.result.started = true;
  d.result.pipeline_report = d.pipeline->run();
  d.collect();
}

void VoSession::requestStop() {
  impl_->stop.store(true, std::memory_order_relaxed);
  impl_->source_stage->interrupt();
}

bool VoSession::failed() const { return impl_->pipeline->failed(); }

const StagePositions& VoSession::positions() const { return impl_->positions; }

const VocaConfig& VoSession::config() const { return impl_->result.config; }

const std::string& VoSession::decoderDescription() const { return impl_->result.decoder_description; }

void VoSession::Impl::collect() {
  const RunReport& report = result.pipeline_report;
  if (report.stopped) result.stop_signal = platform::stopSignal();
  result.source = source.counters();
  result.frames = statistics->frames();
  result.frontend = statistics->frontend();
  result.backend = statistics->backend();
  result.rows = statistics->rows();
  if (trajectory) result.trajectory = trajectory->trajectory();
  for (const std::string& warning : report.warnings) result.warnings.push_back(warning);
  if (recording) {
    recording->finish();  // done by the sink stage already, unless the run failed before it
    if (!recording->failure().empty()) result.warnings.push_back(recording->failure());
    if (recording->dropped() > 0 || recording->imagesSkipped() > 0) {
      result.warnings.push_back(fmt::format(
          "MCAP recording {}: the recorder fell behind: {} frames not recorded, {} recorded without their image",
          options.mcap.file.string(), recording->dropped(), recording->imagesSkipped()));
    }
  }
  if (ros2) {
    ros2->finish();  // done by the sink stage already, unless the run failed before it
    result.ros2_summary = ros2->summary();
    const Ros2Sink::Counters published = ros2->counters();
    if (published.dropped > 0) {
      result.warnings.push_back(
          fmt::format("ROS 2: {} odometry messages dropped: the publisher thread fell behind (a slow network or "
                      "subscriber)",
                      published.dropped));
    }
    if (published.failed > 0) {
      result.warnings.push_back(
          fmt::format("ROS 2: {} odometry messages not published: {}", published.failed, ros2->firstError()));
    }
  }
  if (options.estimate && !report.stopped && !report.error && result.frames > 0 && result.backend.keyframes == 0 &&
      result.backend.lost >= result.frames) {
    result.failure = noEstimateReason(result, options.max_points);
  }
  const std::string ground_truth_name = std::exchange(result.ground_truth, std::string());
  if (options.estimate && options.keep_trajectory && ground_truth && !result.trajectory.poses.empty()) {
    result.ground_truth = ground_truth_name;
    EvalOptions eval_options;
    eval_options.expected_frames = static_cast<std::size_t>(std::max<std::int64_t>(source.info().expected_frames, 0));
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
}

VoRunResult VoSession::takeResult() { return std::move(impl_->result); }

}  // namespace voca::pipeline
