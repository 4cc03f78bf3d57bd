#include "pipeline/stages/decode_stage.h"

#include <fmt/core.h>

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <iterator>
#include <string_view>
#include <utility>

#include "voca/core/error.h"

namespace voca::pipeline {

namespace {

// Frames a decoder may hold back before the stage gives up on it (hardware decoders hold a few).
constexpr std::size_t kMaxPending = 32;
// Room for the longest reason a frame is damaged, beyond its camera's name.
constexpr std::size_t kReasonCapacity = 200;

}  // namespace

struct DecodeStage::Impl {
  struct Pending {
    FrameSlot* slot = nullptr;
    std::array<std::int64_t, 2> pts{};
    std::array<bool, 2> resolved{};  // the camera's picture came out, or is known to be missing
    bool damaged = false;
    std::string why;  // for strict-mode errors; its buffer is kept from frame to frame

    // Empties it for the next frame, keeping why's buffer: a damaged frame then allocates nothing.
    void reset(FrameSlot* next) {
      slot = next;
      pts = {};
      resolved = {};
      damaged = false;
      why.clear();
    }
  };

  DecodeStageOptions options;
  // Frames whose pictures may still be inside the decoders; more would starve the source (set from
  // the runner in start()).
  std::size_t max_held = kMaxPending - 1;
  // Per camera, the pts of the newest frame whose picture came out or was given up: a picture at or
  // before it comes too late (the device returned it out of order, or after the stage gave up).
  std::array<std::int64_t, 2> settled_pts{decode::kNoPts, decode::kNoPts};
  // Per camera: a picture since the last I-picture was damaged or never came out. The pictures
  // predicted from it carry its concealment along (the decoder copies an older picture where data is
  // missing) and are not flagged: they show the scene displaced by the motion that was lost, which
  // tracks as a smooth but wrong path. So they count as damaged too, until an I-picture.
  std::array<bool, 2> references_damaged{};
  std::array<std::unique_ptr<decode::VideoDecoder>, 2> decoders;
  std::array<decode::DecodedFrame, 2> scratch;
  std::array<Pending, kMaxPending> pending;  // a ring, oldest at head
  std::size_t head = 0, size = 0;
  fmt::memory_buffer reason;  // a reason being formatted, in fixed storage

  Pending& at(std::size_t i) { return pending[(head + i) % kMaxPending]; }

  void settle(Pending& p, int camera) {
    const auto c = static_cast<std::size_t>(camera);
    p.resolved[c] = true;
    if (p.pts[c] != decode::kNoPts) settled_pts[c] = std::max(settled_pts[c], p.pts[c]);
  }

  void markDamaged(Pending& p, int camera, std::string_view why) {
    settle(p, camera);
    references_damaged[static_cast<std::size_t>(camera)] = true;
    if (!p.damaged) {
      p.why.clear();
      fmt::format_to(std::back_inserter(p.why), "{}: {}", options.names[static_cast<std::size_t>(camera)], why);
    }
    p.damaged = true;
  }

  // A picture of `camera` came out: it belongs to the oldest waiting frame with its pts; frames before
  // that one never got theirs.
  void match(int camera, decode::DecodedFrame& picture) {
    const auto c = static_cast<std::size_t>(camera);
    std::size_t target = size;
    for (std::size_t i = 0; i < size; ++i) {
      const Pending& p = at(i);
      if (p.resolved[c]) continue;
      if (picture.pts == decode::kNoPts || p.pts[c] == decode::kNoPts || p.pts[c] == picture.pts) {
        target = i;
        break;
      }
    }
    if (target == size) {
      if (picture.pts != decode::kNoPts && settled_pts[c] != decode::kNoPts && picture.pts <= settled_pts[c]) {
        return;  // its frame was already given up: the picture comes too late to be used
      }
      throw RuntimeFailure(
          fmt::format("{}: the decoder produced a picture (pts {}) for no packet sent", options.names[c], picture.pts));
    }
    for (std::size_t i = 0; i < target; ++i) {
      if (!at(i).resolved[c]) markDamaged(at(i), camera, "its picture never came out of the decoder (damaged data)");
    }
    Pending& p = at(target);
    settle(p, camera);
    // An I-picture ends the damage's reach. A decoder that does not report picture types (a hardware
    // wrapper without the software parse) cannot tell; there only flagged pictures are skipped.
    const PictureType type = picture.motion.pictureType();
    if (type == PictureType::kI || type == PictureType::kUnknown) references_damaged[c] = false;
    const bool predicted_from_damaged = references_damaged[c];
    DecodedStereoFrame& frame = p.slot->frame;
    // Hand the decoded buffers over without copying; the decoder keeps the slot's old ones.
    std::swap(frame.images[c], picture.luma);
    std::swap(frame.motion[c], picture.motion);
    if (picture.damaged) {
      markDamaged(p, camera, "damaged or missing bitstream data (concealed by the decoder)");
    } else if (predicted_from_damaged) {
      markDamaged(p, camera, "predicted from a damaged picture (no I-picture since)");
    }
  }

  void decode(FrameSlot& slot, Emitter& out);
  void finish(Emitter& out);

  void drain(int camera) {
    decode::DecodedFrame& picture = scratch[static_cast<std::size_t>(camera)];
    while (decoders[static_cast<std::size_t>(camera)]->receive(picture)) match(camera, picture);
  }

  void emitReady(Emitter& out) {
    while (size > 0 && at(0).resolved[0] && at(0).resolved[1]) {
      if (at(0).damaged && options.decoder.strict) {
        // Thrown with the frame still held, so that releaseHeld() hands its slot back.
        throw InputError(fmt::format("frame {} is damaged ({})", at(0).slot->frameIndex(), at(0).why));
      }
      FrameSlot& slot = *at(0).slot;
      const bool damaged = at(0).damaged;
      at(0).reset(nullptr);
      head = (head + 1) % kMaxPending;
      --size;
      if (slot.frameIndex() < options.first_tracked_frame) {
        out.release(slot, ReleaseReason::kNotTracked);
      } else if (!damaged) {
        slot.frame.has_motion = options.decoder.export_motion;
        slot.frame.decoded = true;
        out.forward(slot);
      } else {
        out.release(slot, ReleaseReason::kDamaged);
      }
    }
  }

  // A decoder outputs nothing for a packet it cannot decode yet: after lost reference data
  // libavcodec's H.264 decoder waits for the next keyframe, and hardware decoders hold a few
  // pictures. Only more packets bring those pictures out, and packets come in slots: the oldest frame
  // is given up (skipped as damaged, like a picture that never comes out) before the stage holds so
  // many slots that the source has none left to fill.
  void giveUpBeyond(std::size_t limit, Emitter& out) {
    while (size > limit) {
      for (int c = 0; c < 2; ++c) {
        if (!at(0).resolved[static_cast<std::size_t>(c)]) {
          reason.clear();
          fmt::format_to(std::back_inserter(reason),
                         "its picture had not come out of the decoder after {} more packets "
                         "(undecodable until the next keyframe after lost data?)",
                         size - 1);
          markDamaged(at(0), c, std::string_view(reason.data(), reason.size()));
        }
      }
      emitReady(out);
    }
  }

  // The stage failed: every slot it holds goes back, except `current`, which the runner releases.
  void releaseHeld(const FrameSlot* current, Emitter& out) noexcept {
    for (std::size_t i = 0; i < size; ++i) {
      Pending& p = at(i);
      if (p.slot != current) out.release(*p.slot, ReleaseReason::kAborted);
      p.reset(nullptr);
    }
    head = 0;
    size = 0;
  }
};

DecodeStage::DecodeStage(const std::array<decode::StreamInfo, 2>& streams, const DecodeStageOptions& options)
    : impl_(std::make_unique<Impl>()) {
  impl_->options = options;
  for (std::size_t c = 0; c < 2; ++c) {
    impl_->decoders[c] = std::make_unique<decode::VideoDecoder>(streams[c], options.decoder, nullptr, options.names[c]);
    impl_->scratch[c].reserve(streams[c].width, streams[c].height);
  }
  const std::size_t longest_name = std::max(options.names[0].size(), options.names[1].size());
  for (Impl::Pending& p : impl_->pending) p.why.reserve(longest_name + kReasonCapacity);
}

DecodeStage::~DecodeStage() = default;

const std::string& DecodeStage::description() const { return impl_->decoders[0]->description(); }

void DecodeStage::start(const StageContext& context) {
  impl_->max_held = std::min(kMaxPending - 1, static_cast<std::size_t>(std::max(context.maxHeldSlots(), 0)));
}

void DecodeStage::process(FrameSlot& slot, Emitter& out) {
  Impl& d = *impl_;
  try {
    d.decode(slot, out);
  } catch (...) {
    d.releaseHeld(&slot, out);
    throw;
  }
}

void DecodeStage::finish(Emitter& out) {
  Impl& d = *impl_;
  try {
    d.finish(out);
  } catch (...) {
    d.releaseHeld(nullptr, out);
    throw;
  }
}

void DecodeStage::Impl::decode(FrameSlot& slot, Emitter& out) {
  Impl& d = *this;
  Impl::Pending& p = d.at(d.size++);
  p.reset(&slot);
  for (std::size_t c = 0; c < 2; ++c) p.pts[c] = slot.encoded.packets[c].pts;
  for (int c = 0; c < 2; ++c) {
    const decode::Packet& packet = slot.encoded.packets[static_cast<std::size_t>(c)];
    decode::VideoDecoder& decoder = *d.decoders[static_cast<std::size_t>(c)];
    try {
      if (d.options.decoder.strict) {
        decoder.send(packet);  // throws, naming the packet
      } else if (!decoder.trySend(packet) && !p.resolved[static_cast<std::size_t>(c)]) {
        d.markDamaged(p, c, "the decoder refused its packet as corrupt");
      }
    } catch (const InputError& e) {
      // Non-strict decoding reports bad data per frame instead of stopping (strict rethrows).
      if (d.options.decoder.strict) throw;
      if (!p.resolved[static_cast<std::size_t>(c)]) d.markDamaged(p, c, e.what());
    }
    d.drain(c);
  }
  d.emitReady(out);
  d.giveUpBeyond(d.max_held, out);
}

void DecodeStage::Impl::finish(Emitter& out) {
  Impl& d = *this;
  for (int c = 0; c < 2; ++c) {
    d.decoders[static_cast<std::size_t>(c)]->sendEnd();
    d.drain(c);
  }
  for (std::size_t i = 0; i < d.size; ++i) {
    for (int c = 0; c < 2; ++c) {
      if (!d.at(i).resolved[static_cast<std::size_t>(c)]) {
        d.markDamaged(d.at(i), c, "the stream ended before its picture was decoded");
      }
    }
  }
  d.emitReady(out);
}

}  // namespace voca::pipeline
