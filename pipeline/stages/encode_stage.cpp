#include "pipeline/stages/encode_stage.h"

#include <fmt/core.h>

#include <algorithm>

#include "voca/core/error.h"

namespace voca::pipeline {

EncodeStage::EncodeStage(const encode::LiveEncoderSettings& settings, int width, int height)
    : settings_(settings), width_(width), height_(height) {
  // In-band headers: the decoder learns the stream from its first keyframe, as from a camera.
  settings_.global_header = false;
  encode::silenceCodecLogs();
  const encode::EncoderChoice choice = encode::openLiveEncoder(encoders_[0], settings_, width, height);
  settings_.kind = choice.kind;  // the right camera on the same encoder
  encode::openLiveEncoder(encoders_[1], settings_, width, height);
  description_ = choice.description;
}

std::array<decode::StreamInfo, 2> EncodeStage::streams() const {
  std::array<decode::StreamInfo, 2> streams;
  for (decode::StreamInfo& info : streams) {
    info.codec = decode::VideoCodec::kH264;
    info.codec_name = "h264";
    info.width = width_;
    info.height = height_;
    info.time_base_num = settings_.fps_den;  // pts count frames
    info.time_base_den = settings_.fps_num;
    info.frame_rate_num = settings_.fps_num;
    info.frame_rate_den = settings_.fps_den;
  }
  return streams;
}

void EncodeStage::start(const StageContext& context) {
  max_held_ = std::min(kMaxPending - 1, static_cast<std::size_t>(std::max(context.maxHeldSlots(), 0)));
}

void EncodeStage::take(int camera, const encode::EncodedPacket& packet) {
  const auto c = static_cast<std::size_t>(camera);
  for (std::size_t i = 0; i < size_; ++i) {
    Pending& p = at(i);
    if (p.coded[c] || p.slot->frameIndex() != packet.pts) continue;
    decode::Packet& out = p.slot->encoded.packets[c];
    out.bytes.assign(packet.bytes.begin(), packet.bytes.end());  // reserved with the slot: no allocation
    out.pts = packet.pts;
    out.dts = packet.dts;
    out.keyframe = packet.keyframe;
    out.index = packets_[c]++;
    p.coded[c] = true;
    return;
  }
  throw RuntimeFailure(
      fmt::format("cam{}: the encoder returned a packet (pts {}) for no frame it was given", c, packet.pts));
}

void EncodeStage::emitReady(Emitter& out) {
  while (size_ > 0 && at(0).coded[0] && at(0).coded[1]) {
    FrameSlot& slot = *at(0).slot;
    at(0) = Pending{};
    head_ = (head_ + 1) % kMaxPending;
    --size_;
    out.forward(slot);
  }
}

void EncodeStage::process(FrameSlot& slot, Emitter& out) {
  slot.encoded.t_ns = slot.raw.t_ns;
  slot.encoded.frame_index = slot.raw.frame_index;
  at(size_++) = Pending{&slot, {}};
  for (int c = 0; c < 2; ++c) {
    for (const encode::EncodedPacket& packet : encoders_[static_cast<std::size_t>(c)].encode(
             slot.raw.images[static_cast<std::size_t>(c)].view(), slot.raw.frame_index)) {
      take(c, packet);
    }
  }
  emitReady(out);
  // An encoder holding more pictures back than the pool allows would starve the source of slots for
  // the frames that bring them out: the oldest frame is given up, as the decode stage does.
  while (size_ > max_held_) {
    FrameSlot& oldest = *at(0).slot;
    at(0) = Pending{};
    head_ = (head_ + 1) % kMaxPending;
    --size_;
    out.release(oldest, ReleaseReason::kDamaged);
  }
}

void EncodeStage::finish(Emitter& out) {
  for (int c = 0; c < 2; ++c) {
    for (const encode::EncodedPacket& packet : encoders_[static_cast<std::size_t>(c)].flush()) take(c, packet);
  }
  emitReady(out);
  while (size_ > 0) {
    FrameSlot& slot = *at(0).slot;
    at(0) = Pending{};
    head_ = (head_ + 1) % kMaxPending;
    --size_;
    out.release(slot, ReleaseReason::kDamaged);
  }
}

}  // namespace voca::pipeline
