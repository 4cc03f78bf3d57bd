#include "voca/eval/evaluate.h"

#include <nlohmann/json.hpp>

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

namespace {

nlohmann::json statsJson(const ErrorStats& stats) {
  return {{"rmse", stats.rmse}, {"mean", stats.mean}, {"median", stats.median}, {"std", stats.std},
          {"min", stats.min},   {"max", stats.max},   {"sse", stats.sse},       {"count", stats.count}};
}

}  // namespace

nlohmann::json evalReportToJson(const EvalReport& report, const EvalOptions& options) {
  nlohmann::json j;
  const PoseAssociation& a = report.association;
  j["association"] = {{"method", a.by_index ? "index" : "timestamp"},
                      {"est_poses", report.est_poses},
                      {"gt_poses", report.gt_poses},
                      {"pairs", a.size()},
                      {"max_diff_s", a.max_diff_s},
                      {"max_abs_dt_s", a.max_abs_dt_s},
                      {"mean_abs_dt_s", a.mean_abs_dt_s},
                      {"reused_poses", a.reused_poses}};

  nlohmann::json ate = statsJson(report.ate.stats);
  ate["alignment"] = alignModeName(report.ate.align);
  const Eigen::Matrix4d T = report.ate.alignment.T_gt_est.matrix();
  ate["T_gt_est"] = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) ate["T_gt_est"].push_back({T(r, 0), T(r, 1), T(r, 2), T(r, 3)});
  ate["scale"] = report.ate.alignment.scale;
  ate["divergence_threshold_m"] = options.ate_divergence_m;
  ate["divergent"] = report.ate_divergent;
  ate["verdict"] = evalVerdictName(report.ate_verdict);
  j["ate"] = ate;

  nlohmann::json rte = report.rte ? statsJson(report.rte->stats) : statsJson(ErrorStats{});
  rte["delta"] = options.rte_delta;
  rte["delta_unit"] = deltaUnitName(options.rte_delta_unit);
  rte["available"] = report.rte.has_value();
  rte["divergence_threshold_m"] = options.rte_divergence_m;
  rte["divergent"] = report.rte_divergent;
  rte["verdict"] = evalVerdictName(report.rte_verdict);
  j["rte"] = rte;

  j["expected_frames"] = options.expected_frames ? nlohmann::json(*options.expected_frames) : nlohmann::json();
  j["coverage"] = report.coverage ? nlohmann::json(*report.coverage) : nlohmann::json();
  return j;
}

}  // namespace voca
