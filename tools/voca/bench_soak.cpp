// `voca bench soak`: options, one soak run, its report.

#include "tools/voca/bench_soak.h"

#include <fmt/core.h>

#include <memory>

#include "pipeline/bench/soak_bench.h"
#include "platform/realtime/stop_signal.h"
#include "tools/voca/number_checks.h"

namespace voca::cli {

namespace {

double mib(std::int64_t bytes) { return static_cast<double>(bytes) / (1024.0 * 1024.0); }

void printReport(const pipeline::SoakReport& r, const pipeline::SoakOptions& options) {
  fmt::print("input: {}\n", r.input);
  fmt::print("{} frames in {:.1f} s ({:.1f} frames/s, paced at {:g}x real time; {} passes of {} frames; {} threads)\n",
             r.frames_in, r.wall_s, r.wall_s > 0.0 ? static_cast<double>(r.frames_in) / r.wall_s : 0.0, r.speed,
             r.passes, r.frames_per_pass, r.threads);
  fmt::print(
      "frames: {} in = {} poses written + {} dropped at the source + {} lost until the next keyframe + {} dropped "
      "by the live policy + {} damaged{}\n",
      r.frames_in, r.written, r.dropped_at_source, r.skipped_to_keyframe, r.dropped_live, r.damaged,
      r.unaccounted == 0 ? "" : fmt::format(" ({} UNACCOUNTED)", r.unaccounted));
  fmt::print("  {} packets damaged by the source; {} tracker resets (loop seams and losses)\n", r.damaged_packets,
             r.tracker_resets);
  fmt::print(
      "RSS: {:.2f} MiB at frame {} (end of the warm-up), {:.2f} MiB at the end, peak {:.2f} MiB after the "
      "warm-up: growth {:+.3f} MiB (target < {:.0f} MiB), of which anonymous memory {:+.3f} MiB (the rest: pages "
      "of the program and its libraries first used)\n",
      mib(r.rss_at_warmup), options.warmup, mib(r.rss_at_end), mib(r.rss_peak_after_warmup), mib(r.rss_growth),
      mib(pipeline::kSoakMaxRssGrowthBytes), mib(r.anonymous_growth));
  fmt::print(
      "allocations (operator new, whole process) over the steady state: {} in {} frames, {:.4f} per frame "
      "(target 0)\n",
      r.steady_allocations, r.steady_frames, r.allocations_per_frame);
  fmt::print("queue high-water marks (frames waiting in front of each stage):");
  for (const pipeline::SoakStage& stage : r.stages) fmt::print(" {} {}", stage.name, stage.queue_high_water);
  fmt::print("\ntrajectory: {}\n", r.trajectory_file.string());
}

int runSoakBench(const pipeline::SoakOptions& cli, const std::string& json) {
  platform::installStopHandlers();
  pipeline::SoakOptions options = cli;
  options.stop_requested = platform::stopRequested;
  const pipeline::SoakReport report = pipeline::runSoak(options);
  if (!json.empty()) pipeline::writeSoakJson(report, json);
  if (report.stopped && report.frames_in == 0) return platform::interruptedExitCode(platform::stopSignal());
  printReport(report, options);
  if (report.stopped) {
    fmt::print(stderr, "voca bench soak: stopped after {} of {} frames; targets not judged\n", report.frames_in,
               options.frames);
    return platform::interruptedExitCode(platform::stopSignal());
  }
  for (const std::string& failure : report.failures) fmt::print(stderr, "voca bench soak: FAILED: {}\n", failure);
  if (!report.failures.empty()) return 1;
  fmt::print("soak passed: every frame accounted for, RSS growth below {:.0f} MiB, no allocation per frame\n",
             mib(pipeline::kSoakMaxRssGrowthBytes));
  return 0;
}

}  // namespace

Runner configureSoakBench(CLI::App& app) {
  auto options = std::make_shared<pipeline::SoakOptions>();
  auto json = std::make_shared<std::string>();
  app.add_option("--frames", options->frames, "Frames the source gives out in all (72000: an hour at 20 Hz)")
      ->capture_default_str()
      ->check(positiveNumber());
  app.add_option("--warmup", options->warmup, "Frames before memory and allocations are measured")
      ->capture_default_str()
      ->check(nonNegativeNumber());
  app.add_option("--drop-rate", options->drop_rate,
                 "Chance per frame that the source drops it (it then resumes at the next keyframe)")
      ->capture_default_str();
  app.add_option("--damage-rate", options->damage_rate,
                 "Chance per frame that one camera's packet has its slice data overwritten with noise")
      ->capture_default_str();
  app.add_option("--seed", options->seed, "Seed of the drops and the damage")->capture_default_str();
  app.add_option("--speed", options->speed, "Replay at this multiple of the recording's real time")
      ->capture_default_str()
      ->check(positiveNumber());
  app.add_option("--input", options->input,
                 "Dataset folder to loop (raw datasets are encoded with a 1 s GOP first); default: a built-in 3 s "
                 "synthetic sequence");
  app.add_option("--trajectory", options->trajectory_file,
                 "Write the poses here (TUM); default: a scratch file, removed at the end");
  app.add_option("--stall-timeout", options->stall_timeout_s,
                 "Seconds without a frame written that count as a deadlock")
      ->capture_default_str()
      ->check(positiveNumber());
  app.add_option("--json", *json, "Also write the report as JSON to this file");
  app.footer(
      "Runs the live pipeline (`voca run --realtime`: staged threads, live policy, decode, frontend, backend,\n"
      "trajectory file) on a short recording replayed over and over with increasing timestamps at --speed\n"
      "times real time. The source drops frames (--drop-rate) and damages packets (--damage-rate) at random,\n"
      "seeded; the decoder recovers at the next keyframe. The loop seam may make the tracker reset.\n"
      "Reports RSS every 1000 frames, operator new calls over the frames after --warmup (process-wide),\n"
      "each stage's queue high-water mark, and where every frame went: frames in = poses written + dropped\n"
      "or lost at the source + dropped by the live policy + damaged.\n"
      "Exits 1 naming each target missed: RSS growth after the warm-up >= 1 MiB, any allocation in the\n"
      "steady state, a frame unaccounted for, no pose written, a stage failure, or a deadlock (no frame\n"
      "written for --stall-timeout s; exit 3 when the pipeline does not stop either).");
  return [options, json] { return runSoakBench(*options, *json); };
}

}  // namespace voca::cli
