#pragma once
// `voca bench frontend`: the KLT frontend's cost per stereo frame in one prior mode, timed as the
// pipeline runs it (every stage in one thread, no estimator) on this thread's CPU clock.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/vo/vo_runner.h"

namespace voca::pipeline {

struct FrontendTiming {
  // Per timed frame (every frame but the first, which only detects): the frontend stage's thread
  // CPU time and its wall-clock time, each the median over the runs (the same work each time, so
  // the median drops what another process on a shared machine added to one run).
  std::vector<double> cpu_ms, wall_ms;
  std::vector<double> run_median_ms;                       // each run's own CPU median over the frames, in run order
  double mean_left_points = 0.0, mean_right_points = 0.0;  // tracks put out per timed frame
  std::string description;                                 // the input, as the first run described it
};

struct FrontendTimingOutcome {
  FrontendTiming timing;
  // The run that failed or was stopped, which ended the timing early (timing is then incomplete).
  std::optional<VoRunResult> ended_early;
};

// Runs the frontend `repeat` times over options.input (estimate forced off, one thread, no progress
// line), calling after_run(run) after each. Throws InputError for repeat < 1 or a run without a
// timed frame, and RuntimeFailure when a run's tracks per frame differ from the first run's (the
// runs would time different work).
FrontendTimingOutcome timeFrontend(VoRunOptions options, int repeat,
                                   const std::function<void(int run)>& after_run = {});

}  // namespace voca::pipeline
