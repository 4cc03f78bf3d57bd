// `voca profile`: summarises a latency trace written by `--trace` the way `--profile` prints a run.

#include <fmt/core.h>

#include <memory>
#include <string>

#include "pipeline/runtime/chrome_trace.h"
#include "tools/voca/command.h"

namespace {

using voca::cli::Runner;

const bool profile_command_registered = voca::cli::registerCommand({
    .name = "profile",
    .summary = "Summarise a saved latency trace (--trace) per stage: p50/p90/p99/max, queues, drops",
    .order = 75,
    .configure = [](CLI::App& app) -> Runner {
      auto trace = std::make_shared<std::string>();
      app.add_option("trace", *trace, "Chrome trace-event JSON written by voca run/track --trace")->required();
      app.footer(
          "Prints the same table as --profile: for each stage the time it worked on a frame (p50, p90, p99, max),\n"
          "the time frames waited in its input queue (wait50, wait99), its thread CPU time (cpu50), its thread\n"
          "and core, its queue's high-water mark and the frames dropped or skipped there; then end to end, from\n"
          "a frame's arrival to the end of the last stage. A trace cut off by a killed run is read as far as it\n"
          "goes. Open the file itself in https://ui.perfetto.dev for the timeline.");
      return [trace] {
        bool complete = true;
        const voca::pipeline::RunReport report = voca::pipeline::readTraceReport(*trace, &complete);
        voca::pipeline::printLatencyReport(report, stdout);
        if (!complete) {
          fmt::print(
              "note: the trace ends without its summary (the run was killed): the figures cover the frames it "
              "holds; queue high-water marks are unknown (0)\n");
        }
        return 0;
      };
    },
});

}  // namespace
