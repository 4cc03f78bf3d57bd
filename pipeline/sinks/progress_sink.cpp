#include "pipeline/sinks/progress_sink.h"

#include <fmt/core.h>

namespace voca::pipeline {

ProgressSink::ProgressSink(std::int64_t total, bool estimate, int frontend_stage, int backend_stage,
                           bool suggest_flow_retry, bool suggest_stereo_tolerance)
    : total_(total),
      estimate_(estimate),
      frontend_stage_(frontend_stage),
      backend_stage_(backend_stage),
      suggest_flow_retry_(suggest_flow_retry),
      suggest_stereo_tolerance_(suggest_stereo_tolerance) {}

void ProgressSink::consume(const FrameSlot& slot) {
  ++frames_;
  if (estimate_ && slot.pose.state != TrackingState::kTracking) {
    line_.message("frame {}: {} ({})", slot.frame.frame_index, trackingStateName(slot.pose.state),
                  untrackedCause(slot.pose));
    hintAtFlowRetry(slot);
    hintAtStereoTolerance(slot);
  }
  if (frames_ % 20 != 0 && frames_ != total_) return;
  const auto ms = [&](int stage) { return slot.timing[static_cast<std::size_t>(stage)].serviceMs(); };
  // "frame 12/300", or "frame 12" for live input of unknown length; formatted into the line's own
  // buffer, so an update allocates nothing.
  const double frontend_ms = ms(frontend_stage_), backend_ms = estimate_ ? ms(backend_stage_) : 0.0;
  if (estimate_ && total_ > 0) {
    line_.update("frame {}/{}: {} landmarks, {} keyframes in the window, {:.1f} + {:.1f} ms", frames_, total_,
                 slot.pose.num_landmarks, slot.pose.num_keyframes, frontend_ms, backend_ms);
  } else if (estimate_) {
    line_.update("frame {}: {} landmarks, {} keyframes in the window, {:.1f} + {:.1f} ms", frames_,
                 slot.pose.num_landmarks, slot.pose.num_keyframes, frontend_ms, backend_ms);
  } else if (total_ > 0) {
    line_.update("tracked {}/{} frames", frames_, total_);
  } else {
    line_.update("tracked {} frames", frames_);
  }
}

// Most points lost in one step is image motion beyond the pyramid's reach more often than not
// (a low frame rate, a fast turn): configs/README.md, "Faster than the pyramid reaches".
void ProgressSink::hintAtFlowRetry(const FrameSlot& slot) {
  constexpr int kMinPoints = 20;
  const TemporalStats& t = slot.frontend_stats.temporal[0];
  if (!suggest_flow_retry_ || slot.pose.failure != FailureReason::kTooFewInliers || t.previous < kMinPoints ||
      4 * t.kept >= t.previous)
    return;
  suggest_flow_retry_ = false;
  line_.message(
      "hint: the tracker lost {} of {} points from the previous frame: the image may move faster than the KLT "
      "pyramid reaches (a low frame rate, a fast turn). Set \"retry_previous_flow\": \"always\" in the "
      "config's frontend section (configs/README.md), or track a video with motion vectors in a prior mode.",
      t.previous - t.kept, t.previous);
}

// A right camera with few of the left camera's points: on strongly compressed video the stereo
// matches fail their round trip (configs/README.md, "The left-right match's round trip").
void ProgressSink::hintAtStereoTolerance(const FrameSlot& slot) {
  constexpr int kMinPoints = 20;
  const FrontendStats& f = slot.frontend_stats;
  const bool starved =
      slot.pose.failure == FailureReason::kTooFewInliers || slot.pose.failure == FailureReason::kTooFewStereoPoints;
  if (!suggest_stereo_tolerance_ || !starved || f.num_left < kMinPoints || 4 * f.num_right >= f.num_left) return;
  suggest_stereo_tolerance_ = false;
  line_.message(
      "hint: the right camera holds {} of the left camera's {} points. On strongly compressed video the stereo "
      "matches fail their round trip (each camera's stream has its own artefacts): set "
      "\"stereo_max_recovered_dist2_px2\" to {}-1 in the config's frontend section (configs/README.md). A "
      "stereo calibration that is off, or \"matching_default_depth_m\" far from the scene's depth, loses them "
      "too.",
      f.num_right, f.num_left, kHintedStereoRoundTripDist2);
}

}  // namespace voca::pipeline
