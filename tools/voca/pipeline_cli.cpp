#include "tools/voca/pipeline_cli.h"

#include <fmt/core.h>

#include <charconv>

#include "pipeline/runtime/chrome_trace.h"
#include "platform/realtime/stop_signal.h"
#include "voca/core/error.h"

namespace voca::cli {

void addPipelineOptions(CLI::App& app, PipelineCli& cli) {
  app.add_option("--threads", cli.threads,
                 "Threads: auto (one per stage), 1 (every stage in one thread), or N (stages grouped in order)")
      ->capture_default_str();
  app.add_option("--frontend-threads", cli.frontend_threads,
                 "Threads the frontend tracks the two cameras on: auto (2 when the stages have threads of their\n"
                 "own, no --pin or one naming frontend.helper, and two or more cores), 1, or 2 (a helper thread\n"
                 "tracks the right camera and the left camera's last points, about half of all; same results)")
      ->capture_default_str();
  app.add_option("--pin", cli.pin,
                 "Stage-to-core map, e.g. decode:0,frontend:0,backend:1 (stages: read, decode, frontend, backend,\n"
                 "write; frontend.helper: the frontend's helper thread, which otherwise shares the frontend's core)");
  app.add_option("--sched", cli.scheduling, "Scheduling class of the pipeline threads: other, fifo or rr")
      ->capture_default_str();
  app.add_option("--priority", cli.priority, "Real-time priority for --sched fifo|rr (1-99)")->capture_default_str();
  app.add_flag("--mlock", cli.lock_memory, "Lock the process's memory in RAM (mlockall)");
  app.add_flag("--realtime", cli.realtime,
               "Replay at the recording's own rate, as a camera delivers frames; a stage that falls behind drops the "
               "oldest waiting frame (counted) instead of making the source wait");
  app.add_option("--speed", cli.speed, "With --realtime: playback speed factor")->capture_default_str();
  app.add_flag("--strict", cli.strict, "Stop at the first damaged frame instead of skipping it");
  app.add_option("--decoder", cli.decoder, "Decoder: auto, software, vaapi or v4l2m2m")->capture_default_str();
  app.add_flag("--skip-deblock", cli.skip_deblock,
               "Software decoding: skip H.264's deblocking filter (about a fifth faster; the pictures differ from\n"
               "the encoder's until the next I-frame, the motion vectors do not)");
  app.add_flag("--profile", cli.profile, "Print p50/p90/p99/max latency per stage and end to end, queues and drops");
  app.add_option("--trace", cli.trace, "Write a Chrome trace-event JSON of every frame's stages (open in Perfetto)");
  app.add_option("--stats", cli.stats,
                 "Write statistics JSON: totals, per-stage latency, skipped frames, one row per frame");
}

pipeline::RunSettings runSettings(const PipelineCli& cli) {
  pipeline::RunSettings settings;
  if (cli.threads != "auto") {
    int threads = 0;
    const auto [end, ec] = std::from_chars(cli.threads.data(), cli.threads.data() + cli.threads.size(), threads);
    if (ec != std::errc{} || end != cli.threads.data() + cli.threads.size() || threads < 1) {
      throw InputError(fmt::format("--threads: expected auto or a positive count, got \"{}\"", cli.threads));
    }
    settings.threads = threads;
  }
  if (cli.frontend_threads == "1" || cli.frontend_threads == "2") {
    settings.frontend_threads = cli.frontend_threads[0] - '0';
  } else if (cli.frontend_threads != "auto") {
    throw InputError(fmt::format("--frontend-threads: expected auto, 1 or 2, got \"{}\"", cli.frontend_threads));
  }
  settings.pins = cli.pin;
  settings.scheduling = cli.scheduling;
  settings.priority = cli.priority;
  settings.lock_memory = cli.lock_memory;
  settings.realtime = cli.realtime;
  settings.speed = cli.speed;
  settings.strict = cli.strict;
  settings.decoder = cli.decoder;
  settings.skip_deblock = cli.skip_deblock;
  settings.trace_file = cli.trace;
  settings.statistics_file = cli.stats;
  return settings;
}

void applyPipelineOptions(const PipelineCli& cli, pipeline::VoRunOptions& options) {
  pipeline::applyRunSettings(runSettings(cli), options);
}

voca_rt::Options apiOptions(const PipelineCli& cli) {
  const pipeline::RunSettings settings = runSettings(cli);
  voca_rt::Options options;
  options.threads = settings.threads;
  options.frontend_threads = settings.frontend_threads;
  options.pins = settings.pins;
  options.scheduling = settings.scheduling;
  options.priority = settings.priority;
  options.lock_memory = settings.lock_memory;
  options.strict = settings.strict;
  options.decoder = settings.decoder;
  options.skip_deblock = settings.skip_deblock;
  options.trace_file = settings.trace_file;
  options.statistics_file = settings.statistics_file;
  options.progress = true;
  options.stop_requested = platform::stopRequested;
  return options;
}

std::string pipelineHelpFooter() {
  return "Pipeline: read -> decode (video input) -> frontend -> backend -> write, each stage on its own thread by\n"
         "default, connected by bounded lock-free queues; --threads 1 runs them all in one thread and writes a\n"
         "byte-identical trajectory. With threads per stage the frontend shares its points with a helper thread\n"
         "(the right camera and the left camera's last points; --frontend-threads). --pin maps stages to\n"
         "cores (as taskset counts them); --sched fifo|rr with\n"
         "--priority and --mlock need CAP_SYS_NICE / a memlock limit, and warn once and go on when refused.\n"
         "Offline replay never drops a frame; --realtime paces the input at its timestamps and drops the\n"
         "oldest waiting frame when the frontend falls behind (every drop is counted and listed).\n"
         "A damaged frame (video data that cannot be decoded; an image file that cannot be read, which a\n"
         "warning names) is skipped and listed (--strict stops instead), and so are the video frames\n"
         "predicted from it up to the next I-picture (they carry the decoder's concealment along). Poses are\n"
         "written and flushed as they are estimated.\n"
         "Exit codes: 0 done; 1 bad input, a stage failed, or no pose was estimated (every frame lost; what\n"
         "was written stays); 2 a command line that does not parse (an unknown option, a missing value);\n"
         "130 stopped by SIGINT (Ctrl-C), 143 by SIGTERM, 129 by SIGHUP (the terminal closed), after writing\n"
         "everything estimated so far; a second signal exits at once.";
}

int reportRunEnd(const pipeline::VoRunResult& result, const PipelineCli& cli, const std::string& command) {
  for (const std::string& warning : result.warnings) fmt::print(stderr, "warning: {}\n", warning);
  if (cli.profile) pipeline::printLatencyReport(result.pipeline_report, stdout);
  // Named only when written: a run stopped before its first frame has no trace.
  if (!cli.trace.empty() && std::filesystem::exists(cli.trace)) {
    fmt::print("trace: {} (open in https://ui.perfetto.dev)\n", cli.trace);
  }
  if (!cli.stats.empty() && std::filesystem::exists(cli.stats)) fmt::print("statistics: {}\n", cli.stats);
  if (result.pipeline_report.error) {
    const pipeline::StageError& e = *result.pipeline_report.error;
    fmt::print(stderr, "voca {}: error: {} stage failed{}: {}\n", command, e.stage,
               e.frame_index >= 0 ? fmt::format(" at frame {}", e.frame_index) : std::string(), e.message);
    return 1;
  }
  if (!result.failure.empty()) {
    fmt::print(stderr, "voca {}: error: {}\n", command, result.failure);
    return 1;
  }
  if (result.stop_signal != 0) {
    fmt::print(stderr, "voca {}: stopped by signal {} after {} frames; outputs hold everything processed\n", command,
               result.stop_signal, result.frames);
    return platform::interruptedExitCode(result.stop_signal);
  }
  return 0;
}

}  // namespace voca::cli

namespace voca::cli {

int reportRunEnd(const voca_rt::Summary& summary, const PipelineCli& cli, const std::string& command) {
  for (const std::string& warning : summary.warnings) fmt::print(stderr, "warning: {}\n", warning);
  if (cli.profile) std::fputs(summary.latency_report.c_str(), stdout);
  // Named only when written: a run stopped before its first frame has no trace.
  if (!cli.trace.empty() && std::filesystem::exists(cli.trace)) {
    fmt::print("trace: {} (open in https://ui.perfetto.dev)\n", cli.trace);
  }
  if (!cli.stats.empty() && std::filesystem::exists(cli.stats)) fmt::print("statistics: {}\n", cli.stats);
  if (!summary.error.empty()) {
    fmt::print(stderr, "voca {}: error: {}\n", command, summary.error);
    return 1;
  }
  if (!summary.failure.empty()) {
    fmt::print(stderr, "voca {}: error: {}\n", command, summary.failure);
    return 1;
  }
  if (summary.stop_signal != 0) {
    fmt::print(stderr, "voca {}: stopped by signal {} after {} frames; outputs hold everything processed\n", command,
               summary.stop_signal, summary.frames);
    return platform::interruptedExitCode(summary.stop_signal);
  }
  return 0;
}

}  // namespace voca::cli
