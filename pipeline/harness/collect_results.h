#pragma once
// A suite's results into the paper's tables: what `voca bench collect` and the end of
// `voca bench suite` do.

#include <filesystem>
#include <string>
#include <vector>

namespace voca::harness {

// Reads <out>/suite.json and every run's result.json (summarising runs that have outputs but no
// result.json, as cluster jobs leave them), evaluates the external trajectories, and writes
// tables/<bitrate>.{md,csv,tex}, summary.{md,csv}, against_none.csv and results.csv into out.
// Returns the paths written.
std::vector<std::filesystem::path> collectResults(const std::filesystem::path& out, const std::string& voca_executable);

}  // namespace voca::harness
