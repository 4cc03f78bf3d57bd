#pragma once
// The decode stage: both cameras' packets -> one DecodedStereoFrame (Y planes, motion fields,
// picture types). Decoders may hold pictures back (hardware decoders do; libavcodec's H.264 decoder
// outputs nothing after lost reference data until the next keyframe), so the stage keeps the slots
// whose pictures have not come out yet and forwards them in order as both cameras' pictures arrive,
// matched by pts. It never keeps more slots than the runner allows (StageContext::maxHeldSlots): the
// source needs a free one to bring the packets that let the pictures out, so the oldest frame is
// given up first. A picture that is missing, given up or flagged damaged makes its frame damaged:
// it is skipped and counted (the tracker resumes on the next decodable frame), or, in strict mode,
// stops the run with an error naming the camera and frame.

#include <array>
#include <memory>
#include <string>

#include "drivers/decode/video_decoder.h"
#include "pipeline/runtime/stage.h"

namespace voca::pipeline {

struct DecodeStageOptions {
  decode::DecoderOptions decoder;  // its `strict` decides: stop on the first damaged frame, or skip
  std::array<std::string, 2> names = {"cam0", "cam1"};  // for messages
  // Frames before this index are decoded for their references and then let go, not tracked
  // (SourceInfo::first_tracked_frame).
  std::int64_t first_tracked_frame = 0;
};

class DecodeStage final : public Stage {
 public:
  DecodeStage(const std::array<decode::StreamInfo, 2>& streams, const DecodeStageOptions& options);
  ~DecodeStage() override;
  std::string_view name() const override { return "decode"; }
  void start(const StageContext& context) override;
  void process(FrameSlot& slot, Emitter& out) override;
  void finish(Emitter& out) override;

  // "decoder: software" or the hardware choice, for the run's log.
  const std::string& description() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace voca::pipeline
