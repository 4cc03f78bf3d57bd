// `voca bench backend`: the estimator alone on synthetic stereo observations (a 7-keyframe window
// and ~200 tracked points by default), timed per frame on this thread's CPU clock.

#include "tools/voca/bench_backend.h"

#include <fmt/core.h>

#include <algorithm>
#include <ctime>
#include <memory>
#include <vector>

#include "voca/backend/estimator.h"
#include "voca/backend/synthetic.h"
#include "voca/core/error.h"
#include "voca/synth/rigs.h"

namespace voca::cli {

namespace {

struct BackendBenchOptions {
  double seconds = 60.0;
  int points = 200;
  double noise_px = 0.5;
  double motion = 1.0;
  int keyframes = 7;
  std::string rig = "euroc";
};

double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5))];
}

int runBackendBench(const BackendBenchOptions& opts) {
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

  VoEstimator estimator(config, *rig);
  std::vector<double> cpu_ms, window_ms;
  cpu_ms.reserve(seq.frames.size());
  double points = 0.0, observations = 0.0, keyframes = 0.0;
  int resets = 0, kf_count = 0, measured = 0;
  const std::size_t warmup = 40;  // until the window holds its full number of keyframes
  for (std::size_t k = 0; k < seq.frames.size(); ++k) {
    const double start = threadCpuMs();
    const PoseEstimate& e = estimator.process(seq.frames[k]);
    const double ms = threadCpuMs() - start;
    resets += e.state != TrackingState::kTracking;
    if (k < warmup) continue;
    cpu_ms.push_back(ms);
    window_ms.push_back(e.time_ms);
    points += static_cast<double>(seq.frames[k].observations[0].size());
    observations += e.num_inliers;
    keyframes += e.num_keyframes;
    kf_count += e.keyframe;
    ++measured;
  }
  const double med = quantile(cpu_ms, 0.5), p99 = quantile(cpu_ms, 0.99);
  fmt::print(
      "backend on synthetic observations ({} rig, {:.0f} s at 20 fps, {:.2f} px noise, motion x{:.1f}), one thread\n",
      opts.rig, opts.seconds, opts.noise_px, opts.motion);
  fmt::print("  measured frames {} (after {} warm-up), keyframes {} ({:.1f} in the window on average), resets {}\n",
             measured, warmup, kf_count, keyframes / std::max(1, measured), resets);
  fmt::print("  tracked points per frame {:.0f} (left), inlier observations per frame {:.0f} (both cameras)\n",
             points / std::max(1, measured), observations / std::max(1, measured));
  fmt::print(
      "  CPU time per frame: median {:.3f} ms, p90 {:.3f} ms, p99 {:.3f} ms, max {:.3f} ms (wall median {:.3f} ms)\n",
      med, quantile(cpu_ms, 0.9), p99, quantile(cpu_ms, 1.0), quantile(window_ms, 0.5));
  fmt::print("  targets (7 keyframes, ~200 points): median <= 4 ms: {}; p99 <= 12 ms: {}\n",
             med <= 4.0 ? "met" : "not met", p99 <= 12.0 ? "met" : "not met");
  return 0;
}

}  // namespace

Runner configureBackendBench(CLI::App& app) {
  auto opts = std::make_shared<BackendBenchOptions>();
  app.add_option("--seconds", opts->seconds, "Length of the synthetic sequence (20 fps)")->capture_default_str();
  app.add_option("--points", opts->points, "Tracked points per frame (left camera)")->capture_default_str();
  app.add_option("--noise", opts->noise_px, "Observation noise, px (Gaussian)")->capture_default_str();
  app.add_option("--motion", opts->motion, "Motion speed factor (1 = gentle handheld)")->capture_default_str();
  app.add_option("--keyframes", opts->keyframes, "Keyframes in the window (max_keyframes)")->capture_default_str();
  app.add_option("--rig", opts->rig, "Built-in stereo rig: euroc or tumvi")->capture_default_str();
  app.footer(
      "Generates observations of points in a room along a smooth trajectory (persistent track ids,\n"
      "grid-limited new points, as the frontend produces them), runs the estimator with the paper's\n"
      "settings and reports per-frame CPU time after the window has filled.");
  return [opts] { return runBackendBench(*opts); };
}

}  // namespace voca::cli
