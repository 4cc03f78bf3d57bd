#include "pipeline/sinks/trajectory_sink.h"

namespace voca::pipeline {

TrajectorySink::TrajectorySink(const std::optional<std::filesystem::path>& file, TrajectoryFormat format,
                               std::size_t reserve_poses, const SE3d& T_body_cam0)
    : keep_(reserve_poses > 0) {
  if (format == TrajectoryFormat::kKitti) T_body_file_ = T_body_cam0;
  if (file) writer_ = std::make_unique<TrajectoryWriter>(*file, format);
  trajectory_.poses.reserve(reserve_poses);
}

void TrajectorySink::consume(const FrameSlot& slot) {
  const TimedPose pose{slot.pose.t_ns, slot.pose.T_world_body};
  if (writer_) writer_->append(T_body_file_ ? TimedPose{pose.t_ns, pose.T_world_body * *T_body_file_} : pose);
  // Within the reserved size only: a live run longer than expected keeps writing the file without
  // growing memory.
  if (keep_ && trajectory_.poses.size() < trajectory_.poses.capacity()) trajectory_.poses.push_back(pose);
}

void TrajectorySink::finish() {
  if (writer_) writer_->close();
}

}  // namespace voca::pipeline
