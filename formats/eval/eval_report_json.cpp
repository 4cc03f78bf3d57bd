#include "formats/eval/eval_report_json.h"

#include <nlohmann/json.hpp>

namespace voca {

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
