#pragma once
// The one runner behind `voca run`, `voca track`, `voca demo` and `voca bench`: opens an input
// (a raw dataset, optionally encoded first the way the paper did, or a VOCA video folder), builds
// the staged pipeline (read -> [decode] -> frontend -> [backend] -> write), runs it and returns
// everything a caller prints or checks: trajectory, statistics, per-stage latency, drops, damaged
// frames, and ATE/RTE when the dataset has ground truth. Outputs stream while the run goes: a stopped
// or failed run leaves every pose estimated so far in the trajectory file.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivers/decode/decoder_kind.h"
#include "drivers/source/stereo_source.h"
#include "formats/config/config.h"
#include "formats/dataset/dataset.h"
#include "formats/trajectory/trajectory_io.h"
#include "pipeline/runtime/runner.h"
#include "pipeline/sinks/sink_stage.h"
#include "pipeline/sinks/statistics_sink.h"
#include "voca/eval/evaluate.h"

namespace voca::view {
class FoxgloveServer;
}  // namespace voca::view

namespace voca::pipeline {

// The live view (`--view`, pipeline/sinks/view_sink.h): the run's telemetry to Foxglove, Lichtblick
// and the built-in page.
struct ViewRunOptions {
  // A server the caller started (startViewServer), published to for this run; `voca demo` keeps one
  // for both of its runs. Else, when address ("[host:]port") is set, the run starts its own before
  // anything is written (an address that cannot be bound is an InputError) and closes it at the end.
  view::FoxgloveServer* server = nullptr;
  std::string address;
  double image_rate_hz = 10.0;  // for a server the run starts
};

// The recording (`--mcap`, pipeline/sinks/mcap_sink.h): the live view's channels written to an MCAP file
// as the run goes. A write error stops the recording, not the run (a warning says so).
struct McapRunOptions {
  std::filesystem::path file;  // empty: no recording
  double image_rate_hz = 10.0;  // camera images per second of the frames' time, 0 to 30
};

struct VoRunOptions {
  // Input: a dataset folder, or a stream URL (udp://127.0.0.1:5000) that `voca stream` sends to.
  std::filesystem::path input;
  std::optional<std::filesystem::path> calibration;
  std::optional<std::filesystem::path> config;        // file or shipped name; default: euroc (kitti for KITTI folders)
  std::optional<std::filesystem::path> ground_truth;  // overrides the dataset's own
  std::optional<PriorMode> mode;                      // overrides the config's frontend.prior_mode
  std::optional<bool> bridge_iframes;                 // overrides the config's frontend.bridge_iframes
  std::int64_t encode_bitrate_bps = 0;  // raw datasets: encode (two-pass x264, the paper's way) to a temp folder first
  int first_frame = 0;                  // track from this frame of the dataset (video: decoded from 0)
  int max_frames = 0;                   // 0 = all
  int max_points = 1000;                // frontend capacity per camera
  bool estimate = true;                 // false: frontend only (`voca track`)
  decode::DecoderKind decoder = decode::DecoderKind::kAuto;
  bool skip_deblock = false;  // software decoding without the loop filter (faster, pictures inexact)
  // Stream URLs: how long to wait for the stream to begin, and the silence that ends it.
  double stream_start_timeout_s = 30.0;
  double stream_timeout_s = 3.0;

  // Outputs (empty paths: not written).
  std::filesystem::path trajectory_file;
  TrajectoryFormat trajectory_format = TrajectoryFormat::kTum;
  std::filesystem::path statistics_file;  // JSON: totals, per-stage latency, drops, per-frame rows
  std::filesystem::path overlay_file;     // .mp4 of the left camera with the tracks drawn
  bool keep_trajectory = true;            // in memory too (for evaluation and callers)
  std::vector<FrameSink*> extra_sinks;    // also given every finished frame, after the built-in sinks
  ViewRunOptions view;                    // live view; off unless a server or an address is given
  McapRunOptions mcap;                    // recording; off unless a file is given

  // How to run.
  PipelineOptions pipeline;  // threads, pins, scheduling, memory locking, trace file, stop request
  bool realtime = false;     // pace the source at the recording's timestamps; drop instead of waiting
  double speed = 1.0;        // realtime playback speed
  bool strict = false;       // stop at the first damaged frame instead of skipping it
  bool progress = true;      // progress lines on stderr
  // Threads the frontend tracks the two cameras on: 1, or 2 (a helper thread tracks the right camera
  // and the left camera's last points, about half of all points; the same results). 0: 2 when the
  // pins name the helper ("frontend.helper"), or when the stages have threads of their own
  // (pipeline.threads != 1), no stage is pinned, and the process may use two cores or more; else 1.
  int frontend_camera_threads = 0;
};

struct VoRunResult {
  std::string description;          // the input, one line
  std::string decoder_description;  // "decoder: software", empty for raw images
  VocaConfig config;                // as used, after --mode
  std::string config_name;          // the file or shipped name the config came from
  StereoRig rig;                    // the calibration the run used
  bool has_motion = false;          // decoded video: motion vectors available
  int width = 0, height = 0;
  Trajectory trajectory;  // causal, body frame of the calibration (when keep_trajectory)
  std::int64_t frames = 0;
  FrontendTotals frontend;
  BackendTotals backend;
  std::vector<FrameRecord> rows;
  RunReport pipeline;               // per-stage latency, queues, drops, damaged frames, error
  int frontend_camera_threads = 1;  // as resolved from VoRunOptions::frontend_camera_threads
  std::string source_end;           // live input: why it ended ("no data for 3 s"), empty otherwise
  std::optional<EvalReport> eval;   // when there is ground truth and the evaluation succeeded
  std::string ground_truth;         // the file evaluated against (also when the evaluation failed: a warning says why)
  SourceCounters source;            // frames the live source lost or could not pair
  int stop_signal = 0;              // the signal that stopped the run early (0: none)
  // The frames began to flow: the run's outputs (trajectory, overlay, trace) were opened. False for
  // a run stopped while encoding or waiting for its stream; files at those paths are not its own.
  bool started = false;
  std::vector<std::string> warnings;
  // Why the run estimated nothing (every frame lost), with a hint at the cause; empty otherwise.
  // Commands report it as an error and exit non-zero: the trajectory holds no estimate.
  std::string failure;
};

// Encodes a raw dataset the way the paper did (two-pass libx264 at bitrate_bps, its x264 options) into
// a VOCA video folder at out, printing progress on stderr when asked. Returns false, having written
// nothing, when stop_requested() turns true first.
bool encodeForReplay(const std::filesystem::path& input, const std::filesystem::path& out, std::int64_t bitrate_bps,
                     const std::optional<std::filesystem::path>& calibration, bool progress,
                     const std::function<bool()>& stop_requested);

// The configuration a run uses and the name reports give it: the file or shipped name asked for,
// else the shipped config for the input (configs/kitti_vo.json for a KITTI folder, whose street scenes
// need its stereo guess; configs/euroc_vo.json for everything else). The shipped file, not the
// struct defaults: where the two differ, the shipped file is the measured choice.
struct RunConfig {
  VocaConfig config;
  std::string name;
};
RunConfig resolveRunConfig(const std::optional<std::filesystem::path>& config, bool kitti_input = false);

// Throws InputError for bad input found before the run starts (missing dataset, calibration or
// config; images that do not match the calibration). A stage failing during the run does not throw:
// the result carries it in pipeline.error, with everything estimated up to then.
VoRunResult runVisualOdometry(const VoRunOptions& options);

// The same on an input that is already open (a live camera, a network stream, a test's source):
// options' input, calibration, config, ground_truth, encode_bitrate_bps, first_frame and max_frames are not used;
// its mode and bridge_iframes still override the config's. Does not write options.statistics_file
// (the caller does, after adding its own warnings). ground_truth, when given, is evaluated against.
VoRunResult runVisualOdometryOn(StereoSource& source, const StereoRig& rig, const VocaConfig& config,
                                const VoRunOptions& options, const std::optional<Trajectory>& ground_truth = {},
                                const std::string& ground_truth_name = {});

// The end-of-run summary `voca run` prints (frames, keyframes, resets, ms per frame, ATE/RTE).
void printRunSummary(const VoRunResult& result, std::FILE* out);
// The frontend summary `voca track` prints (tracks, survival, rescues, guess distances, time).
void printTrackSummary(const VoRunResult& result, const FrontendConfig& config, std::FILE* out);

// Writes the statistics JSON (also done by runVisualOdometry when statistics_file is set).
void writeStatisticsJson(const VoRunResult& result, const std::filesystem::path& file);

}  // namespace voca::pipeline
