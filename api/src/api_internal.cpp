#include "api/src/api_internal.h"

#include <fmt/core.h>

#include <algorithm>

#include "drivers/ros2/ros2_names.h"
#include "formats/calib/calibration_io.h"
#include "formats/trajectory/trajectory_io.h"
#include "pipeline/runtime/chrome_trace.h"
#include "pipeline/vo/run_settings.h"
#include "pipeline/vo/run_summary.h"
#include "platform/realtime/clock.h"
#include "voca/frontend/frontend.h"

namespace voca_rt::detail {

namespace pl = voca::pipeline;

namespace {

voca::ros2::OdometryPublisherOptions ros2Options(const Ros2Output& output) {
  voca::ros2::OdometryPublisherOptions ros2;
  ros2.topic = voca::ros2::fullyQualifiedTopicName(output.topic, "--ros2-topic");
  voca::ros2::checkFrameId(output.odom_frame, "--ros2-odom-frame");
  voca::ros2::checkFrameId(output.base_frame, "--ros2-base-frame");
  if (output.odom_frame == output.base_frame) {
    throw voca::InputError(fmt::format(
        "--ros2-odom-frame and --ros2-base-frame: both are \"{}\"; a transform needs two frames", output.odom_frame));
  }
  ros2.odom_frame = output.odom_frame;
  ros2.base_frame = output.base_frame;
  if (output.domain_id < 0) {
    ros2.domain_id = voca::ros2::domainIdFromEnvironment();
  } else if (output.domain_id > static_cast<int>(voca::ros2::kMaxDomainId)) {
    throw voca::InputError(
        fmt::format("ROS 2 domain {}: expected 0 to {}", output.domain_id, voca::ros2::kMaxDomainId));
  } else {
    ros2.domain_id = static_cast<std::uint32_t>(output.domain_id);
  }
  return ros2;
}

}  // namespace

pl::VoRunOptions runOptions(const Options& options, bool realtime, double speed) {
  pl::VoRunOptions run;
  if (!options.config.empty()) run.config = options.config;
  if (!options.mode.empty()) run.mode = voca::requirePriorMode(options.mode, "--mode");
  run.bridge_iframes = options.bridge_iframes;
  if (options.max_points < 1 || options.max_points > voca::FrontendCapacities::kMaxPointsBound) {
    throw voca::InputError(fmt::format("--max-points {}: expected 1 to {} points per camera", options.max_points,
                                       voca::FrontendCapacities::kMaxPointsBound));
  }
  run.max_points = options.max_points;
  run.estimate = options.estimate;
  pl::RunSettings settings;
  settings.threads = options.threads;
  settings.frontend_threads = options.frontend_threads;
  settings.pins = options.pins;
  settings.scheduling = options.scheduling;
  settings.priority = options.priority;
  settings.lock_memory = options.lock_memory;
  settings.realtime = realtime;
  settings.speed = speed;
  settings.strict = options.strict;
  settings.decoder = options.decoder;
  settings.skip_deblock = options.skip_deblock;
  settings.trace_file = options.trace_file;
  settings.statistics_file = options.statistics_file;
  pl::applyRunSettings(settings, run);
  const auto format = voca::parseTrajectoryFormat(options.trajectory_format);
  if (!format) {
    throw voca::InputError(
        fmt::format("--format: expected tum, euroc or kitti, got \"{}\"", options.trajectory_format));
  }
  run.trajectory_file = options.trajectory_file;
  run.trajectory_format = *format;
  run.progress = options.progress;
  if (options.ros2) run.ros2 = ros2Options(*options.ros2);
  run.view.address = options.view_address;
  run.view.image_rate_hz = options.view_image_rate_hz;
  run.mcap.file = options.mcap_file;
  run.mcap.image_rate_hz = options.view_image_rate_hz;
  // A library answers its caller, not the process's signals: without a stop request of the caller's
  // only finish() and the destructor stop a run.
  run.pipeline_options.stop_requested = options.stop_requested ? options.stop_requested : [] { return false; };
  return run;
}

voca::StereoRig stereoRig(const Calibration& calibration, const std::string& source) {
  std::vector<voca::CameraValues> cameras;
  for (const CameraModel& model : calibration.cameras) {
    voca::CameraValues values;
    values.model = model.type;
    values.params = model.intrinsics;
    values.width = model.width;
    values.height = model.height;
    values.T_body_cam = Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(model.T_body_cam.data());
    cameras.push_back(std::move(values));
  }
  return voca::stereoRigFromValues(cameras, source);
}

voca::StereoRig stereoRig(const Options& options) {
  if (!options.calibration.cameras.empty()) return stereoRig(options.calibration, "the calibration value");
  if (options.calibration_file.empty()) {
    throw voca::InputError("no calibration: set Options::calibration_file (or Options::calibration) to the cameras'");
  }
  return voca::loadCalibration(options.calibration_file);
}

Calibration calibration(const voca::StereoRig& rig) {
  Calibration out;
  for (const voca::CameraCalibration& camera : rig.cameras) {
    CameraModel model;
    model.type = std::string(camera.camera.modelName());
    model.intrinsics = camera.camera.params();
    model.width = camera.width;
    model.height = camera.height;
    Eigen::Map<Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(model.T_body_cam.data()) = camera.T_body_cam.matrix();
    out.cameras.push_back(std::move(model));
  }
  return out;
}

namespace {

double stageMs(const pl::FrameSlot& slot, int position) {
  if (position < 0) return 0.0;
  return slot.timing[static_cast<std::size_t>(position)].serviceMs();
}

TrackingState state(voca::TrackingState state) {
  switch (state) {
    case voca::TrackingState::kTracking:
      return TrackingState::kOk;
    case voca::TrackingState::kReset:
      return TrackingState::kReset;
    case voca::TrackingState::kLost:
      break;
  }
  return TrackingState::kLost;
}

}  // namespace

void toPose(const pl::FrameSlot& slot, const pl::StagePositions& positions, std::int64_t now_ns, Pose& pose) {
  const voca::PoseEstimate& estimate = slot.pose;
  pose.t_ns = estimate.t_ns;
  pose.frame_index = estimate.frame_index;
  const Eigen::Vector3d p = estimate.T_world_body.translation();
  const Eigen::Quaterniond q = estimate.T_world_body.so3().unitQuaternion();
  pose.position = {p.x(), p.y(), p.z()};
  pose.orientation = {q.x(), q.y(), q.z(), q.w()};
  pose.state = state(estimate.state);
  pose.keyframe = estimate.keyframe;
  pose.landmarks = estimate.num_landmarks;
  pose.inliers = estimate.num_inliers;
  pose.latency.encode_ms = stageMs(slot, positions.encode);
  pose.latency.decode_ms = stageMs(slot, positions.decode);
  pose.latency.frontend_ms = stageMs(slot, positions.frontend);
  pose.latency.backend_ms = stageMs(slot, positions.backend);
  pose.latency.end_to_end_ms = static_cast<double>(now_ns - slot.arrival_ns) * 1e-6;
}

Summary summary(const pl::VoRunResult& result, bool estimate) {
  Summary s;
  const pl::RunReport& report = result.pipeline_report;
  s.input = result.description;
  s.config = result.config_name;
  s.started = result.started;
  s.frames = result.frames;
  s.keyframes = result.backend.keyframes;
  s.resets = result.backend.resets;
  s.lost = result.backend.lost;
  s.dropped = report.dropped;
  s.damaged = report.damaged;
  s.frames_lost = result.source.frames_lost;
  s.unpaired = result.source.unpaired;
  s.threads = result.started ? report.threads + result.frontend_camera_threads - 1 : 0;
  s.wall_s = report.wall_s;
  s.frames_per_second = report.wall_s > 0.0 ? static_cast<double>(report.completed) / report.wall_s : 0.0;
  const pl::LatencyHistogram& e = report.end_to_end;
  s.end_to_end_ms = {static_cast<double>(e.quantileNs(0.5)) * 1e-6, static_cast<double>(e.quantileNs(0.9)) * 1e-6,
                     static_cast<double>(e.quantileNs(0.99)) * 1e-6, static_cast<double>(e.maxNs()) * 1e-6};
  if (result.eval) {
    s.ate_rmse_m = result.eval->ate.stats.rmse;
    if (result.eval->rte) s.rte_rmse_m = result.eval->rte->stats.rmse;
  }
  s.stop_signal = result.stop_signal;
  s.stopped = report.stopped;
  if (report.error) {
    const pl::StageError& error = *report.error;
    s.error = fmt::format("{} stage failed{}: {}", error.stage,
                          error.frame_index >= 0 ? fmt::format(" at frame {}", error.frame_index) : std::string(),
                          error.message);
  }
  s.failure = result.failure;
  s.warnings = result.warnings;
  s.ros2_summary = result.ros2_summary;
  s.report = estimate ? pl::formatRunSummary(result) : pl::formatTrackSummary(result, result.config.frontend);
  if (result.started) s.latency_report = pl::formatLatencyReport(report);
  return s;
}

PoseSink::PoseSink(PoseCallback callback, std::size_t poll_capacity)
    : callback_(std::move(callback)), ring_(poll_capacity) {}

void PoseSink::lock() {
  while (busy_.test_and_set(std::memory_order_acquire)) {
  }
}

void PoseSink::consume(const pl::FrameSlot& slot) {
  toPose(slot, positions_, voca::platform::monotonicNs(), current_);
  if (callback_) callback_(current_);
  if (ring_.empty()) return;
  lock();
  const std::size_t capacity = ring_.size();
  if (size_ == capacity) {
    head_ = (head_ + 1) % capacity;  // the oldest unpolled pose gives way
    --size_;
  }
  ring_[(head_ + size_) % capacity] = current_;
  ++size_;
  unlock();
}

bool PoseSink::poll(Pose& pose) {
  if (ring_.empty()) return false;
  lock();
  const bool have = size_ > 0;
  if (have) {
    pose = ring_[head_];
    head_ = (head_ + 1) % ring_.size();
    --size_;
  }
  unlock();
  return have;
}

}  // namespace voca_rt::detail
