#pragma once
// Progress of a run on stderr: a line every few frames, one per frame that was not tracked, and once
// per run a hint at the config key that most likely helps when tracking fails in a known way.

#include <cstdint>

#include "pipeline/sinks/sink_stage.h"
#include "platform/terminal/progress_line.h"

namespace voca::pipeline {

// The looser end of the stereo round trip (squared px) that the starved-right-camera hint suggests;
// a config already at or above it gets no hint.
inline constexpr double kHintedStereoRoundTripDist2 = 0.5;

class ProgressSink final : public FrameSink {
 public:
  // total: the frames expected (0: unknown, live input). estimate: the run has a backend.
  // frontend_stage, backend_stage: the stages' positions in the pipeline, to read their times.
  // suggest_flow_retry: retry_previous_flow does not act on this input, so a failure where the
  // temporal step lost most points gets a hint at that key, once. suggest_stereo_tolerance: the
  // left-right match's round trip is tighter than kHintedStereoRoundTripDist2, so a failure where the
  // right camera holds few of the left camera's points gets a hint at stereo_max_recovered_dist2_px2, once.
  ProgressSink(std::int64_t total, bool estimate, int frontend_stage, int backend_stage, bool suggest_flow_retry,
               bool suggest_stereo_tolerance);
  void consume(const FrameSlot& slot) override;
  void finish() override { line_.end(); }

 private:
  void hintAtFlowRetry(const FrameSlot& slot);
  void hintAtStereoTolerance(const FrameSlot& slot);

  std::int64_t total_;
  bool estimate_;
  int frontend_stage_, backend_stage_;
  bool suggest_flow_retry_;
  bool suggest_stereo_tolerance_;
  std::int64_t frames_ = 0;
  platform::ProgressLine line_;
};

}  // namespace voca::pipeline
