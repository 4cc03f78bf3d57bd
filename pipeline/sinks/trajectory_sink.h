#pragma once
// Streams each pose to the trajectory file as soon as it is estimated (flushed per row), and keeps
// the trajectory in memory for evaluation when asked to.

#include <filesystem>
#include <memory>
#include <optional>

#include "formats/trajectory/trajectory_io.h"
#include "formats/trajectory/trajectory_writer.h"
#include "pipeline/sinks/sink_stage.h"

namespace voca::pipeline {

class TrajectorySink final : public FrameSink {
 public:
  // file: nullopt writes no file. reserve_poses: poses kept in memory without reallocating (the
  // expected frame count; 0 keeps none). KITTI rows are the left camera's poses (the benchmark's
  // convention, and what `voca eval` reads a KITTI file as), so that format's file gets
  // T_world_body * T_body_cam0; the other formats and the kept trajectory are body poses.
  TrajectorySink(const std::optional<std::filesystem::path>& file, TrajectoryFormat format, std::size_t reserve_poses,
                 const SE3d& T_body_cam0);
  void consume(const FrameSlot& slot) override;
  void finish() override;

  const Trajectory& trajectory() const { return trajectory_; }

 private:
  std::unique_ptr<TrajectoryWriter> writer_;
  Trajectory trajectory_;
  std::optional<SE3d> T_body_file_;  // the frame of the file's poses when it is not the body (KITTI: cam0)
  bool keep_;
};

}  // namespace voca::pipeline
