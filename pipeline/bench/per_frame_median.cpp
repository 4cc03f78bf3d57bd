#include "pipeline/bench/per_frame_median.h"

#include <fmt/core.h>

#include <cstddef>

#include "voca/core/error.h"
#include "voca/core/quantile.h"

namespace voca::pipeline {

std::vector<double> perFrameMedian(const std::vector<std::vector<double>>& run_ms) {
  if (run_ms.empty()) throw InputError("per-frame median: no runs");
  const std::size_t frames = run_ms.front().size();
  for (const std::vector<double>& run : run_ms) {
    if (run.size() != frames) {
      throw InputError(fmt::format("per-frame median: a run of {} frames beside one of {}", run.size(), frames));
    }
  }
  std::vector<double> medians(frames), frame_ms(run_ms.size());
  for (std::size_t k = 0; k < frames; ++k) {
    for (std::size_t run = 0; run < run_ms.size(); ++run) frame_ms[run] = run_ms[run][k];
    medians[k] = quantileInPlace(frame_ms, 0.5);
  }
  return medians;
}

}  // namespace voca::pipeline
