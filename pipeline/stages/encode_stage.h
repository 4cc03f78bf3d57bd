#pragma once
// The on-device encode stage: both cameras' raw gray images -> one H.264 access unit each, by the
// live encoder (the board's hardware encoder where there is one, else x264: no B-frames, one
// reference, no look-ahead). The decode stage that follows gives the pictures back with the codec's
// motion vectors, so raw input runs the same path as frames from a camera that compresses on the
// robot. An encoder that holds pictures back (some hardware does) makes the stage hold their slots
// until the packets come out, matched by presentation time.

#include <array>
#include <cstddef>
#include <string>

#include "drivers/decode/demuxer.h"
#include "drivers/encode/live_encoder.h"
#include "drivers/encode/video_encoder.h"
#include "pipeline/runtime/stage.h"

namespace voca::pipeline {

class EncodeStage final : public Stage {
 public:
  // Opens one encoder per camera for width x height frames (throws InputError when the requested
  // encoder is missing or refuses the size).
  EncodeStage(const encode::LiveEncoderSettings& settings, int width, int height);
  std::string_view name() const override { return "encode"; }
  int relativeCost() const override { return 2; }
  void start(const StageContext& context) override;
  void process(FrameSlot& slot, Emitter& out) override;
  void finish(Emitter& out) override;

  // What the decode stage needs to know of the two streams (headers in band, pts in frames).
  std::array<decode::StreamInfo, 2> streams() const;
  // "encoder: x264 (libx264, 1000 kbit/s, GOP 120)".
  const std::string& description() const { return description_; }

 private:
  static constexpr std::size_t kMaxPending = 16;
  struct Pending {
    FrameSlot* slot = nullptr;
    std::array<bool, 2> coded{};
  };
  Pending& at(std::size_t i) { return pending_[(head_ + i) % kMaxPending]; }
  void take(int camera, const encode::EncodedPacket& packet);
  void emitReady(Emitter& out);

  encode::LiveEncoderSettings settings_;
  int width_, height_;
  std::array<encode::VideoEncoder, 2> encoders_;
  std::string description_;
  std::array<Pending, kMaxPending> pending_{};
  std::size_t head_ = 0, size_ = 0;
  std::size_t max_held_ = kMaxPending - 1;
  std::array<std::int64_t, 2> packets_{};
};

}  // namespace voca::pipeline
