#pragma once
// Command-line options every command that runs the pipeline shares (`voca run`, `voca track`,
// `voca bench pipeline`): threads and pinning, real-time scheduling, live-rate replay, damaged-frame
// policy, decoder choice, and the latency outputs.

#include <CLI/CLI.hpp>
#include <string>

#include "pipeline/vo/vo_runner.h"

namespace voca::cli {

struct PipelineCli {
  std::string threads = "auto";
  std::string frontend_threads = "auto";
  std::string pin;
  std::string scheduling = "other";
  int priority = 50;
  bool lock_memory = false;
  bool realtime = false;
  double speed = 1.0;
  bool strict = false;
  std::string decoder = "auto";
  bool skip_deblock = false;
  bool profile = false;
  std::string trace;
  std::string stats;
};

// Declares the options on a command.
void addPipelineOptions(CLI::App& app, PipelineCli& cli);

// Copies the parsed options into the runner's, validating them (InputError naming the option).
void applyPipelineOptions(const PipelineCli& cli, pipeline::VoRunOptions& options);

// The help text explaining threads, pinning, exit codes and outputs, for a command's footer.
std::string pipelineHelpFooter();

// After a run: warnings, the --profile table, and the exit code for an interrupted or failed run
// (0 when it completed; the error is printed as "voca <command>: error: ...").
int reportRunEnd(const pipeline::VoRunResult& result, const PipelineCli& cli, const std::string& command);

}  // namespace voca::cli
