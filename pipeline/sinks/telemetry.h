#pragma once
// A run's telemetry: the channels a live viewer subscribes to (Foxglove WebSocket) and a recorder
// writes (MCAP), and the two steps that make their messages. captureTelemetry() runs on the pipeline's
// write thread and only copies what the wanted channels need from a finished frame into a snapshot
// reserved beforehand; a TelemetryEncoder on the consumer's own thread turns each snapshot into
// (channel, time, JSON payload) messages: the left image with its tracks drawn as JPEG, the codec's
// motion vectors, the pose, the transform, the path so far (and the ground truth's, aligned to the
// estimate's world frame at the first frame), the window's landmarks and the frame's statistics.
// Neither step allocates in steady state.

#include <Eigen/Core>
#include <bitset>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/encode/jpeg_encoder.h"
#include "formats/foxglove/foxglove_schemas.h"
#include "pipeline/runtime/frame_slot.h"
#include "pipeline/sinks/sink_stage.h"
#include "voca/trajectory/trajectory.h"

namespace voca::pipeline {

enum class TelemetryChannel : std::uint8_t {
  kImage,            // foxglove.CompressedImage: the left camera with its tracks drawn (JPEG)
  kMotionVectors,    // foxglove.ImageAnnotations: the left camera's motion vectors
  kPose,             // foxglove.PoseInFrame: the body's pose in the odometry frame
  kTransform,        // foxglove.FrameTransform: odometry frame -> body
  kPath,             // foxglove.PosesInFrame: the estimated path so far
  kGroundTruthPath,  // foxglove.PosesInFrame: the ground truth's path so far (inputs that have one)
  kLandmarks,        // foxglove.PointCloud: the estimator's window landmarks
  kFrameStats,       // voca.FrameStats: latency per stage, tracks, window, skipped frames
};
inline constexpr int kTelemetryChannelCount = 8;
using TelemetryChannels = std::bitset<kTelemetryChannelCount>;
inline std::size_t channelBit(TelemetryChannel channel) { return static_cast<std::size_t>(channel); }

struct TelemetryChannelInfo {
  TelemetryChannel channel;
  std::string_view topic;
  foxglove::SchemaId schema;
};
// Every channel, in TelemetryChannel order. Messages are JSON (foxglove::kJsonEncoding) described by
// the schema's JSON Schema (foxglove::kJsonSchemaEncoding).
std::span<const TelemetryChannelInfo> telemetryChannels();

// Frame names, as ROS names them: poses, path and landmarks are in the odometry frame ("odom", the
// body pose of the first frame), the transform goes odom -> base_link (the calibration's body frame).
inline constexpr std::string_view kOdometryFrame = "odom";
inline constexpr std::string_view kBodyFrame = "base_link";
inline constexpr std::string_view kLeftCameraFrame = "cam0";

// Camera images per second for a viewer or a recording (the image channel is the expensive one).
inline constexpr double kTelemetryDefaultImageRateHz = 10.0;
inline constexpr double kTelemetryMaxImageRateHz = 30.0;

// What one finished frame gives the channels, copied out of the slot.
struct TelemetrySnapshot {
  TelemetryChannels channels;  // the channels to publish for this frame
  std::int64_t t_ns = 0;
  std::int64_t frame_index = 0;
  bool has_pose = false;  // the run estimates poses (not `voca track`)
  SE3d T_world_body;
  TrackingState state = TrackingState::kLost;
  bool keyframe = false;
  int keyframes = 0, landmarks_alive = 0, inliers = 0;
  int tracks_left = 0, tracks_right = 0;
  double decode_ms = 0.0, frontend_ms = 0.0, backend_ms = 0.0, end_to_end_ms = 0.0;
  std::int64_t dropped = 0, damaged = 0;
  std::int64_t view_dropped = 0;  // snapshots the consumer lost so far; set by it
  // kImage:
  GrayImage left;
  std::vector<PointTrace> traces;
  std::vector<KeypointObservation> observations;
  // kMotionVectors:
  std::vector<MotionBlock> motion_blocks;
  // kLandmarks:
  std::vector<Eigen::Vector3f> landmarks;

  // For frames up to width x height with max_points points per camera and max_landmarks landmarks.
  void reserve(int width, int height, int max_points, int max_landmarks);
};

// Copies the frame's scalars and what the wanted channels need into out (within its reserved
// capacity: never allocates). out.channels = wanted.
void captureTelemetry(const FrameSlot& slot, const StagePositions& stages, TelemetryChannels wanted,
                      TelemetrySnapshot& out);

// A path of bounded length: every pose while it fits, then every 2nd, 4th, ... (the stride doubles
// each time it fills up), always ending at the newest pose. Fixed memory.
class DecimatedPath {
 public:
  explicit DecimatedPath(std::size_t capacity);
  void add(const SE3d& pose);
  // Oldest first; the newest pose last.
  std::span<const SE3d> poses() const { return poses_; }
  std::size_t stride() const { return stride_; }

 private:
  std::size_t capacity_;
  std::vector<SE3d> poses_;  // kept poses (index multiples of stride_), then the newest if not among them
  bool newest_appended_ = false;
  std::size_t added_ = 0;
  std::size_t stride_ = 1;
};

struct TelemetryOptions {
  int width = 0, height = 0;  // of the frames
  int max_points = 0;
  int max_landmarks = 0;
  int jpeg_quality = 5;                      // libavcodec quantiser scale, 2 (best) to 31
  std::size_t max_path_poses = 4096;         // per path message (DecimatedPath)
  const Trajectory* ground_truth = nullptr;  // copied; body poses in the ground truth's world frame
};

class TelemetryEncoder {
 public:
  // payload is valid during the call only.
  using Publish = std::function<void(TelemetryChannel channel, std::int64_t t_ns, std::string_view payload)>;

  explicit TelemetryEncoder(const TelemetryOptions& options);
  ~TelemetryEncoder();

  // Give it every frame of the run, in order, as a snapshot or (a frame nobody wants messages of) as
  // its pose alone: the paths take each pose, whether or not a snapshot asks for them to be published.
  // Publishes the snapshot's channels.
  void encode(const TelemetrySnapshot& snapshot, const Publish& publish);
  void addPose(std::int64_t t_ns, const SE3d& T_world_body);

  bool hasGroundTruth() const { return !ground_truth_.poses.empty(); }

 private:
  Trajectory ground_truth_;
  bool aligned_ = false;
  SE3d T_odom_gtworld_;  // the ground truth's world in the odometry frame, fixed at the first frame
  DecimatedPath path_, ground_truth_path_;
  RgbImage overlay_;
  std::unique_ptr<encode::JpegEncoder> jpeg_;
  std::string json_;
};

}  // namespace voca::pipeline
