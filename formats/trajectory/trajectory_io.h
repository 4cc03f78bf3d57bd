#pragma once
// Trajectory files: TUM, EuRoC csv and KITTI poses read and written with full precision.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string_view>
#include <vector>

#include "voca/trajectory/trajectory.h"

namespace voca {

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

// Parses a decimal number of seconds ("12.5", "1.403715529112143517e+09") exactly into integer
// nanoseconds, rounding half away from zero below 1 ns. nullopt if the text is not a number or
// overflows int64.
std::optional<int64_t> parseSecondsToNs(std::string_view text);

}  // namespace voca
