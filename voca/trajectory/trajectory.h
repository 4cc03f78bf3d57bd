#pragma once
// Timestamped pose sequences and their resampling. Their files (TUM, EuRoC csv, KITTI) are
// formats/trajectory/trajectory_io.h.

#include <cstdint>
#include <optional>
#include <vector>

#include "voca/geometry/se3.h"

namespace voca {

// One pose of a trajectory: the body frame at time t_ns, expressed in the world frame.
struct TimedPose {
  int64_t t_ns = 0;
  SE3d T_world_body;
};

// A sequence of poses in file order (time order for the timestamped formats).
struct Trajectory {
  std::vector<TimedPose> poses;
  // False for KITTI poses read without a times file: t_ns is then the frame index in seconds and
  // the poses can only be paired with another trajectory by index (as evo does for KITTI).
  bool has_timestamps = true;
  // KITTI only: each row's 3x4 matrix exactly as written. The files keep 7-9 digits, so these are
  // orthonormal only to ~1e-7, and T_world_body holds their projection onto SE(3); evaluation uses
  // the matrices as read, as evo does, to reproduce its numbers. Empty for the other formats;
  // ignored unless it has one entry per pose.
  std::vector<Eigen::Matrix<double, 3, 4>> raw_matrices;
};

// The pose at t_ns: linear in translation, slerp in rotation between the neighbouring poses.
// nullopt outside [first, last] or for an empty trajectory. Poses must be sorted by time.
std::optional<SE3d> interpolatePose(const Trajectory& trajectory, int64_t t_ns);

// The same motion described by another body frame: T_world_new = T_world_body * T_body_new for
// every pose (e.g. T_body_new = T_body_cam0 turns body poses into cam0 poses). Drops raw_matrices.
Trajectory changeBodyFrame(const Trajectory& trajectory, const SE3d& T_body_new);

}  // namespace voca
