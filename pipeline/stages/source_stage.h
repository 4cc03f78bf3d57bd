#pragma once
// The source stage: pulls frames from a StereoSource into slots, optionally paced at the recording's
// own rate (live-rate replay), and stamps each frame's arrival time.

#include <atomic>
#include <cstdint>

#include "drivers/source/stereo_source.h"
#include "pipeline/runtime/stage.h"

namespace voca::pipeline {

struct SourceStageOptions {
  // Deliver each frame when its timestamp comes due (relative to the first), as a camera would;
  // the frame's arrival time is then the due time, so lateness counts as latency.
  bool realtime = false;
  double speed = 1.0;  // realtime: playback speed factor
  // Raw sources: the frame goes straight to the frontend (no encode stage follows), so the images
  // are handed over into the decoded-frame message without copying.
  bool raw_to_frame = true;
};

class SourceStageAdapter final : public SourceStage {
 public:
  SourceStageAdapter(StereoSource& source, const SourceStageOptions& options);
  std::string_view name() const override { return "read"; }
  Produced produce(FrameSlot& slot) override;
  void interrupt() override;

 private:
  // Sleeps until the frame with sensor time t_ns is due; false when interrupted first.
  bool waitUntilDue(std::int64_t t_ns, std::int64_t& due_ns);

  StereoSource& source_;
  SourceStageOptions options_;
  std::atomic<bool> interrupted_{false};
  bool have_origin_ = false;
  std::int64_t origin_t_ns_ = 0;
  std::int64_t origin_mono_ns_ = 0;
};

}  // namespace voca::pipeline
