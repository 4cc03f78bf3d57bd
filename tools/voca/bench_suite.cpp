// `voca bench suite` and `voca bench collect`: options and printing; the work is in pipeline/harness.

#include "tools/voca/bench_suite.h"

#include <fmt/core.h>

#include <memory>
#include <string>

#include "pipeline/harness/collect_results.h"
#include "pipeline/harness/run_suite.h"
#include "pipeline/harness/suite.h"
#include "platform/process/child_process.h"
#include "platform/realtime/stop_signal.h"
#include "voca/core/error.h"

namespace voca::cli {

namespace {

struct SuiteOptions {
  std::string suite_file, out;
  int jobs = 1;
  std::string emit_jobs;
  bool retry_failed = false;
};

void printWritten(const std::vector<std::filesystem::path>& files, const std::filesystem::path& out) {
  fmt::print("tables: {}/tables/<bitrate>.{{md,csv,tex}}, summary: {}/summary.md, all runs: {}/results.csv\n",
             out.string(), out.string(), out.string());
  fmt::print("({} files; plots: tools/plot_suite.py {})\n", files.size(), out.string());
}

int runSuiteCommand(const SuiteOptions& o) {
  if (o.jobs < 1) throw InputError(fmt::format("--jobs {}: expected 1 or more", o.jobs));
  const harness::Suite suite = harness::loadSuite(o.suite_file);
  const std::filesystem::path out = std::filesystem::absolute(o.out);
  const std::string voca = platform::currentExecutable().string();
  const harness::SuitePlan plan = harness::planSuite(suite, out, voca);

  if (!o.emit_jobs.empty()) {
    // The suite file goes into the folder now, so `voca bench collect` finds it after the jobs ran.
    harness::writeSuiteFile(suite, out);
    if (o.emit_jobs == "synth") {
      for (const harness::Job& job : plan.synth) fmt::print("{}\n", harness::shellCommand(job.argv));
    } else if (o.emit_jobs == "encode") {
      for (const harness::Job& job : plan.encodes) fmt::print("{}\n", harness::shellCommand(job.argv));
    } else {
      for (const harness::PlannedRun& run : plan.runs) {
        std::filesystem::create_directories(run.job.output);
        fmt::print("{}\n", harness::shellCommand(run.job.argv));
      }
    }
    return 0;
  }

  platform::installStopHandlers();
  harness::SuiteRunOptions options;
  options.jobs = o.jobs;
  options.retry_failed = o.retry_failed;
  options.stop_requested = platform::stopRequested;
  const harness::SuiteRunReport report = harness::runSuite(suite, plan, out, options);
  const auto files = harness::collectResults(out, voca);
  fmt::print("suite {}: {} runs, {} done before, {} run now, {} failed{}\n", suite.name, report.total, report.skipped,
             report.ran, report.failed, report.stopped ? " (stopped: call again to resume)" : "");
  printWritten(files, out);
  if (report.stopped) return platform::interruptedExitCode(platform::stopSignal());
  if (report.ran > 0 && report.failed == report.ran) {
    // Single failures are results (x in the tables); all of them is a broken setup.
    fmt::print(stderr, "error: every run of this call failed; the first: {}\n", report.first_failure);
    return 1;
  }
  return 0;
}

}  // namespace

Runner configureSuiteBench(CLI::App& app) {
  auto o = std::make_shared<SuiteOptions>();
  app.add_option("suite", o->suite_file, "Suite file (JSON; e.g. configs/bench_suite_default.json)")->required();
  app.add_option("--out,-o", o->out, "Output folder: encodings, runs, tables (a second call resumes)")->required();
  app.add_option("--jobs,-j", o->jobs, "Runs at a time, each its own `voca` process")->capture_default_str();
  app.add_option("--emit-jobs", o->emit_jobs,
                 "Print one stage's jobs instead of running them, one complete command line each, independent of "
                 "each other: 'synth' (renderings), then 'encode' (encodings), then 'run' (the runs)")
      ->check(CLI::IsMember({"synth", "encode", "run"}));
  app.add_flag("--retry-failed", o->retry_failed, "Run again what an earlier call recorded as failed");
  app.footer(
      "A suite names sequences (dataset folders, VOCA video folders or `voca synth` arguments), bitrates\n"
      "(raw, 250k, 500k, 1000k, 5000k ...), prior modes, I-frame bridging on/off and configs, plus\n"
      "trajectories of other systems to compare with. Every video is encoded once into <out>/videos;\n"
      "each run is a child `voca run` writing <out>/runs/<id>/{trajectory.txt,stats.json,log.txt,\n"
      "result.json}. A run that crashes or fails is recorded as x and the suite goes on (exit code 1\n"
      "when every run of the call failed); a second call skips what is done. Tables follow the paper's\n"
      "rules: <out>/tables/<bitrate>.{md,csv,tex}, <out>/summary.md, with each prior mode against\n"
      "`none` (also <out>/against_none.csv). With \"repeats\": N each VOCA-RT cell is the median of N\n"
      "runs tracking from frames 0, s, 2s ... (s = \"repeat_step_frames\", default 5), since one run's\n"
      "error depends on its luck. Cluster: --emit-jobs synth, then encode, then run, each | parallel\n"
      "(or a Slurm array), then `voca bench collect <out>`. Ctrl-C stops after the running runs; call\n"
      "again.");
  return [o] { return runSuiteCommand(*o); };
}

Runner configureCollectBench(CLI::App& app) {
  auto out = std::make_shared<std::string>();
  app.add_option("dir", *out, "Suite output folder (with suite.json, as --out or --emit-jobs made it)")->required();
  app.footer(
      "Merges the results of runs made elsewhere (a cluster sharing the folder, or an interrupted suite)\n"
      "into the tables: runs with outputs but no result.json are summarised; runs without outputs are\n"
      "shown as ? (no result yet), failed runs as x.");
  return [out] {
    const std::filesystem::path dir = std::filesystem::absolute(*out);
    printWritten(harness::collectResults(dir, platform::currentExecutable().string()), dir);
    return 0;
  };
}

}  // namespace voca::cli
