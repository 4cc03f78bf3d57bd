#pragma once
// One evaluation of an estimated trajectory against ground truth, with the paper's failure rules.

#include <cstddef>
#include <optional>
#include <string_view>

#include "voca/eval/association.h"
#include "voca/eval/metrics.h"
#include "voca/trajectory/trajectory.h"

namespace voca {

// What to compute; the defaults are the paper's (evo_ape -a, evo_rpe -d 6 -u f, thresholds of
// Table 1; use ate_divergence_m = 1 for the Monado dataset).
struct EvalOptions {
  double max_diff_s = 0.01;
  AlignMode align = AlignMode::kSe3;
  double rte_delta = 6.0;
  DeltaUnit rte_delta_unit = DeltaUnit::kFrames;
  double ate_divergence_m = 10.0;
  double rte_divergence_m = 0.10;
  // Frames the run should have estimated; enables the "R" verdict (more than half missing).
  std::optional<std::size_t> expected_frames;
};

// How a run is shown in the paper's tables: its value, infinity when divergent, R when reset.
enum class EvalVerdict { kOk, kDivergent, kReset };
std::string_view evalVerdictName(EvalVerdict verdict);

// Everything `voca eval` reports.
struct EvalReport {
  std::size_t est_poses = 0;
  std::size_t gt_poses = 0;
  PoseAssociation association;
  AteResult ate;
  std::optional<RteResult> rte;  // nullopt when the associated poses are too few for one pair
  bool ate_divergent = false;
  bool rte_divergent = false;
  std::optional<double> coverage;  // estimated poses / expected frames
  EvalVerdict ate_verdict = EvalVerdict::kOk;
  EvalVerdict rte_verdict = EvalVerdict::kOk;
};

// The frame whose poses a trajectory holds: the calibration's body frame (our outputs, EuRoC
// ground truth) or the left camera (KITTI poses).
enum class PoseFrame { kBody, kCam0 };

// The same motion expressed in another frame, using the calibration's T_body_cam0.
Trajectory convertPoseFrame(const Trajectory& trajectory, PoseFrame from, PoseFrame to, const SE3d& T_body_cam0);

// Associates, aligns and measures. Both trajectories must be in the same body frame already.
EvalReport evaluateTrajectory(const Trajectory& est, const Trajectory& gt, const EvalOptions& options = {});

}  // namespace voca
