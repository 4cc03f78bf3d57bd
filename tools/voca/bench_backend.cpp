// `voca bench backend`: the estimator alone, timed per stereo frame on this thread's CPU clock, on
// the frontend's real tracks of a moving sequence (default) or on synthetic observations.

#include "tools/voca/bench_backend.h"
#include "tools/voca/bench_budget.h"

#include <fmt/core.h>
#include <fmt/format.h>

#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "pipeline/bench/backend_bench.h"
#include "pipeline/harness/bench_sequence.h"
#include "platform/machine/cpu_info.h"
#include "platform/realtime/stop_signal.h"
#include "tools/voca/number_checks.h"
#include "voca/backend/estimator.h"
#include "voca/backend/synthetic.h"
#include "voca/core/error.h"
#include "voca/core/quantile.h"
#include "voca/frontend/frontend_config.h"
#include "voca/synth/rigs.h"

namespace voca::cli {

namespace {

constexpr double kBackendTargetMedianMs = 4.0;  // per stereo frame on one core

struct BackendBenchOptions {
  std::string input;            // dataset or video folder; empty: the cached moving sequence
  std::string synth = "euroc";  // which cached sequence
  std::string calib, config, mode{priorModeName(PriorMode::kMvParallelOf)};
  int frames = 0;
  int warmup = 40;
  int repeat = 3;  // --repeat, as in the other benches
  bool synthetic = false;
  // --synthetic
  double seconds = 60.0;
  int points = 200;
  double noise_px = 0.5;
  double motion = 1.0;
  int keyframes = 7;
  std::string rig = "euroc";
};

void printTiming(const pipeline::EstimatorTiming& t) {
  const double median = voca::median(t.cpu_ms), p99 = quantile(t.cpu_ms, 0.99);
  fmt::print("  measured frames {} (after {} warm-up), keyframes {} ({:.1f} in the window on average), resets {}\n",
             t.measured, t.warmup, t.keyframes, t.mean_window_keyframes, t.resets);
  fmt::print("  tracked points per frame {:.0f} (left), inlier observations per frame {:.0f}\n", t.mean_left_points,
             t.mean_inliers);
  fmt::print(
      "  LM iterations per frame {:.2f}, window linearisations per frame {:.2f}, cost passes per frame {:.2f}, "
      "pose-only steps per frame {:.2f}\n",
      t.mean_lm_iterations, t.mean_linearizations, t.mean_cost_passes, t.mean_pose_iterations);
  fmt::print("  CPU time per frame{}: median {:.3f} ms, p90 {:.3f} ms, p99 {:.3f} ms, max {:.3f} ms\n",
             t.run_median_ms.size() > 1 ? fmt::format(" (each frame's median of {} runs)", t.run_median_ms.size()) : "",
             median, quantile(t.cpu_ms, 0.9), p99, quantile(t.cpu_ms, 1.0));
  if (t.run_median_ms.size() > 1) fmt::print("  each run's own median: {:.3f} ms\n", fmt::join(t.run_median_ms, ", "));
  const char* verdict = budgetVerdict(median, p99, kBackendTargetMedianMs);
  fmt::print("  target per stereo frame on one core: median <= {} ms, p99 <= 2x median: {}\n", kBackendTargetMedianMs,
             verdict);
}

int runSyntheticBench(const BackendBenchOptions& opts) {
  const auto rig = synth::builtinRig(opts.rig);
  if (!rig) throw InputError("--rig: expected euroc or tumvi, got \"" + opts.rig + "\"");
  if (opts.seconds < 5.0) throw InputError("--seconds: expected at least 5");
  if (opts.points < 20) throw InputError("--points: expected at least 20");
  SyntheticObservationsConfig sc;
  sc.duration_s = opts.seconds;
  sc.max_points_per_frame = opts.points;
  sc.noise_px = opts.noise_px;
  sc.motion_scale = opts.motion;
  const SyntheticObservations seq = makeSyntheticObservations(*rig, sc);
  BackendConfig config;
  config.max_keyframes = opts.keyframes;
  validateBackendConfig(config, "--keyframes");
  fmt::print(
      "backend on synthetic observations ({} rig, {:.0f} s at 20 fps, {:.2f} px noise, motion x{:.1f}), one thread\n",
      opts.rig, opts.seconds, opts.noise_px, opts.motion);
  printTiming(pipeline::timeEstimator(seq.frames, *rig, config, static_cast<std::size_t>(opts.warmup), opts.repeat));
  return 0;
}

int runTrackBench(const BackendBenchOptions& opts) {
  platform::installStopHandlers();
  pipeline::VoRunOptions run;
  run.progress = false;
  run.max_frames = opts.frames;
  run.mode = requirePriorMode(opts.mode, "--mode");
  if (!opts.calib.empty()) run.calibration = opts.calib;
  if (!opts.config.empty()) run.config = opts.config;
  std::string description;
  if (opts.input.empty()) {
    harness::BenchSequenceSpec spec;
    spec.camera = opts.synth;
    const std::optional<std::filesystem::path> cached =
        harness::ensureBenchSequence(spec, harness::benchCacheRoot(), true, platform::stopRequested);
    if (!cached) return platform::interruptedExitCode(platform::stopSignal());
    run.input = *cached;
    if (opts.config.empty()) run.config = harness::benchSequenceConfig(spec);
    description = harness::describeBenchSequence(spec);
  } else {
    run.input = opts.input;
  }
  fmt::print(stderr, "recording the frontend's tracks ({} mode)...\n", opts.mode);
  const std::optional<pipeline::TrackRecording> recording = pipeline::recordFrontendTracks(run);
  if (!recording) return platform::interruptedExitCode(platform::stopSignal());
  if (description.empty()) description = recording->description;
  fmt::print("machine: {} ({} hardware threads)\n", platform::cpuModel(), std::thread::hardware_concurrency());
  fmt::print("backend on the frontend's tracks ({} mode, config {}), one thread: {}\n", opts.mode,
             run.config ? run.config->string() : "euroc", description);
  printTiming(pipeline::timeEstimator(recording->frames, recording->rig, recording->config.backend,
                                      static_cast<std::size_t>(opts.warmup), opts.repeat));
  return 0;
}

}  // namespace

Runner configureBackendBench(CLI::App& app) {
  auto opts = std::make_shared<BackendBenchOptions>();
  app.add_option("input", opts->input,
                 "Raw dataset or VOCA video folder whose tracks feed the estimator (default: the cached moving "
                 "synthetic sequence, see --synth)");
  app.add_option("--synth", opts->synth, "Cached moving sequence without an input: euroc (752x480) or tumvi (512x512)")
      ->capture_default_str();
  app.add_option("--calib", opts->calib, "Calibration file (default: the one found with the input)");
  app.add_option("--config", opts->config,
                 "Config JSON file or shipped name: euroc, tumvi, kitti (default: the sequence's own, else euroc)");
  app.add_option("--mode", opts->mode, "Prior mode of the frontend run that records the tracks")->capture_default_str();
  app.add_option("--frames", opts->frames, "Use only the first N frames (0 = all)")
      ->capture_default_str()
      ->check(nonNegativeNumber());
  app.add_option("--warmup", opts->warmup,
                 "Frames run but not timed first: the window filling up to its number of keyframes")
      ->capture_default_str()
      ->check(nonNegativeNumber());
  app.add_option("--repeat", opts->repeat,
                 "Times the estimator is run over the same observations; each frame's time is the median of its "
                 "runs (the same work each time: what a busy machine adds to one run drops out)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  app.add_flag("--synthetic", opts->synthetic,
               "Synthetic observations of a room instead of real tracks (options below)");
  app.add_option("--seconds", opts->seconds, "--synthetic: length of the sequence (20 fps)")->capture_default_str();
  app.add_option("--points", opts->points, "--synthetic: tracked points per frame (left camera)")
      ->capture_default_str();
  app.add_option("--noise", opts->noise_px, "--synthetic: observation noise, px (Gaussian)")
      ->capture_default_str()
      ->check(nonNegativeNumber());
  app.add_option("--motion", opts->motion, "--synthetic: motion speed factor (1 = gentle handheld)")
      ->capture_default_str()
      ->check(positiveNumber());
  app.add_option("--keyframes", opts->keyframes, "--synthetic: keyframes in the window (max_keyframes)")
      ->capture_default_str();
  app.add_option("--rig", opts->rig, "--synthetic: built-in stereo rig, euroc or tumvi")->capture_default_str();
  app.footer(
      "By default the frontend runs once over a moving synthetic sequence (voca synth --motion aggressive\n"
      "--seconds 40, encoded at 500 kbit/s, generated on first use and cached), every frame's tracks are\n"
      "kept, and the estimator alone is then timed on them: exactly the observations the pipeline feeds\n"
      "it. The first --warmup frames fill the window and are not measured. The estimator runs --repeat\n"
      "times over the same observations (it is deterministic: a run that differs is an error); each\n"
      "frame's time is the median of its runs, and each run's own median is printed beside it.\n"
      "--synthetic instead generates observations of points in a room along a smooth trajectory\n"
      "(persistent ids, grid-limited new points) and runs the estimator with the paper's settings.");
  return [opts] { return opts->synthetic ? runSyntheticBench(*opts) : runTrackBench(*opts); };
}

}  // namespace voca::cli
