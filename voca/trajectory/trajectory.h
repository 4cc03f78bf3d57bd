#pragma once
// Timestamped pose sequences and their file formats (TUM, EuRoC csv, KITTI), plus resampling.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string_view>
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

// TUM: `t tx ty tz qx qy qz qw` in seconds; EuRoC: `t_ns,px,py,pz,qw,qx,qy,qz[,...]` csv;
// KITTI: 12 numbers per row, the 3x4 matrix T_world_cam0 in row-major order.
enum class TrajectoryFormat { kTum, kEuroc, kKitti };

std::string_view trajectoryFormatName(TrajectoryFormat format);
// "tum", "euroc" or "kitti"; nullopt for anything else.
std::optional<TrajectoryFormat> parseTrajectoryFormat(std::string_view name);

// Guesses the format from the first data row (comma-separated -> EuRoC, 8 fields -> TUM,
// 12 fields -> KITTI). Throws InputError naming the file and line when it cannot tell.
TrajectoryFormat detectTrajectoryFormat(const std::filesystem::path& path);

// Reads a trajectory, detecting the format unless one is given. For KITTI, kitti_times (one time
// in seconds per line, as KITTI's times.txt) supplies the timestamps; without it the poses are
// indexed by frame (has_timestamps = false). Timestamps must not decrease (repeats are kept, as
// evo keeps them). Malformed rows
// throw InputError with file:line and what was expected.
Trajectory loadTrajectory(const std::filesystem::path& path, std::optional<TrajectoryFormat> format = {},
                          const std::filesystem::path& kitti_times = {});

// Reads a KITTI times.txt-style file: one time in seconds per non-empty line, returned in ns.
std::vector<int64_t> loadTimesFile(const std::filesystem::path& path);

// Writes with full precision: timestamps exactly (TUM seconds with 9 decimals, EuRoC integer ns),
// numbers in their shortest round-trip form. KITTI rows carry no timestamps.
void saveTrajectory(const Trajectory& trajectory, const std::filesystem::path& path, TrajectoryFormat format);

// The pose at t_ns: linear in translation, slerp in rotation between the neighbouring poses.
// nullopt outside [first, last] or for an empty trajectory. Poses must be sorted by time.
std::optional<SE3d> interpolatePose(const Trajectory& trajectory, int64_t t_ns);

// The same motion described by another body frame: T_world_new = T_world_body * T_body_new for
// every pose (e.g. T_body_new = T_body_cam0 turns body poses into cam0 poses). Drops raw_matrices.
Trajectory changeBodyFrame(const Trajectory& trajectory, const SE3d& T_body_new);

// Parses a decimal number of seconds ("12.5", "1.403715529112143517e+09") exactly into integer
// nanoseconds, rounding half away from zero below 1 ns. nullopt if the text is not a number or
// overflows int64.
std::optional<int64_t> parseSecondsToNs(std::string_view text);

}  // namespace voca
