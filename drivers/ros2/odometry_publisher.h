#pragma once
// Visual odometry into a ROS 2 graph over DDS, without ROS installed: nav_msgs/msg/Odometry on a
// topic (/odom) and the odom -> base_link transform on /tf (tf2_msgs/msg/TFMessage), with the DDS
// names, types (XCDR1, little-endian, as rmw_cyclonedds_cpp writes them) and QoS that ROS 2 nodes
// use, through Cyclone DDS's C API. Cyclone reads its network settings from CYCLONEDDS_URI.

#include <Eigen/Core>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "voca/geometry/se3.h"

namespace voca::ros2 {

// QoS as ROS 2 nodes use it: reliable, volatile, keep-last with these depths.
inline constexpr int kOdometryHistoryDepth = 10;  // rclcpp's default for a publisher
inline constexpr int kTfHistoryDepth = 100;       // tf2_ros::TransformBroadcaster's
inline constexpr const char* kTfTopic = "/tf";

struct OdometryPublisherOptions {
  std::uint32_t domain_id = 0;           // usually domainIdFromEnvironment() (ROS_DOMAIN_ID)
  std::string topic = "/odom";           // a ROS topic name (ros2_names.h), relative ones in the root namespace
  std::string odom_frame = "odom";       // header.frame_id: the world frame (the first frame's body pose)
  std::string base_frame = "base_link";  // child_frame_id: the body frame of the calibration
};

// One message's content. The twist is in the base frame, as nav_msgs/Odometry has it.
struct OdometrySample {
  std::int64_t t_ns = 0;  // the frame's sensor time: header.stamp
  SE3d T_odom_base;
  Eigen::Vector3d linear_velocity_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_velocity_radps = Eigen::Vector3d::Zero();
  // False: no velocity estimate (first pose of a track). The twist is published as zero with
  // twist covariance element 0 set to -1, ROS's mark for "no estimate of this quantity".
  bool twist_known = false;
};

// The constant body-frame twist (linear, angular) that carries T_world_prev to T_world_cur in dt_s
// seconds: log(T_world_prev^-1 T_world_cur) / dt_s. Exact for motion at constant body velocity (a car
// on a circle gets its forward speed and yaw rate, with no sideways component from the chord).
Eigen::Matrix<double, 6, 1> bodyTwist(const SE3d& T_world_prev, const SE3d& T_world_cur, double dt_s);

class OdometryPublisher {
 public:
  // Joins the DDS domain and creates the two writers. Throws InputError for an invalid topic or frame
  // id or a domain above kMaxDomainId, RuntimeFailure when Cyclone DDS cannot start (its message and
  // the CYCLONEDDS_URI in use).
  explicit OdometryPublisher(const OdometryPublisherOptions& options);
  ~OdometryPublisher();
  OdometryPublisher(const OdometryPublisher&) = delete;
  OdometryPublisher& operator=(const OdometryPublisher&) = delete;

  // Writes the Odometry and the transform. Call from one thread at a time. Uses no memory of its own
  // per call (the messages are built in place); Cyclone serialises into buffers of its own. Returns
  // false when a stamp does not fit ROS's Time (int32 seconds) or a write failed; lastError() says which.
  bool publish(const OdometrySample& sample);
  const std::string& lastError() const;

  // Waits up to `timeout` until every matched subscriber has acknowledged all messages written, so
  // the last poses reach them before the writers go away. True when all did (or none is matched).
  bool waitForAcknowledgments(std::chrono::milliseconds timeout);

  int matchedOdometrySubscribers() const;
  const std::string& odometryDdsTopic() const;  // "rt/odom"
  std::uint32_t domainId() const;

 private:
  struct Impl;  // keeps Cyclone's headers and the generated types out of users' translation units
  std::unique_ptr<Impl> impl_;
};

}  // namespace voca::ros2
