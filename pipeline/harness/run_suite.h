#pragma once
// Running a suite's plan: renderings and encodings once (cached in the output folder), then every run
// as a child `voca run` process (so a crash of one run is recorded as x and the suite goes on), up to
// `jobs` at a time, skipping what a previous call finished; each run's result (collect_results.h
// makes the tables).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "pipeline/harness/suite.h"
#include "platform/process/child_process.h"

namespace voca::harness {

struct SuiteRunOptions {
  int jobs = 1;
  bool retry_failed = false;             // run again what a previous call recorded as failed
  bool progress = true;                  // a line per finished job on stderr, with done/total and time left
  std::function<bool()> stop_requested;  // checked between jobs: start nothing new, wait for the running ones
};

struct SuiteRunReport {
  int total = 0;              // runs in the plan
  int skipped = 0;            // done by an earlier call
  int ran = 0;                // run now
  int failed = 0;             // of those, recorded as failed
  std::string first_failure;  // "<run id>: <reason>" of the first run recorded as failed now
  int preparation_failures = 0;
  bool stopped = false;
};

// Writes <out>/suite.json (the suite with absolute paths), which `voca bench collect` reads.
void writeSuiteFile(const Suite& suite, const std::filesystem::path& out);

SuiteRunReport runSuite(const Suite& suite, const SuitePlan& plan, const std::filesystem::path& out,
                        const SuiteRunOptions& options);

// One run's result.json from its folder (trajectory, stats.json) and, when known, how the process
// ended. A run is "ok" when it exited cleanly and was evaluated; otherwise "failed" with the reason.
nlohmann::json summariseRun(const PlannedRun& run, const std::optional<platform::ChildExit>& exit, double wall_s);

// The longest stretch of frames tracked without a reset, a loss or a gap, as a fraction of the frames
// (the paper's R rule), from the stats.json frame rows.
double resetFreeFraction(const nlohmann::json& statistics);

}  // namespace voca::harness
