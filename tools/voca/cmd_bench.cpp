// `voca bench <mode>`: throughput measurements on this machine, and evaluation suites. Each mode is one entry of kModes
// below (a name, a summary and a configure function declaring its options), so a new mode is one
// function plus one row.

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "tools/voca/bench_backend.h"
#include "tools/voca/bench_decode.h"
#include "tools/voca/bench_frontend.h"
#include "tools/voca/bench_pipeline.h"
#include "tools/voca/bench_soak.h"
#include "tools/voca/bench_suite.h"
#include "tools/voca/command.h"

namespace {

using voca::cli::Runner;

// One `voca bench` sub-mode.
struct BenchMode {
  const char* name;
  const char* summary;
  std::function<Runner(CLI::App&)> configure;
};

const std::vector<BenchMode>& benchModes() {
  static const std::vector<BenchMode> modes = {
      {"decode", "Decoder CPU time per stereo frame: full decode with/without MV export, MV-only parse",
       voca::cli::configureDecodeBench},
      {"frontend", "Frontend CPU time per stereo frame for each prior mode", voca::cli::configureFrontendBench},
      {"pipeline", "Whole-pipeline frames/s offline (1 thread vs staged), latency at real rate, peak memory",
       voca::cli::configurePipelineBench},
      {"soak", "The live pipeline for an hour of frames on a looping, lossy source: RSS, allocations, queues, frames",
       voca::cli::configureSoakBench},
      {"backend", "Estimator cost per frame on the tracks of a moving sequence (or --synthetic observations)",
       voca::cli::configureBackendBench},
      {"suite", "Evaluation suite: sequences x bitrates x modes -> the paper's tables (resumable, --jobs, cluster)",
       voca::cli::configureSuiteBench},
      {"collect", "Tables from a suite folder whose runs ran elsewhere (--emit-jobs on a cluster)",
       voca::cli::configureCollectBench},
  };
  return modes;
}

const bool bench_command_registered = voca::cli::registerCommand({
    .name = "bench",
    .summary = "Measure throughput of pipeline stages, or run evaluation suites for the paper's tables",
    .order = 70,
    .configure = [](CLI::App& app) -> Runner {
      app.require_subcommand(1);
      auto runners = std::make_shared<std::vector<std::pair<CLI::App*, Runner>>>();
      for (const BenchMode& mode : benchModes()) {
        CLI::App* sub = app.add_subcommand(mode.name, mode.summary);
        runners->emplace_back(sub, mode.configure(*sub));
      }
      return [runners] {
        for (auto& [sub, run] : *runners) {
          if (sub->parsed()) return run();
        }
        return 1;
      };
    },
});

}  // namespace
