#pragma once
// The ROS 2 options of the commands that estimate poses (`voca run`, `voca live`): --ros2 publishes
// the odometry and /tf into a ROS 2 graph over DDS (pipeline/sinks/ros2_sink.h).

#include <CLI/CLI.hpp>
#include <string>

#include "voca_rt/odometry.h"

namespace voca::cli {

struct Ros2Cli {
  bool enabled = false;
  std::string topic = "/odom";
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
};

// Declares --ros2, --ros2-topic, --ros2-odom-frame and --ros2-base-frame (the last three need --ros2).
void addRos2Options(CLI::App& app, Ros2Cli& cli);

// With --ros2, sets options.ros2 (the library checks the names and ROS_DOMAIN_ID before any input is
// opened, naming the option or the variable).
void applyRos2Options(const Ros2Cli& cli, voca_rt::Options& options);

// The help text: what is published, QoS, domain, frames, and Cyclone DDS's network settings.
std::string ros2HelpFooter();

// After a run with --ros2: what was published (one line on stdout).
void printRos2Summary(const voca_rt::Summary& summary);

}  // namespace voca::cli
