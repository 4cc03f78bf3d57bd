#pragma once
// What a visual-odometry run is asked to do (VoRunOptions) and what it gives back (VoRunResult): the
// types every part of the runner shares (input selection, the session, summaries, statistics file).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "drivers/decode/decoder_kind.h"
#include "drivers/encode/live_encoder.h"
#include "drivers/ros2/odometry_publisher.h"
#include "drivers/source/stereo_source.h"
#include "formats/config/config.h"
#include "formats/trajectory/trajectory_io.h"
#include "pipeline/runtime/runner.h"
#include "pipeline/sinks/sink_stage.h"
#include "pipeline/sinks/statistics_sink.h"
#include "voca/calib/calibration.h"
#include "voca/eval/evaluate.h"

namespace voca::view {
class FoxgloveServer;
}  // namespace voca::view

namespace voca::pipeline {

// The live view (`--view`, pipeline/sinks/view_sink.h): the run's telemetry to Foxglove, Lichtblick
// and the built-in page.
struct ViewRunOptions {
  // A server the caller started (startViewServer), published to for this run; `voca demo` and the
  // library keep one for the run's whole life. Else, when address ("[host:]port") is set, the session
  // starts its own before anything is written (an address that cannot be bound is an InputError).
  view::FoxgloveServer* server = nullptr;
  std::string address;
  double image_rate_hz = 10.0;  // for a server the session starts
};

// The recording (`--mcap`, pipeline/sinks/mcap_sink.h): the live view's channels written to an MCAP
// file as the run goes. A write error stops the recording, not the run (a warning says so).
struct McapRunOptions {
  std::filesystem::path file;   // empty: no recording
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
  // Raw input: each camera encoded on the fly by the live encoder (hardware where there is one, else
  // x264; causal, one packet per frame) and decoded again with its motion vectors, as frames from a
  // camera that compresses on the robot would be. nullopt: the raw images are tracked.
  std::optional<encode::LiveEncoderSettings> live_encode;
  // Stream URLs: how long to wait for the stream to begin, and the silence that ends it.
  double stream_start_timeout_s = 30.0;
  double stream_timeout_s = 3.0;

  // Outputs (empty paths: not written).
  std::filesystem::path trajectory_file;
  TrajectoryFormat trajectory_format = TrajectoryFormat::kTum;
  std::filesystem::path statistics_file;  // JSON: totals, per-stage latency, drops, per-frame rows
  std::filesystem::path overlay_file;     // .mp4 of the left camera with the tracks drawn
  bool keep_trajectory = true;            // in memory too (for evaluation and callers)
  // Per-frame statistics rows kept in memory (VoRunResult::rows); -1: the expected frame count, an
  // hour at 30 Hz for live input. A soak test keeps none: its memory must not grow with its length.
  std::int64_t statistics_rows = -1;
  std::vector<FrameSink*> extra_sinks;  // also given every finished frame, after the built-in sinks
  // ROS 2 (--ros2): every tracked pose as nav_msgs/Odometry and the odom -> base transform on /tf over
  // DDS, written by a thread of its own (pipeline/sinks/ros2_sink.h). Needs estimate.
  std::optional<ros2::OdometryPublisherOptions> ros2;
  ViewRunOptions view;  // live view; off unless a server or an address is given
  McapRunOptions mcap;  // recording; off unless a file is given

  // How to run.
  PipelineOptions pipeline_options;  // threads, pins, scheduling, memory locking, trace file, stop request
  bool realtime = false;             // pace the source at the recording's timestamps; drop instead of waiting
  double speed = 1.0;                // realtime playback speed
  bool strict = false;               // stop at the first damaged frame instead of skipping it
  bool progress = true;              // progress lines on stderr
  // Threads the frontend tracks the two cameras on: 1, or 2 (a helper thread tracks the right camera
  // and the left camera's last points, about half of all points; the same results). 0: 2 when the
  // pins name the helper ("frontend.helper"), or when the stages have threads of their own
  // (pipeline_options.threads != 1), no stage is pinned, and the process may use two cores or more;
  // else 1.
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
  RunReport pipeline_report;        // per-stage latency, queues, drops, damaged frames, error
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
  std::string ros2_summary;  // what --ros2 published, one line (Ros2Sink::summary); empty without it
  // Why the run estimated nothing (every frame lost), with a hint at the cause; empty otherwise.
  // Commands report it as an error and exit non-zero: the trajectory holds no estimate.
  std::string failure;
};

// The configuration a run uses and the name reports give it: the file or shipped name asked for,
// else the shipped config for the input (configs/kitti_vo.json for a KITTI folder, whose street scenes
// need its stereo guess; configs/euroc_vo.json for everything else). The shipped file, not the
// struct defaults: where the two differ, the shipped file is the measured choice.
struct RunConfig {
  VocaConfig config;
  std::string name;
};
RunConfig resolveRunConfig(const std::optional<std::filesystem::path>& config, bool kitti_input = false);

// The stop request a run polls between frames: the caller's, else a SIGINT, SIGTERM or SIGHUP seen by
// the process's stop handlers (platform/realtime/stop_signal.h; never true where none are installed).
std::function<bool()> stopRequest(const VoRunOptions& options);

}  // namespace voca::pipeline
