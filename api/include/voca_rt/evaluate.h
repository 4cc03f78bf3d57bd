#pragma once
// Trajectory errors as the VOCA paper reports them and `voca eval` prints them (the same numbers as
// evo): ATE, the RMSE of positions after an SE(3) Umeyama alignment (no scale: stereo), and RTE, the
// RMSE of relative translations over 6 frames without alignment.

#include <cstdint>
#include <optional>
#include <string>

#include "voca_rt/export.h"

namespace voca_rt {

struct Evaluation {
  std::int64_t associated = 0;  // estimated poses matched to ground truth by timestamp
  double ate_rmse_m = 0.0;
  double ate_max_m = 0.0;
  std::optional<double> rte_rmse_m;  // empty when the trajectory is shorter than the RTE's delta
  bool divergent = false;            // ATE > 10 m or RTE > 10 cm: the paper's "diverged"
};

// Reads both files (TUM, EuRoC csv or KITTI, told apart by their content) and evaluates the
// estimate against the ground truth. Throws Error naming a file that cannot be read or that holds
// no pose matching the other's times.
VOCA_RT_API Evaluation evaluate(const std::string& ground_truth_file, const std::string& estimate_file);

}  // namespace voca_rt
