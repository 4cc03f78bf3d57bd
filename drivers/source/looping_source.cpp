#include "drivers/source/looping_source.h"

#include <fmt/core.h>

#include <algorithm>

#include "drivers/source/dataset_source.h"
#include "voca/core/error.h"

namespace voca {

namespace {

// Where a packet's noise starts: past the 4-byte length prefix and the slice header's first bytes,
// so the decoder still takes it for a slice of this picture and conceals what it cannot decode.
constexpr std::size_t kDamageOffset = 12;

void checkRate(double rate, const char* what) {
  if (!(rate >= 0.0 && rate < 1.0)) {
    throw InputError(fmt::format("looping source: {} rate {} is outside [0, 1)", what, rate));
  }
}

// The time from a pass's first frame to the next pass's: the recording's span plus one mean frame
// interval, so the seam is paced like any other frame.
std::int64_t passPeriod(std::int64_t first, std::int64_t last, std::size_t frames) {
  const auto intervals = static_cast<std::int64_t>(frames - 1);
  return last - first + (last - first + intervals / 2) / intervals;
}

}  // namespace

LoopingVideoSource::LoopingVideoSource(const Dataset& dataset, const LoopOptions& options)
    : options_(options), random_(options.seed) {
  checkRate(options.drop_rate, "drop");
  checkRate(options.damage_rate, "damage");
  if (options.frames < 0) throw InputError(fmt::format("looping source: {} frames asked for", options.frames));
  VideoFolderSource recording(dataset);
  EncodedStereoPacket packet;
  while (recording.next(packet)) recording_.push_back(packet);
  const std::size_t n = recording_.size();
  if (n < 2) {
    throw InputError(fmt::format("{}: {} frame(s); a loop needs at least 2", dataset.root.string(), n));
  }
  if (!recording_[0].packets[0].keyframe || !recording_[0].packets[1].keyframe) {
    throw InputError(
        fmt::format("{}: the first frame is not a keyframe of both cameras; a pass could not be decoded "
                    "after the previous one",
                    dataset.root.string()));
  }
  pass_period_ns_ = passPeriod(recording_.front().t_ns, recording_.back().t_ns, n);
  for (std::size_t c = 0; c < 2; ++c) {
    pass_period_pts_[c] = passPeriod(recording_.front().packets[c].pts, recording_.back().packets[c].pts, n);
  }
  if (pass_period_ns_ <= 0) throw InputError(fmt::format("{}: timestamps do not increase", dataset.root.string()));
  info_ = recording.info();
  info_.expected_frames = options.frames;
  info_.first_tracked_frame = 0;
  info_.description = fmt::format("{} looped ({} frames per pass{}{})", recording.info().description, n,
                                  options.drop_rate > 0.0 ? fmt::format(", {:g} dropped", options.drop_rate) : "",
                                  options.damage_rate > 0.0 ? fmt::format(", {:g} damaged", options.damage_rate) : "");
}

void LoopingVideoSource::damage(decode::Packet& packet) {
  std::vector<std::uint8_t>& bytes = packet.bytes;
  for (std::size_t i = std::min(kDamageOffset, bytes.size() / 2); i < bytes.size(); i += 8) {
    const std::uint64_t noise = random_();
    for (std::size_t k = 0; k < 8 && i + k < bytes.size(); ++k)
      bytes[i + k] = static_cast<std::uint8_t>(noise >> (8 * k));
  }
}

bool LoopingVideoSource::next(EncodedStereoPacket& packet) {
  const auto n = static_cast<std::int64_t>(recording_.size());
  for (;;) {
    if (interrupted_.load(std::memory_order_relaxed)) return false;
    if (options_.frames > 0 && next_index_ >= options_.frames) return false;
    const std::int64_t index = next_index_++;
    frames_.store(next_index_, std::memory_order_relaxed);
    const std::int64_t pass = index / n;
    const EncodedStereoPacket& original = recording_[static_cast<std::size_t>(index % n)];
    if (waiting_for_keyframe_) {
      if (!original.packets[0].keyframe || !original.packets[1].keyframe) {
        skipped_.fetch_add(1, std::memory_order_relaxed);
        continue;
      }
      waiting_for_keyframe_ = false;
    }
    if (options_.drop_rate > 0.0 && uniform_(random_) < options_.drop_rate) {
      dropped_.fetch_add(1, std::memory_order_relaxed);
      waiting_for_keyframe_ = true;
      continue;
    }
    packet.t_ns = original.t_ns + pass * pass_period_ns_;
    packet.frame_index = index;
    for (std::size_t c = 0; c < 2; ++c) {
      const decode::Packet& from = original.packets[c];
      decode::Packet& to = packet.packets[c];
      to.bytes.assign(from.bytes.begin(), from.bytes.end());  // reuses the buffer once it holds the largest
      to.pts = from.pts == decode::kNoPts ? from.pts : from.pts + pass * pass_period_pts_[c];
      to.dts = from.dts == decode::kNoPts ? from.dts : from.dts + pass * pass_period_pts_[c];
      to.keyframe = from.keyframe;
      to.index = index;
    }
    if (options_.damage_rate > 0.0 && uniform_(random_) < options_.damage_rate) {
      damage(packet.packets[random_() % 2]);
      damaged_packets_.fetch_add(1, std::memory_order_relaxed);
    }
    delivered_.fetch_add(1, std::memory_order_relaxed);
    return true;
  }
}

SourceCounters LoopingVideoSource::counters() const {
  return {.frames_lost = dropped_.load(std::memory_order_relaxed) + skipped_.load(std::memory_order_relaxed)};
}

LoopCounters LoopingVideoSource::loopCounters() const {
  const auto n = static_cast<std::int64_t>(recording_.size());
  LoopCounters counters;
  counters.frames = frames_.load(std::memory_order_relaxed);
  counters.delivered = delivered_.load(std::memory_order_relaxed);
  counters.dropped = dropped_.load(std::memory_order_relaxed);
  counters.skipped = skipped_.load(std::memory_order_relaxed);
  counters.damaged_packets = damaged_packets_.load(std::memory_order_relaxed);
  counters.passes = counters.frames == 0 ? 0 : (counters.frames - 1) / n + 1;
  return counters;
}

}  // namespace voca
