#pragma once
// The trajectory files an evaluation compares, read with the frame their poses are in. The frame of a
// file follows its format's convention unless said otherwise: KITTI rows are the left camera's poses
// (the benchmark's, and what `voca run --format kitti` writes), TUM and EuRoC rows the body's.

#include <string>

#include "formats/trajectory/trajectory_io.h"
#include "voca/eval/evaluate.h"
#include "voca/trajectory/trajectory.h"

namespace voca {

struct EvalInput {
  Trajectory trajectory;
  TrajectoryFormat format = TrajectoryFormat::kTum;
  std::string frame;  // "body" or "cam0"
};

// The frame a format's poses are in by convention: "cam0" for KITTI, "body" otherwise.
const char* conventionalPoseFrame(TrajectoryFormat format);

// Reads a trajectory file. format: "auto" (detected), "tum", "euroc" or "kitti"; times: a KITTI
// file's times (seconds per line), empty for none; frame: "auto" (the format's convention), "body"
// or "cam0". Throws InputError naming the file.
EvalInput loadEvalInput(const std::string& path, const std::string& format = "auto", const std::string& times = {},
                        const std::string& frame = "auto");

// Converts the estimate into the ground truth's frame with the calibration's T_body_cam0 when the two
// differ. Throws InputError when they differ and no calibration is given.
void matchPoseFrames(EvalInput& estimate, const EvalInput& ground_truth, const std::string& calibration_path);

}  // namespace voca
