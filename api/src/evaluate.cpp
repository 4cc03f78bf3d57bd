#include "voca_rt/evaluate.h"

#include "api/src/api_internal.h"
#include "formats/eval/eval_inputs.h"
#include "voca/eval/evaluate.h"

namespace voca_rt {

Evaluation evaluate(const std::string& ground_truth_file, const std::string& estimate_file) {
  return detail::translated([&] {
    const voca::EvalInput ground_truth = voca::loadEvalInput(ground_truth_file);
    voca::EvalInput estimate = voca::loadEvalInput(estimate_file);
    voca::matchPoseFrames(estimate, ground_truth, {});
    const voca::EvalOptions options;  // the paper's: SE(3) alignment, RTE over 6 frames
    const voca::EvalReport report = voca::evaluateTrajectory(estimate.trajectory, ground_truth.trajectory, options);
    Evaluation evaluation;
    evaluation.associated = static_cast<std::int64_t>(report.ate.stats.count);
    evaluation.ate_rmse_m = report.ate.stats.rmse;
    evaluation.ate_max_m = report.ate.stats.max;
    if (report.rte) evaluation.rte_rmse_m = report.rte->stats.rmse;
    evaluation.divergent = report.ate_divergent || report.rte_divergent;
    return evaluation;
  });
}

}  // namespace voca_rt
