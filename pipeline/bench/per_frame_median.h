#pragma once
// How the benches combine repeated runs over the same frames: each frame's median over the runs.
// The work is the same each run, so a load spike on a shared machine that hits one run of a frame
// drops out, where pooling every run's frames would keep it.

#include <vector>

namespace voca::pipeline {

// Each frame's median over runs of the same frames (run_ms[run][frame]; every run as long as the
// first). Throws InputError for no runs or runs of different lengths.
std::vector<double> perFrameMedian(const std::vector<std::vector<double>>& run_ms);

}  // namespace voca::pipeline
