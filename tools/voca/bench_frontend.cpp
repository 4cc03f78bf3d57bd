// `voca bench frontend`: the frontend alone through the pipeline runner, per prior mode.

#include "tools/voca/bench_frontend.h"

#include "tools/voca/pipeline_cli.h"

#include <fmt/core.h>

#include <algorithm>
#include <memory>
#include <thread>

#include "drivers/encode/video_encoder.h"
#include "formats/dataset/dataset.h"
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
constexpr double kTargetMedianMs = 4.0;

int runFrontendBench(const FrontendBenchOptions& opts) {
  if (opts.repeat < 1) throw InputError(fmt::format("--repeat: expected at least 1, got {}", opts.repeat));
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
    if (!pipeline::encodeForReplay(input, encoded->path(), encode::parseBitrate(opts.bitrate), calibration, true,
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
             "left pts", "right pts", fmt::format("target (<= {} ms)", kTargetMedianMs));
  // The repeat counter is wiped before each table row (stdout) so only the rows stay on a terminal.
  platform::ProgressLine progress;
  for (PriorMode mode : modes) {
    std::vector<double> cpu_ms, wall_ms;
    double left_points = 0.0, right_points = 0.0;
    for (int r = 0; r < opts.repeat; ++r) {
      pipeline::VoRunOptions options;
      options.input = input;
      if (!opts.calib.empty() && !encoded) options.calibration = opts.calib;
      if (!config.empty()) options.config = config;
      options.mode = mode;
      options.estimate = false;
      options.max_frames = opts.frames;
      options.max_points = opts.max_points;
      options.progress = false;
      options.pipeline.threads = 1;
      const pipeline::VoRunResult result = pipeline::runVisualOdometry(options);
      if (result.pipeline.error || result.stop_signal != 0) {
        progress.end();
        return reportRunEnd(result, PipelineCli{}, "bench");
      }
      if (r == 0 && mode == modes.front()) fmt::print("input: {}\n", result.description);
      // The first frame only detects.
      for (std::size_t k = 1; k < result.rows.size(); ++k) {
        cpu_ms.push_back(result.rows[k].frontend_cpu_ms);
        wall_ms.push_back(result.rows[k].frontend_ms);
        left_points += result.rows[k].left;
        right_points += result.rows[k].right;
      }
      progress.update("{} repeat {}/{}", priorModeName(mode), r + 1, opts.repeat);
    }
    progress.clear();
    double mean = 0.0;
    for (double v : cpu_ms) mean += v;
    const double counted = static_cast<double>(std::max<std::size_t>(1, cpu_ms.size()));
    const double median = quantile(cpu_ms, 0.5), p99 = quantile(cpu_ms, 0.99);
    const char* verdict = median > kTargetMedianMs ? "missed" : p99 > 2.0 * median ? "missed (p99)" : "met";
    fmt::print("{:<16} {:9.3f} {:9.3f} {:9.3f} {:9.3f} {:10.0f} {:10.0f}  {}\n", priorModeName(mode), median, p99,
               mean / counted, quantile(wall_ms, 0.5), left_points / counted, right_points / counted, verdict);
  }
  fmt::print("target per stereo frame on one core, every mode: median <= {} ms, p99 <= 2x median\n", kTargetMedianMs);
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
  app.add_option("--frames", opts->frames, "Use only the first N frames (0 = all)")->capture_default_str();
  app.add_option("--repeat", opts->repeat, "Runs over the sequence per mode")->capture_default_str();
  app.add_option("--max-points", opts->max_points, "Frontend capacity: points per camera")->capture_default_str();
  app.add_option("--modes", opts->modes, "Prior modes to time (space- or comma-separated)")
      ->delimiter(',')
      ->capture_default_str();
  app.footer(
      "Runs the pipeline without the backend, every stage in one thread, for each prior mode, and prints\n"
      "the frontend stage's thread CPU time per stereo frame (median, p99, mean; decoding is its own stage\n"
      "and not counted), the wall-clock median and the mean number of left/right points. The first frame\n"
      "(detection only) is not counted. Raw datasets are encoded once first.\n"
      "Without an input it measures a moving synthetic sequence (voca synth --motion aggressive --seconds 40,\n"
      "encoded at 500 kbit/s), rendered once and kept in $XDG_CACHE_HOME/voca/bench (else ~/.cache/voca/bench);\n"
      "the first call takes minutes. The target column checks median <= 4 ms and p99 <= 2x median.");
  return [opts] { return runFrontendBench(*opts); };
}

}  // namespace voca::cli
