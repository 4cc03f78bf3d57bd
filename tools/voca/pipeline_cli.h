#pragma once
// Command-line options every command that runs the pipeline shares (`voca run`, `voca track`,
// `voca bench pipeline`): threads and pinning, real-time scheduling, live-rate replay, damaged-frame
// policy, decoder choice, and the latency outputs.

#include <CLI/CLI.hpp>
#include <string>

#include "pipeline/vo/run_settings.h"
#include "pipeline/vo/vo_runner.h"
#include "voca_rt/odometry.h"

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

// The parsed options as the runner's settings: "auto" and counts read (InputError naming the option).
pipeline::RunSettings runSettings(const PipelineCli& cli);
// Copies the parsed options into the runner's, validating them (InputError naming the option).
void applyPipelineOptions(const PipelineCli& cli, pipeline::VoRunOptions& options);

// The parsed options as the library API's (threads, pins, scheduling, decoder, trace and statistics
// files); --realtime and --speed belong to the input (voca_rt::Input). The CLI's stop handlers
// become the run's stop request.
voca_rt::Options apiOptions(const PipelineCli& cli);

// The help text explaining threads, pinning, exit codes and outputs, for a command's footer.
std::string pipelineHelpFooter();

// After a run: warnings, the --profile table, and the exit code for an interrupted or failed run
// (0 when it completed; the error is printed as "voca <command>: error: ...").
int reportRunEnd(const pipeline::VoRunResult& result, const PipelineCli& cli, const std::string& command);
int reportRunEnd(const voca_rt::Summary& summary, const PipelineCli& cli, const std::string& command);

}  // namespace voca::cli
