#pragma once
// Appends poses to a trajectory file one row at a time, each flushed as it is written, so a run that
// is stopped or crashes leaves every pose estimated so far in a parseable file.

#include <cstdint>
#include <cstdio>
#include <filesystem>

#include <fmt/format.h>

#include "formats/trajectory/trajectory_io.h"

namespace voca {

// Appends one row of the format to `row` (a pose's line of the file, with its '\n'): what the
// writer writes, for programs that print rows themselves.
void formatTrajectoryRow(const TimedPose& pose, TrajectoryFormat format, fmt::memory_buffer& row);
// The TUM row of a pose given by its parts, written as they are: rebuilding an SE3 first would
// renormalise the quaternion and change its last digits against the writer's rows.
void formatTumRow(std::int64_t t_ns, const Eigen::Vector3d& p_world_body, const Eigen::Quaterniond& q_world_body,
                  fmt::memory_buffer& row);

class TrajectoryWriter {
 public:
  // Creates (or truncates) the file and writes the format's header line (none for KITTI). Throws
  // InputError naming the file when it cannot be created.
  TrajectoryWriter(const std::filesystem::path& path, TrajectoryFormat format);
  ~TrajectoryWriter();
  TrajectoryWriter(const TrajectoryWriter&) = delete;
  TrajectoryWriter& operator=(const TrajectoryWriter&) = delete;

  // One row, with full precision (timestamps exact, numbers in their shortest round-trip form),
  // handed to the OS before returning. Does not allocate. Throws InputError on a write error.
  void append(const TimedPose& pose);
  // Closes the file; throws InputError when the data could not be written. The destructor closes
  // without throwing.
  void close();

  const std::filesystem::path& path() const { return path_; }
  TrajectoryFormat format() const { return format_; }
  std::int64_t rows() const { return rows_; }

 private:
  std::filesystem::path path_;
  TrajectoryFormat format_;
  std::FILE* file_ = nullptr;
  std::int64_t rows_ = 0;
};

}  // namespace voca
