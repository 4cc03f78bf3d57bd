#include "pipeline/bench/frontend_bench.h"

#include <fmt/core.h>

#include <cstddef>
#include <utility>

#include "pipeline/bench/per_frame_median.h"
#include "voca/core/error.h"
#include "voca/core/quantile.h"

namespace voca::pipeline {

FrontendTimingOutcome timeFrontend(VoRunOptions options, int repeat, const std::function<void(int run)>& after_run) {
  if (repeat < 1) throw InputError(fmt::format("repeat {}: the frontend must be timed at least once", repeat));
  options.estimate = false;
  options.progress = false;
  options.pipeline_options.threads = 1;
  FrontendTimingOutcome outcome;
  FrontendTiming& timing = outcome.timing;
  std::vector<std::vector<double>> run_cpu_ms, run_wall_ms;
  std::vector<FrameRecord> first_rows;
  for (int run = 0; run < repeat; ++run) {
    VoRunResult result = runVisualOdometry(options);
    if (result.pipeline_report.error || result.stop_signal != 0) {
      outcome.ended_early = std::move(result);
      return outcome;
    }
    if (result.rows.size() < 2) {
      throw InputError(
          fmt::format("{}: {} frame(s), the frontend needs two to be timed", result.description, result.rows.size()));
    }
    if (run == 0) {
      timing.description = result.description;
      double left = 0.0, right = 0.0;
      // The first frame only detects.
      for (std::size_t k = 1; k < result.rows.size(); ++k) {
        left += result.rows[k].left;
        right += result.rows[k].right;
      }
      const double timed = static_cast<double>(result.rows.size() - 1);
      timing.mean_left_points = left / timed;
      timing.mean_right_points = right / timed;
    } else {
      bool same = result.rows.size() == first_rows.size();
      for (std::size_t k = 0; same && k < result.rows.size(); ++k) {
        same = result.rows[k].left == first_rows[k].left && result.rows[k].right == first_rows[k].right &&
               result.rows[k].lost == first_rows[k].lost && result.rows[k].detected == first_rows[k].detected;
      }
      if (!same) {
        throw RuntimeFailure(fmt::format(
            "run {} of the frontend tracked other points than the first: it is not deterministic, so its runs "
            "cannot be compared",
            run + 1));
      }
    }
    std::vector<double>& cpu = run_cpu_ms.emplace_back();
    std::vector<double>& wall = run_wall_ms.emplace_back();
    for (std::size_t k = 1; k < result.rows.size(); ++k) {
      cpu.push_back(result.rows[k].frontend_cpu_ms);
      wall.push_back(result.rows[k].frontend_ms);
    }
    timing.run_median_ms.push_back(median(cpu));
    if (run == 0) first_rows = std::move(result.rows);
    if (after_run) after_run(run);
  }
  timing.cpu_ms = perFrameMedian(run_cpu_ms);
  timing.wall_ms = perFrameMedian(run_wall_ms);
  return outcome;
}

}  // namespace voca::pipeline
