// `voca bench frontend`: the frontend alone through the pipeline runner, per prior mode.

#include "tools/voca/bench_frontend.h"
#include "tools/voca/bench_budget.h"

#include "tools/voca/number_checks.h"
#include "tools/voca/pipeline_cli.h"

#include <fmt/core.h>
#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <numeric>
#include <thread>

#include "drivers/encode/dataset_encoder.h"
#include "drivers/encode/video_encoder.h"
#include "formats/dataset/dataset.h"
#include "pipeline/bench/frontend_bench.h"
#include "pipeline/harness/bench_sequence.h"
#include "pipeline/vo/vo_runner.h"
#include "platform/filesystem/temp_dir.h"
#include "platform/machine/cpu_info.h"
#include "platform/realtime/stop_signal.h"
#include "platform/terminal/progress_line.h"
#include "voca/core/error.h"
#include "voca/core/quantile.h"
#include "voca/frontend/patch_kernels_avx2.h"
#include "voca/frontend/simd4.h"

namespace voca::cli {

namespace {

struct FrontendBenchOptions {
  std::string input;
  std::string synth = "euroc";
  std::string calib;
  std::string config;
  std::string bitrate = "500k";
  int frames = 0;
  int repeat = 3;
  int max_points = 1000;
  std::vector<std::string> modes = [] {
    std::vector<std::string> names;
    for (PriorMode mode : kAllPriorModes) names.emplace_back(priorModeName(mode));
    return names;
  }();
};

// The frontend budget per stereo frame on one core, on the moving sequences.
constexpr double kFrontendTargetMedianMs = 4.0;

int runFrontendBench(const FrontendBenchOptions& opts) {
  std::vector<PriorMode> modes;
  for (const std::string& name : opts.modes) modes.push_back(requirePriorMode(name, "--modes"));
  platform::installStopHandlers();

  // No input: the cached moving sequence, generated on first use.
  std::filesystem::path input = opts.input;
  std::string config = opts.config;
  if (input.empty()) {
    harness::BenchSequenceSpec spec;
    spec.camera = opts.synth;
    const std::optional<std::filesystem::path> cached =
        harness::ensureBenchSequence(spec, harness::benchCacheRoot(), true, platform::stopRequested);
    if (!cached) return platform::interruptedExitCode(platform::stopSignal());
    input = *cached;
    if (config.empty()) config = harness::benchSequenceConfig(spec);
    fmt::print("sequence: {}\n", harness::describeBenchSequence(spec));
  }
  // Raw datasets are encoded once, so every mode and repeat tracks the same decoded frames.
  std::optional<TempDir> encoded;
  if (openDataset(input).layout != DatasetLayout::kVocaVideo) {
    encoded.emplace("voca-bench");
    const std::optional<std::filesystem::path> calibration =
        opts.calib.empty() ? std::nullopt : std::optional<std::filesystem::path>(opts.calib);
    if (!encode::encodeForReplay(input, encoded->path(), encode::parseBitrate(opts.bitrate), calibration, true,
                                 platform::stopRequested)) {
      return platform::interruptedExitCode(platform::stopSignal());
    }
    input = encoded->path();
  }

  fmt::print(
      "machine: {} ({} hardware threads, KLT kernels: {}); frontend on one thread, thread CPU time per "
      "stereo frame\n",
      platform::cpuModel(), std::thread::hardware_concurrency(),
      patch_kernels::avx2Available() ? fmt::format("{}, warped sampling avx2", simd4::Native::kName)
                                     : std::string(simd4::Native::kName));
  fmt::print("{:<16} {:>9} {:>9} {:>9} {:>9} {:>10} {:>10}  {}\n", "mode", "median ms", "p99 ms", "mean ms", "wall p50",
             "left pts", "right pts", fmt::format("target (<= {} ms)", kFrontendTargetMedianMs));
  // The repeat counter is wiped before each table row (stdout) so only the rows stay on a terminal.
  platform::ProgressLine progress;
  for (PriorMode mode : modes) {
    pipeline::VoRunOptions options;
    options.input = input;
    if (!opts.calib.empty() && !encoded) options.calibration = opts.calib;
    if (!config.empty()) options.config = config;
    options.mode = mode;
    options.max_frames = opts.frames;
    options.max_points = opts.max_points;
    const pipeline::FrontendTimingOutcome outcome = pipeline::timeFrontend(options, opts.repeat, [&](int run) {
      progress.update("{} repeat {}/{}", priorModeName(mode), run + 1, opts.repeat);
    });
    if (outcome.ended_early) {
      progress.end();
      return reportRunEnd(*outcome.ended_early, PipelineCli{}, "bench");
    }
    progress.clear();
    const pipeline::FrontendTiming& timing = outcome.timing;
    if (mode == modes.front()) fmt::print("input: {}\n", timing.description);
    const double median = quantile(timing.cpu_ms, 0.5), p99 = quantile(timing.cpu_ms, 0.99);
    const char* verdict = budgetVerdict(median, p99, kFrontendTargetMedianMs);
    const double mean =
        std::accumulate(timing.cpu_ms.begin(), timing.cpu_ms.end(), 0.0) / static_cast<double>(timing.cpu_ms.size());
    fmt::print("{:<16} {:9.3f} {:9.3f} {:9.3f} {:9.3f} {:10.0f} {:10.0f}  {}\n", priorModeName(mode), median, p99, mean,
               quantile(timing.wall_ms, 0.5), timing.mean_left_points, timing.mean_right_points, verdict);
    if (timing.run_median_ms.size() > 1) {
      fmt::print("  each run's own median: {:.3f} ms\n", fmt::join(timing.run_median_ms, ", "));
    }
  }
  fmt::print("target per stereo frame on one core, every mode: median <= {} ms, p99 <= 2x median\n",
             kFrontendTargetMedianMs);
  return 0;
}

}  // namespace

Runner configureFrontendBench(CLI::App& app) {
  auto opts = std::make_shared<FrontendBenchOptions>();
  app.add_option("input", opts->input,
                 "Raw dataset (EuRoC/TUM-VI/KITTI folder) or VOCA video folder (default: the cached moving "
                 "synthetic sequence, see --synth)");
  app.add_option("--synth", opts->synth,
                 "Without an input: the moving sequence of this camera, euroc (752x480) or tumvi (512x512)")
      ->capture_default_str()
      ->check(CLI::IsMember({"euroc", "tumvi"}));
  app.add_option("--calib", opts->calib, "Calibration file (default: the one found with the dataset)");
  app.add_option("--config", opts->config,
                 "Config JSON file, or a shipped config by name: euroc, tumvi, kitti (default: euroc; without an "
                 "input: the --synth camera's)");
  app.add_option("--bitrate", opts->bitrate, "Raw datasets are encoded at this rate first to get motion vectors")
      ->capture_default_str();
  app.add_option("--frames", opts->frames, "Use only the first N frames (0 = all)")
      ->capture_default_str()
      ->check(nonNegativeNumber());
  app.add_option("--repeat", opts->repeat,
                 "Runs over the sequence per mode; each frame's time is the median of its runs")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  app.add_option("--max-points", opts->max_points, "Frontend capacity: points per camera")->capture_default_str();
  app.add_option("--modes", opts->modes, "Prior modes to time (space- or comma-separated)")
      ->delimiter(',')
      ->capture_default_str();
  app.footer(
      "Runs the pipeline without the backend, every stage in one thread, for each prior mode, and prints\n"
      "the frontend stage's thread CPU time per stereo frame (median, p99, mean; decoding is its own stage\n"
      "and not counted), the wall-clock median and the mean number of left/right points. The first frame\n"
      "(detection only) is not counted. Raw datasets are encoded once first. Each mode runs --repeat times\n"
      "over the same frames (the frontend is deterministic: a run that tracks other points is an error);\n"
      "each frame's time is the median of its runs, and each run's own median is printed below the row.\n"
      "Without an input it measures a moving synthetic sequence (voca synth --motion aggressive --seconds 40,\n"
      "encoded at 500 kbit/s), rendered once and kept in $XDG_CACHE_HOME/voca/bench (else ~/.cache/voca/bench);\n"
      "the first call takes minutes. The target column checks median <= 4 ms and p99 <= 2x median.");
  return [opts] { return runFrontendBench(*opts); };
}

}  // namespace voca::cli
