#include "tools/voca/ros2_cli.h"

#include <fmt/core.h>

namespace voca::cli {

void addRos2Options(CLI::App& app, Ros2Cli& cli) {
  CLI::Option* ros2 = app.add_flag(
      "--ros2", cli.enabled,
      "Publish the odometry into a ROS 2 graph over DDS (no ROS needed): nav_msgs/Odometry on /odom and the\n"
      "odom -> base_link transform on /tf (see below)");
  app.add_option("--ros2-topic", cli.topic, "ROS 2 topic of the odometry (relative names are in the root namespace)")
      ->capture_default_str()
      ->needs(ros2);
  app.add_option("--ros2-odom-frame", cli.odom_frame, "Frame id of the odometry's world frame (header.frame_id)")
      ->capture_default_str()
      ->needs(ros2);
  app.add_option("--ros2-base-frame", cli.base_frame, "Frame id of the body frame of the calibration (child_frame_id)")
      ->capture_default_str()
      ->needs(ros2);
}

void applyRos2Options(const Ros2Cli& cli, voca_rt::Options& options) {
  if (!cli.enabled) return;
  options.ros2 = voca_rt::Ros2Output{.topic = cli.topic, .odom_frame = cli.odom_frame, .base_frame = cli.base_frame};
}

std::string ros2HelpFooter() {
  return "ROS 2 (--ros2): each tracked pose goes into the ROS 2 graph over DDS (Cyclone DDS; ROS itself is not\n"
         "needed), from a thread of its own that never holds the pipeline up, as nav_msgs/msg/Odometry on\n"
         "--ros2-topic (DDS topic rt/odom) and as the odom -> base_link transform on /tf (tf2_msgs/msg/TFMessage),\n"
         "with the QoS ROS 2 nodes use: reliable, volatile, keep-last 10 (/odom) and 100 (/tf). The domain is\n"
         "ROS_DOMAIN_ID (unset: 0; 0 to 232). Stamps are the frames' sensor times (`voca live`: the cameras'\n"
         "CLOCK_MONOTONIC). The pose is the trajectory file's body pose in odom, which is the first frame's body\n"
         "pose; the twist is the body-frame velocity between consecutive poses, zero (covariance element 0 = -1:\n"
         "no estimate) for the first pose of a track. Covariances are zero: ROS's \"unknown\" (the estimator gives\n"
         "none). Lost and reset frames repeat a held pose and are not published: /odom and /tf pause while\n"
         "tracking is down. Cyclone takes its network settings from CYCLONEDDS_URI; on a network without\n"
         "multicast, name the other hosts as peers (the robot's, the laptop's with rviz2), on each of them:\n"
         "  CYCLONEDDS_URI='<CycloneDDS><Domain id=\"any\"><General><AllowMulticast>false</AllowMulticast>\n"
         "  </General><Discovery><ParticipantIndex>auto</ParticipantIndex><Peers><Peer address=\"192.168.1.20\"/>\n"
         "  </Peers></Discovery></Domain></CycloneDDS>'\n"
         "(add <Interfaces><NetworkInterface name=\"eth0\"/></Interfaces> inside General to pick the interface).";
}

void printRos2Summary(const voca_rt::Summary& summary) {
  if (!summary.ros2_summary.empty()) fmt::print("{}\n", summary.ros2_summary);
}

}  // namespace voca::cli
