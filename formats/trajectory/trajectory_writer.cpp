#include "formats/trajectory/trajectory_writer.h"

#include <fmt/format.h>

#include <iterator>

#include "voca/core/error.h"

namespace voca {

TrajectoryWriter::TrajectoryWriter(const std::filesystem::path& path, TrajectoryFormat format)
    : path_(path), format_(format) {
  file_ = std::fopen(path.c_str(), "w");
  if (file_ == nullptr) throw InputError(fmt::format("cannot write trajectory file {}", path.string()));
  const char* header = format == TrajectoryFormat::kEuroc
                           ? "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y "
                             "[],q_RS_z []\n"
                       : format == TrajectoryFormat::kTum ? "# timestamp tx ty tz qx qy qz qw\n"
                                                          : "";
  if (std::fputs(header, file_) < 0 || std::fflush(file_) != 0) {
    std::fclose(file_);
    file_ = nullptr;
    throw InputError(fmt::format("error writing trajectory file {}", path.string()));
  }
}

TrajectoryWriter::~TrajectoryWriter() {
  if (file_ != nullptr) std::fclose(file_);
}

void formatTumRow(std::int64_t t_ns, const Eigen::Vector3d& p_world_body, const Eigen::Quaterniond& q_world_body,
                  fmt::memory_buffer& row) {
  // Seconds with exactly 9 decimals, so the nanosecond timestamp reads back unchanged; fmt's "{}"
  // is the shortest text that reads back to the same double.
  const bool negative = t_ns < 0;
  const std::uint64_t magnitude =
      negative ? std::uint64_t{0} - static_cast<std::uint64_t>(t_ns) : static_cast<std::uint64_t>(t_ns);
  fmt::format_to(std::back_inserter(row), "{}{}.{:09d} {} {} {} {} {} {} {}\n", negative ? "-" : "",
                 magnitude / 1'000'000'000u, magnitude % 1'000'000'000u, p_world_body.x(), p_world_body.y(),
                 p_world_body.z(), q_world_body.x(), q_world_body.y(), q_world_body.z(), q_world_body.w());
}

void formatTrajectoryRow(const TimedPose& pose, TrajectoryFormat format, fmt::memory_buffer& row) {
  const Eigen::Vector3d& p = pose.T_world_body.translation();
  const Eigen::Quaterniond& q = pose.T_world_body.unitQuaternion();
  auto out = std::back_inserter(row);
  switch (format) {
    case TrajectoryFormat::kTum:
      formatTumRow(pose.t_ns, p, q, row);
      break;
    case TrajectoryFormat::kEuroc:
      fmt::format_to(out, "{},{},{},{},{},{},{},{}\n", pose.t_ns, p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z());
      break;
    case TrajectoryFormat::kKitti: {
      const Eigen::Matrix<double, 3, 4> m = pose.T_world_body.matrix3x4();
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 4; ++c) fmt::format_to(out, "{}{}", (r == 0 && c == 0) ? "" : " ", m(r, c));
      }
      row.push_back('\n');
      break;
    }
  }
}

void TrajectoryWriter::append(const TimedPose& pose) {
  if (file_ == nullptr) throw InputError(fmt::format("trajectory file {} is closed", path_.string()));
  // A row is at most ~300 characters, within the buffer's inline storage: no allocation.
  fmt::memory_buffer row;
  formatTrajectoryRow(pose, format_, row);
  if (std::fwrite(row.data(), 1, row.size(), file_) != row.size() || std::fflush(file_) != 0) {
    throw InputError(fmt::format("error writing trajectory file {}", path_.string()));
  }
  ++rows_;
}

void TrajectoryWriter::close() {
  if (file_ == nullptr) return;
  const bool failed = std::ferror(file_) != 0;
  const int rc = std::fclose(file_);
  file_ = nullptr;
  if (failed || rc != 0) throw InputError(fmt::format("error writing trajectory file {}", path_.string()));
}

}  // namespace voca
