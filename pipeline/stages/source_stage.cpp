#include "pipeline/stages/source_stage.h"

#include <algorithm>
#include <cmath>
#include <thread>

#include "platform/realtime/clock.h"

namespace voca::pipeline {

SourceStageAdapter::SourceStageAdapter(StereoSource& source, const SourceStageOptions& options)
    : source_(source), options_(options) {}

void SourceStageAdapter::interrupt() {
  interrupted_ = true;
  source_.interrupt();
}

bool SourceStageAdapter::waitUntilDue(std::int64_t t_ns, std::int64_t& due_ns) {
  const std::int64_t now = platform::monotonicNs();
  if (!have_origin_) {
    have_origin_ = true;
    origin_t_ns_ = t_ns;
    origin_mono_ns_ = now;
  }
  const double offset = static_cast<double>(t_ns - origin_t_ns_) / std::max(options_.speed, 1e-6);
  due_ns = origin_mono_ns_ + static_cast<std::int64_t>(std::llround(offset));
  // Short sleeps, so an interrupt is seen within a few milliseconds.
  for (std::int64_t left = due_ns - platform::monotonicNs(); left > 0; left = due_ns - platform::monotonicNs()) {
    if (interrupted_) return false;
    std::this_thread::sleep_for(std::chrono::nanoseconds(std::min<std::int64_t>(left, 5'000'000)));
  }
  return !interrupted_;
}

Produced SourceStageAdapter::produce(FrameSlot& slot) {
  if (interrupted_) return Produced::kEnd;
  DecodedStereoFrame& frame = slot.frame;
  std::int64_t t_ns = 0;
  if (source_.info().kind == SourceKind::kRaw) {
    if (!source_.next(slot.raw)) return Produced::kEnd;
    t_ns = slot.raw.t_ns;
    frame.t_ns = slot.raw.t_ns;
    frame.frame_index = slot.raw.frame_index;
    // Nothing to pace or hand over: the runner releases it straight away.
    if (slot.raw.damaged) return Produced::kDamaged;
    if (options_.raw_to_frame) {
      for (int c = 0; c < DecodedStereoFrame::kNumCameras; ++c) {
        const auto i = static_cast<std::size_t>(c);
        std::swap(frame.images[i], slot.raw.images[i]);
        if (frame.motion[i].maxWidth() < frame.images[i].width() ||
            frame.motion[i].maxHeight() < frame.images[i].height()) {
          frame.motion[i] = MotionField(frame.images[i].width(), frame.images[i].height());
        }
        frame.motion[i].reset(frame.images[i].width(), frame.images[i].height(), PictureType::kUnknown);
        frame.motion[i].finalize();
      }
      frame.has_motion = false;
      frame.decoded = false;
    }
  } else {
    if (!source_.next(slot.encoded)) return Produced::kEnd;
    t_ns = slot.encoded.t_ns;
    frame.t_ns = slot.encoded.t_ns;
    frame.frame_index = slot.encoded.frame_index;
  }
  frame.frames_missing_before = 0;
  frame.depth_hint_m = 0.0;
  // Frames before the first tracked one (a video decoded from its start for the references) are
  // not paced: the recording's clock starts where the tracking does.
  if (options_.realtime && frame.frame_index >= source_.info().first_tracked_frame) {
    std::int64_t due = 0;
    if (!waitUntilDue(t_ns, due)) return Produced::kEnd;
    slot.arrival_ns = due;
  }
  return Produced::kFrame;
}

}  // namespace voca::pipeline
