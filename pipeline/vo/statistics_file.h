#pragma once
// The statistics file of a run (`--stats out.json`): totals, per-stage latency, queues, skipped
// frames, the guess-distance histograms (the paper's Fig. 5) and one row per frame.

#include <filesystem>

#include "pipeline/vo/vo_run.h"

namespace voca::pipeline {

// Throws InputError naming the file when it cannot be written.
void writeStatisticsJson(const VoRunResult& result, const std::filesystem::path& file);

}  // namespace voca::pipeline
