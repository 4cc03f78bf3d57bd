#pragma once
// Publishes the odometry into a ROS 2 graph as it is estimated (drivers/ros2): nav_msgs/Odometry on
// the topic and the odom -> base_link transform on /tf. consume() runs on the pipeline's write
// thread, so it only computes the twist and copies the message into a bounded lock-free ring; a
// publisher thread of its own does the DDS writes, so a slow subscriber or network never holds the
// pipeline up. A full ring drops the message and counts it.
//
// Which frames are published: tracked ones only. A lost frame repeats the last good pose, and a reset
// frame restarts tracking at it: neither is a fresh estimate of where the body is, and publishing the
// held pose would tell Nav2 or a filter that the robot stopped. So /odom and /tf pause while tracking
// is down (stale-data timeouts notice) and resume from the reset pose; the motion during the outage is
// missing from odom, which stays continuous (REP 105). The first tracked frame after a reset gets its
// twist from the reset frame's pose, the anchor of the new track; a frame with no tracked or reset
// predecessor (the first of a run, or one after lost frames) has no twist estimate.

#include <readerwriterqueue/readerwritercircularbuffer.h>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <thread>

#include "drivers/ros2/odometry_publisher.h"
#include "pipeline/sinks/sink_stage.h"

namespace voca::pipeline {

class Ros2Sink final : public FrameSink {
 public:
  struct Counters {
    std::int64_t published = 0;  // written to DDS (an Odometry and a transform each)
    std::int64_t dropped = 0;    // the ring was full: the publisher thread had fallen behind
    std::int64_t untracked = 0;  // lost or reset frames, not published (see above)
    std::int64_t failed = 0;     // DDS refused the write, or the stamp did not fit ROS's Time
  };

  // About 2 s of frames at 30 Hz: a subscriber may stall that long before messages are dropped.
  static constexpr std::size_t kDefaultRingCapacity = 64;

  // Joins the DDS domain and creates the writers (OdometryPublisher: InputError for bad options,
  // RuntimeFailure when Cyclone DDS cannot start). Starts no thread.
  explicit Ros2Sink(const ros2::OdometryPublisherOptions& options, std::size_t ring_capacity = kDefaultRingCapacity);
  ~Ros2Sink() override;
  Ros2Sink(const Ros2Sink&) = delete;
  Ros2Sink& operator=(const Ros2Sink&) = delete;

  // Launches the publisher thread. Until then messages wait in the ring (and drop when it is full).
  void start();
  // Write thread: no allocation, no lock, no wait.
  void consume(const FrameSlot& slot) override;
  // Publishes what the ring still holds, stops the thread, and gives subscribers up to
  // kAcknowledgeTimeout to confirm the last messages (reliable delivery before the process ends).
  void finish() override;

  // The publisher thread's counts are final once finish() returned.
  Counters counters() const;
  // One line for the run's report: what went where, what was not published and why.
  std::string summary() const;
  const std::string& firstError() const { return first_error_; }  // of a failed write; after finish()

  static constexpr std::chrono::milliseconds kAcknowledgeTimeout{2000};

 private:
  void publishLoop();

  ros2::OdometryPublisher publisher_;
  moodycamel::BlockingReaderWriterCircularBuffer<ros2::OdometrySample> ring_;
  std::thread thread_;
  std::atomic<bool> stopping_{false};
  bool finished_ = false;

  // Write thread: the pose the next twist is measured from.
  bool has_previous_ = false;
  std::int64_t previous_t_ns_ = 0;
  SE3d previous_T_world_body_;

  std::atomic<std::int64_t> published_{0}, dropped_{0}, untracked_{0}, failed_{0};
  std::string first_error_;
  bool acknowledged_ = true;
};

}  // namespace voca::pipeline
