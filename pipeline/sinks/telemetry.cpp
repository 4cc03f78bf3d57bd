#include "pipeline/sinks/telemetry.h"

#include <algorithm>
#include <array>
#include <cstring>

#include "formats/foxglove/foxglove_json.h"
#include "pipeline/sinks/overlay_sink.h"

namespace voca::pipeline {

namespace {

using foxglove::SchemaId;

constexpr std::array<TelemetryChannelInfo, kTelemetryChannelCount> kChannels = {{
    {TelemetryChannel::kImage, "/voca/camera/left/compressed", SchemaId::kCompressedImage},
    {TelemetryChannel::kMotionVectors, "/voca/camera/left/motion_vectors", SchemaId::kImageAnnotations},
    {TelemetryChannel::kPose, "/voca/pose", SchemaId::kPoseInFrame},
    {TelemetryChannel::kTransform, "/tf", SchemaId::kFrameTransform},
    {TelemetryChannel::kPath, "/voca/path", SchemaId::kPosesInFrame},
    {TelemetryChannel::kGroundTruthPath, "/voca/ground_truth/path", SchemaId::kPosesInFrame},
    {TelemetryChannel::kLandmarks, "/voca/landmarks", SchemaId::kPointCloud},
    {TelemetryChannel::kFrameStats, "/voca/stats", SchemaId::kFrameStats},
}};

// Copies as much of src as dst's reserved capacity holds (dst never grows).
template <typename T>
void copyBounded(std::span<const T> src, std::vector<T>& dst) {
  const std::size_t n = std::min(src.size(), dst.capacity());
  dst.resize(n);
  std::copy_n(src.begin(), n, dst.begin());
}

double stageMs(const FrameSlot& slot, int stage) {
  if (stage < 0) return 0.0;
  return slot.timing[static_cast<std::size_t>(stage)].serviceMs();
}

// Blocks of a motion field: at most one per 4x4 cell of the picture.
std::size_t maxMotionBlocks(int width, int height) {
  return static_cast<std::size_t>((width + 3) / 4) * static_cast<std::size_t>((height + 3) / 4);
}

}  // namespace

std::span<const TelemetryChannelInfo> telemetryChannels() { return kChannels; }

void TelemetrySnapshot::reserve(int width, int height, int max_points, int max_landmarks) {
  left.reserve(width, height);
  traces.reserve(static_cast<std::size_t>(max_points));
  observations.reserve(static_cast<std::size_t>(max_points));
  motion_blocks.reserve(maxMotionBlocks(width, height));
  landmarks.reserve(static_cast<std::size_t>(max_landmarks));
}

void captureTelemetry(const FrameSlot& slot, const StagePositions& stages, TelemetryChannels wanted,
                      TelemetrySnapshot& out) {
  out.channels = wanted;
  out.t_ns = slot.frame.t_ns;
  out.frame_index = slot.frame.frame_index;
  out.has_pose = stages.backend >= 0;
  const PoseEstimate& pose = slot.pose;
  out.T_world_body = pose.T_world_body;
  out.state = pose.state;
  out.keyframe = pose.keyframe;
  out.keyframes = pose.num_keyframes;
  out.landmarks_alive = pose.num_landmarks;
  out.inliers = pose.num_inliers;
  out.tracks_left = static_cast<int>(slot.tracked.observations[0].size());
  out.tracks_right = static_cast<int>(slot.tracked.observations[1].size());
  out.decode_ms = stageMs(slot, stages.decode);
  out.frontend_ms = stageMs(slot, stages.frontend);
  out.backend_ms = stageMs(slot, stages.backend);
  // Arrival to the frame reaching the sinks: what a user of the pose waits.
  out.end_to_end_ms =
      stages.write >= 0
          ? platform::nsToMs(slot.timing[static_cast<std::size_t>(stages.write)].start_ns - slot.arrival_ns)
          : 0.0;
  out.dropped = slot.dropped_so_far;
  out.damaged = slot.damaged_so_far;
  if (wanted.test(channelBit(TelemetryChannel::kImage))) {
    const GrayImage& image = slot.frame.images[0];
    out.left.resize(image.width(), image.height());
    std::memcpy(out.left.data(), image.data(), image.pixelCount());
    copyBounded<PointTrace>(slot.left_traces, out.traces);
    copyBounded<KeypointObservation>(slot.tracked.observations[0], out.observations);
  }
  if (wanted.test(channelBit(TelemetryChannel::kMotionVectors))) {
    if (slot.frame.has_motion) {
      copyBounded<MotionBlock>(slot.frame.motion[0].blocks(), out.motion_blocks);
    } else {
      out.motion_blocks.clear();
    }
  }
  if (wanted.test(channelBit(TelemetryChannel::kLandmarks))) {
    copyBounded<Eigen::Vector3f>(slot.landmarks_world, out.landmarks);
  }
}

DecimatedPath::DecimatedPath(std::size_t capacity) : capacity_(std::max<std::size_t>(capacity, 2)) {
  poses_.reserve(capacity_ + 1);
}

void DecimatedPath::add(const SE3d& pose) {
  if (newest_appended_) {
    poses_.pop_back();
    newest_appended_ = false;
  }
  const std::size_t index = added_++;
  if (index % stride_ == 0 && poses_.size() == capacity_) {
    // Full: keep every other pose (indices multiples of twice the stride).
    std::size_t kept = 0;
    for (std::size_t i = 0; i < poses_.size(); i += 2) poses_[kept++] = poses_[i];
    poses_.resize(kept);
    stride_ *= 2;
  }
  poses_.push_back(pose);
  newest_appended_ = index % stride_ != 0;
}

TelemetryEncoder::TelemetryEncoder(const TelemetryOptions& options)
    : path_(options.max_path_poses), ground_truth_path_(options.max_path_poses) {
  if (options.ground_truth != nullptr) ground_truth_ = *options.ground_truth;
  overlay_.reserve(options.width, options.height);
  jpeg_ = std::make_unique<encode::JpegEncoder>(options.width, options.height, options.jpeg_quality);
  // The largest message: a JPEG is below the raw RGB size in practice (a larger one grows the buffer
  // once), a path its poses, a motion field one segment per 4x4 block.
  const std::size_t pixels = static_cast<std::size_t>(options.width) * static_cast<std::size_t>(options.height);
  json_.reserve(std::max({foxglove::compressedImageMaxBytes(pixels * 3),
                          foxglove::posesInFrameMaxBytes(options.max_path_poses + 1),
                          foxglove::motionVectorAnnotationsMaxBytes(maxMotionBlocks(options.width, options.height)),
                          foxglove::pointCloudMaxBytes(static_cast<std::size_t>(options.max_landmarks)),
                          foxglove::kSmallMessageMaxBytes}));
}

TelemetryEncoder::~TelemetryEncoder() = default;

void TelemetryEncoder::addPose(std::int64_t t_ns, const SE3d& T_world_body) {
  path_.add(T_world_body);
  if (const std::optional<SE3d> T_gtworld_body = interpolatePose(ground_truth_, t_ns)) {
    if (!aligned_) {
      T_odom_gtworld_ = T_world_body * T_gtworld_body->inverse();
      aligned_ = true;
    }
    ground_truth_path_.add(T_odom_gtworld_ * *T_gtworld_body);
  }
}

void TelemetryEncoder::encode(const TelemetrySnapshot& s, const Publish& publish) {
  const auto wants = [&](TelemetryChannel channel) { return s.channels.test(channelBit(channel)); };
  const auto send = [&](TelemetryChannel channel) { publish(channel, s.t_ns, json_); };
  const std::int64_t t = s.t_ns;
  if (s.has_pose) addPose(t, s.T_world_body);
  if (wants(TelemetryChannel::kImage) && !s.left.empty()) {
    renderTrackOverlay(s.left, s.traces, s.observations, overlay_);
    foxglove::writeCompressedImage(t, kLeftCameraFrame, "jpeg", jpeg_->encode(overlay_.view()), json_);
    send(TelemetryChannel::kImage);
  }
  if (wants(TelemetryChannel::kMotionVectors)) {
    foxglove::writeMotionVectorAnnotations(t, s.motion_blocks, json_);
    send(TelemetryChannel::kMotionVectors);
  }
  if (s.has_pose && wants(TelemetryChannel::kPose)) {
    foxglove::writePoseInFrame(t, kOdometryFrame, s.T_world_body, json_);
    send(TelemetryChannel::kPose);
  }
  if (s.has_pose && wants(TelemetryChannel::kTransform)) {
    foxglove::writeFrameTransform(t, kOdometryFrame, kBodyFrame, s.T_world_body, json_);
    send(TelemetryChannel::kTransform);
  }
  if (s.has_pose && wants(TelemetryChannel::kPath)) {
    foxglove::writePosesInFrame(t, kOdometryFrame, path_.poses(), json_);
    send(TelemetryChannel::kPath);
  }
  if (aligned_ && wants(TelemetryChannel::kGroundTruthPath)) {
    foxglove::writePosesInFrame(t, kOdometryFrame, ground_truth_path_.poses(), json_);
    send(TelemetryChannel::kGroundTruthPath);
  }
  if (s.has_pose && wants(TelemetryChannel::kLandmarks)) {
    foxglove::writePointCloud(t, kOdometryFrame, s.landmarks, json_);
    send(TelemetryChannel::kLandmarks);
  }
  if (wants(TelemetryChannel::kFrameStats)) {
    foxglove::FrameStats stats;
    stats.t_ns = t;
    stats.frame_index = s.frame_index;
    stats.state = s.has_pose ? trackingStateName(s.state) : std::string_view("tracking");
    stats.keyframe = s.keyframe;
    stats.decode_ms = s.decode_ms;
    stats.frontend_ms = s.frontend_ms;
    stats.backend_ms = s.backend_ms;
    stats.end_to_end_ms = s.end_to_end_ms;
    stats.tracks_left = s.tracks_left;
    stats.tracks_right = s.tracks_right;
    stats.landmarks = s.landmarks_alive;
    stats.keyframes = s.keyframes;
    stats.inliers = s.inliers;
    stats.dropped = s.dropped;
    stats.damaged = s.damaged;
    stats.view_dropped = s.view_dropped;
    foxglove::writeFrameStats(stats, json_);
    send(TelemetryChannel::kFrameStats);
  }
}

}  // namespace voca::pipeline
