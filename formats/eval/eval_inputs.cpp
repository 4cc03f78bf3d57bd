#include "formats/eval/eval_inputs.h"

#include <fmt/format.h>

#include "formats/calib/calibration_io.h"
#include "voca/core/error.h"

namespace voca {

const char* conventionalPoseFrame(TrajectoryFormat format) {
  return format == TrajectoryFormat::kKitti ? "cam0" : "body";
}

EvalInput loadEvalInput(const std::string& path, const std::string& format, const std::string& times,
                        const std::string& frame) {
  EvalInput loaded;
  if (format == "auto") {
    loaded.format = detectTrajectoryFormat(path);
  } else {
    const std::optional<TrajectoryFormat> parsed = parseTrajectoryFormat(format);
    if (!parsed) throw InputError(fmt::format("{}: format \"{}\": expected auto, tum, euroc or kitti", path, format));
    loaded.format = *parsed;
  }
  loaded.trajectory = loadTrajectory(path, loaded.format, times);
  loaded.frame = frame != "auto" ? frame : conventionalPoseFrame(loaded.format);
  return loaded;
}

void matchPoseFrames(EvalInput& estimate, const EvalInput& ground_truth, const std::string& calibration_path) {
  if (estimate.frame == ground_truth.frame) return;
  if (calibration_path.empty()) {
    throw InputError(fmt::format(
        "the estimate is in the {} frame and the ground truth in the {} frame: give --calib so the estimate can be "
        "converted (or --est-frame/--gt-frame if they are really the same)",
        estimate.frame, ground_truth.frame));
  }
  const StereoRig rig = loadCalibration(calibration_path);
  if (rig.cameras.empty()) throw InputError(fmt::format("{} has no cameras", calibration_path));
  const auto frame = [](const std::string& name) { return name == "cam0" ? PoseFrame::kCam0 : PoseFrame::kBody; };
  estimate.trajectory = convertPoseFrame(estimate.trajectory, frame(estimate.frame), frame(ground_truth.frame),
                                         rig.cameras[0].T_body_cam);
  estimate.frame = ground_truth.frame;
}

}  // namespace voca
