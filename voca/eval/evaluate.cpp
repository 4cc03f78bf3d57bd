#include "voca/eval/evaluate.h"

namespace voca {

std::string_view evalVerdictName(EvalVerdict verdict) {
  switch (verdict) {
    case EvalVerdict::kOk:
      return "ok";
    case EvalVerdict::kDivergent:
      return "divergent";
    case EvalVerdict::kReset:
      return "R";
  }
  return "unknown";
}

namespace {

// The associated poses as matrices; KITTI rows as read when the trajectory has them (see
// Trajectory::raw_matrices) so RTE matches evo's.
std::vector<Eigen::Matrix4d> associatedMatrices(const Trajectory& trajectory, const std::vector<std::size_t>& index) {
  const bool raw = trajectory.raw_matrices.size() == trajectory.poses.size();
  std::vector<Eigen::Matrix4d> matrices;
  matrices.reserve(index.size());
  for (const std::size_t i : index) {
    Eigen::Matrix4d T = trajectory.poses[i].T_world_body.matrix();
    if (raw) T.topRows<3>() = trajectory.raw_matrices[i];
    matrices.push_back(T);
  }
  return matrices;
}

}  // namespace

Trajectory convertPoseFrame(const Trajectory& trajectory, PoseFrame from, PoseFrame to, const SE3d& T_body_cam0) {
  if (from == to) return trajectory;
  // T_world_cam0 = T_world_body * T_body_cam0, and back with the inverse.
  return changeBodyFrame(trajectory, from == PoseFrame::kBody ? T_body_cam0 : T_body_cam0.inverse());
}

EvalReport evaluateTrajectory(const Trajectory& est, const Trajectory& gt, const EvalOptions& options) {
  EvalReport report;
  report.est_poses = est.poses.size();
  report.gt_poses = gt.poses.size();
  report.association = associateTrajectories(est, gt, options.max_diff_s);

  const std::vector<Eigen::Matrix4d> T_world_est = associatedMatrices(est, report.association.est_index);
  const std::vector<Eigen::Matrix4d> T_world_gt = associatedMatrices(gt, report.association.gt_index);
  std::vector<Eigen::Vector3d> p_world_est, p_world_gt;
  for (const Eigen::Matrix4d& T : T_world_est) p_world_est.push_back(T.topRightCorner<3, 1>());
  for (const Eigen::Matrix4d& T : T_world_gt) p_world_gt.push_back(T.topRightCorner<3, 1>());

  report.ate = absoluteTrajectoryError(p_world_est, p_world_gt, options.align);
  RteResult rte = relativeTrajectoryError(T_world_est, T_world_gt, options.rte_delta, options.rte_delta_unit);
  if (!rte.pairs.empty()) report.rte = std::move(rte);

  report.ate_divergent = report.ate.stats.rmse > options.ate_divergence_m;
  report.rte_divergent = report.rte && report.rte->stats.rmse > options.rte_divergence_m;
  bool reset = false;
  if (options.expected_frames && *options.expected_frames > 0) {
    report.coverage = static_cast<double>(report.est_poses) / static_cast<double>(*options.expected_frames);
    // The paper's R: the system could not estimate more than half of the trajectory.
    reset = *report.coverage < 0.5;
  }
  const auto verdict = [reset](bool divergent) {
    if (reset) return EvalVerdict::kReset;
    return divergent ? EvalVerdict::kDivergent : EvalVerdict::kOk;
  };
  report.ate_verdict = verdict(report.ate_divergent);
  report.rte_verdict = verdict(report.rte_divergent);
  return report;
}

}  // namespace voca
