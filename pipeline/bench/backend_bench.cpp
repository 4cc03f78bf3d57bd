#include "pipeline/bench/backend_bench.h"

#include <fmt/core.h>

#include "pipeline/bench/per_frame_median.h"
#include "pipeline/sinks/sink_stage.h"
#include "platform/realtime/clock.h"
#include "voca/backend/estimator.h"
#include "voca/core/error.h"
#include "voca/core/quantile.h"

namespace voca::pipeline {

namespace {

// Keeps a copy of each finished frame's tracks (the frontend's output, the backend's input).
class TrackRecorder final : public FrameSink {
 public:
  explicit TrackRecorder(std::vector<TrackedStereoFrame>& frames) : frames_(frames) {}
  void consume(const FrameSlot& slot) override { frames_.push_back(slot.tracked); }

 private:
  std::vector<TrackedStereoFrame>& frames_;
};

}  // namespace

std::optional<TrackRecording> recordFrontendTracks(VoRunOptions options) {
  TrackRecording recording;
  TrackRecorder recorder(recording.frames);
  options.estimate = false;
  options.keep_trajectory = false;
  options.extra_sinks.push_back(&recorder);
  const VoRunResult result = runVisualOdometry(options);
  if (result.pipeline_report.error) throw RuntimeFailure(result.pipeline_report.error->message);
  if (result.stop_signal != 0) return std::nullopt;
  recording.rig = result.rig;
  recording.config = result.config;
  recording.description = result.description;
  return recording;
}

namespace {

// One run of a new estimator over the frames: the CPU time of every measured frame into cpu_ms; returns
// the estimates' counts and sums (the caller forms the means, and compares runs by them).
struct RunStatistics {
  int resets = 0, keyframes = 0;
  double window = 0.0, points = 0.0, inliers = 0.0, iterations = 0.0, linearizations = 0.0, cost_passes = 0.0,
         pose_iterations = 0.0;
  bool operator==(const RunStatistics&) const = default;
};

RunStatistics runEstimatorOnce(const std::vector<TrackedStereoFrame>& frames, const StereoRig& rig,
                               const BackendConfig& config, std::size_t warmup, std::vector<double>& cpu_ms) {
  RunStatistics stats;
  cpu_ms.clear();
  VoEstimator estimator(config, rig);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const std::int64_t start = platform::threadCpuNs();
    const PoseEstimate& estimate = estimator.process(frames[k]);
    const std::int64_t elapsed = platform::threadCpuNs() - start;
    stats.resets += estimate.state != TrackingState::kTracking;
    if (k < warmup) continue;
    cpu_ms.push_back(1e-6 * static_cast<double>(elapsed));
    stats.keyframes += estimate.keyframe;
    stats.window += estimate.num_keyframes;
    stats.points += static_cast<double>(frames[k].observations[0].size());
    stats.inliers += estimate.num_inliers;
    stats.iterations += estimate.lm_iterations;
    stats.linearizations += estimate.lm_linearizations;
    stats.cost_passes += estimate.lm_cost_passes;
    stats.pose_iterations += estimate.pose_iterations;
  }
  return stats;
}

}  // namespace

EstimatorTiming timeEstimator(const std::vector<TrackedStereoFrame>& frames, const StereoRig& rig,
                              const BackendConfig& config, std::size_t warmup, int repeat) {
  if (frames.size() <= warmup) {
    throw InputError(fmt::format("{} frames: the estimator needs more than the {} warm-up frames to be timed",
                                 frames.size(), warmup));
  }
  if (repeat < 1) throw InputError(fmt::format("repeat {}: the estimator must be timed at least once", repeat));
  EstimatorTiming timing;
  timing.warmup = warmup;
  const std::size_t measured = frames.size() - warmup;
  std::vector<std::vector<double>> run_ms(static_cast<std::size_t>(repeat));
  RunStatistics stats;
  for (int run = 0; run < repeat; ++run) {
    std::vector<double>& ms = run_ms[static_cast<std::size_t>(run)];
    ms.reserve(measured);
    const RunStatistics this_run = runEstimatorOnce(frames, rig, config, warmup, ms);
    if (run == 0) {
      stats = this_run;
    } else if (!(this_run == stats)) {
      throw RuntimeFailure(
          fmt::format("run {} of the estimator differs from the first (iterations, inliers or "
                      "keyframes): it is not deterministic, so its runs cannot be compared",
                      run + 1));
    }
    timing.run_median_ms.push_back(median(ms));
  }
  timing.cpu_ms = perFrameMedian(run_ms);
  timing.measured = static_cast<int>(measured);
  timing.resets = stats.resets;
  timing.keyframes = stats.keyframes;
  const double n = static_cast<double>(measured);
  timing.mean_window_keyframes = stats.window / n;
  timing.mean_left_points = stats.points / n;
  timing.mean_inliers = stats.inliers / n;
  timing.mean_lm_iterations = stats.iterations / n;
  timing.mean_linearizations = stats.linearizations / n;
  timing.mean_cost_passes = stats.cost_passes / n;
  timing.mean_pose_iterations = stats.pose_iterations / n;
  return timing;
}

}  // namespace voca::pipeline
