#include "pipeline/sinks/ros2_sink.h"

#include <fmt/core.h>

#include "platform/realtime/thread_control.h"

namespace voca::pipeline {

namespace {

// How often the idle publisher thread looks at the stop flag; messages wake it at once.
constexpr std::int64_t kPollUs = 20'000;

}  // namespace

Ros2Sink::Ros2Sink(const ros2::OdometryPublisherOptions& options, std::size_t ring_capacity)
    : publisher_(options), ring_(ring_capacity) {}

Ros2Sink::~Ros2Sink() {
  stopping_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
}

void Ros2Sink::start() {
  if (!thread_.joinable() && !finished_) thread_ = std::thread([this] { publishLoop(); });
}

void Ros2Sink::consume(const FrameSlot& slot) {
  const PoseEstimate& pose = slot.pose;
  if (pose.state != TrackingState::kTracking) {
    untracked_.fetch_add(1, std::memory_order_relaxed);
    // A reset frame anchors the new track: the next tracked frame moved from its pose.
    has_previous_ = pose.state == TrackingState::kReset;
    previous_t_ns_ = pose.t_ns;
    previous_T_world_body_ = pose.T_world_body;
    return;
  }
  ros2::OdometrySample sample;
  sample.t_ns = pose.t_ns;
  sample.T_odom_base = pose.T_world_body;
  // Frames the pipeline skipped in between only lengthen the interval: the twist is the mean over it.
  if (has_previous_ && pose.t_ns > previous_t_ns_) {
    const double dt_s = static_cast<double>(pose.t_ns - previous_t_ns_) * 1e-9;
    const Eigen::Matrix<double, 6, 1> twist = ros2::bodyTwist(previous_T_world_body_, pose.T_world_body, dt_s);
    sample.linear_velocity_mps = twist.head<3>();
    sample.angular_velocity_radps = twist.tail<3>();
    sample.twist_known = true;
  }
  has_previous_ = true;
  previous_t_ns_ = pose.t_ns;
  previous_T_world_body_ = pose.T_world_body;
  if (!ring_.try_enqueue(sample)) dropped_.fetch_add(1, std::memory_order_relaxed);
}

void Ros2Sink::publishLoop() {
  platform::nameCurrentThread("ros2-publish");
  ros2::OdometrySample sample;
  const auto publish = [&] {
    if (publisher_.publish(sample)) {
      published_.fetch_add(1, std::memory_order_relaxed);
    } else {
      if (failed_.fetch_add(1, std::memory_order_relaxed) == 0) first_error_ = publisher_.lastError();
    }
  };
  for (;;) {
    if (ring_.wait_dequeue_timed(sample, kPollUs)) {
      publish();
    } else if (stopping_.load(std::memory_order_acquire)) {
      break;
    }
  }
  // Everything consumed before the stop flag was set is in the ring now.
  while (ring_.try_dequeue(sample)) publish();
  acknowledged_ = publisher_.waitForAcknowledgments(kAcknowledgeTimeout);
}

void Ros2Sink::finish() {
  if (finished_) return;
  finished_ = true;
  stopping_.store(true, std::memory_order_release);
  if (thread_.joinable()) {
    thread_.join();
  } else {
    publishLoop();  // never started: publish what the ring holds from here
  }
}

Ros2Sink::Counters Ros2Sink::counters() const {
  return {published_.load(std::memory_order_relaxed), dropped_.load(std::memory_order_relaxed),
          untracked_.load(std::memory_order_relaxed), failed_.load(std::memory_order_relaxed)};
}

std::string Ros2Sink::summary() const {
  const Counters c = counters();
  std::string line = fmt::format("ros2: {} odometry messages on {} and transforms on rt/tf (ROS 2 domain {})",
                                 c.published, publisher_.odometryDdsTopic(), publisher_.domainId());
  if (c.untracked > 0) line += fmt::format(", {} lost or reset frames not published", c.untracked);
  if (c.dropped > 0) line += fmt::format(", {} dropped (the publisher fell behind)", c.dropped);
  if (c.failed > 0) line += fmt::format(", {} failed ({})", c.failed, first_error_);
  if (!acknowledged_) line += ", not all acknowledged by the subscribers before the end";
  return line;
}

}  // namespace voca::pipeline
