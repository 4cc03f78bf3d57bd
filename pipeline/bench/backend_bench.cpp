#include "pipeline/bench/backend_bench.h"

#include <fmt/core.h>

#include "pipeline/sinks/sink_stage.h"
#include "platform/realtime/clock.h"
#include "voca/backend/estimator.h"
#include "voca/core/error.h"

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
  if (result.pipeline.error) throw RuntimeFailure(result.pipeline.error->message);
  if (result.stop_signal != 0) return std::nullopt;
  recording.rig = result.rig;
  recording.config = result.config;
  recording.description = result.description;
  return recording;
}

EstimatorTiming timeEstimator(const std::vector<TrackedStereoFrame>& frames, const StereoRig& rig,
                              const BackendConfig& config, std::size_t warmup) {
  if (frames.size() <= warmup) {
    throw InputError(fmt::format("{} frames: the estimator needs more than the {} warm-up frames to be timed",
                                 frames.size(), warmup));
  }
  EstimatorTiming timing;
  timing.warmup = warmup;
  timing.cpu_ms.reserve(frames.size() - warmup);
  VoEstimator estimator(config, rig);
  double window = 0.0, points = 0.0, inliers = 0.0, iterations = 0.0, linearizations = 0.0, pose_iterations = 0.0;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const std::int64_t start = platform::threadCpuNs();
    const PoseEstimate& estimate = estimator.process(frames[k]);
    const std::int64_t elapsed = platform::threadCpuNs() - start;
    timing.resets += estimate.state != TrackingState::kTracking;
    if (k < warmup) continue;
    timing.cpu_ms.push_back(1e-6 * static_cast<double>(elapsed));
    timing.keyframes += estimate.keyframe;
    window += estimate.num_keyframes;
    points += static_cast<double>(frames[k].observations[0].size());
    inliers += estimate.num_inliers;
    iterations += estimate.lm_iterations;
    linearizations += estimate.lm_linearizations;
    pose_iterations += estimate.pose_iterations;
    ++timing.measured;
  }
  const double n = static_cast<double>(timing.measured);
  timing.mean_window_keyframes = window / n;
  timing.mean_left_points = points / n;
  timing.mean_inliers = inliers / n;
  timing.mean_lm_iterations = iterations / n;
  timing.mean_linearizations = linearizations / n;
  timing.mean_pose_iterations = pose_iterations / n;
  return timing;
}

}  // namespace voca::pipeline
