#pragma once
// The sensor timestamp and frame index of each picture, carried inside the H.264 access unit as
// an SEI "user data unregistered" message (ITU-T H.264 D.1.6) with a VOCA-RT UUID. The stamp
// travels with the picture through any container or transport and is exact to the nanosecond
// (MPEG-TS's 90 kHz clock would round it to 11 us and wrap after 26 hours); decoders skip SEI they
// do not know, so the stream stays a standard one.

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace voca::network {

struct FrameStamp {
  std::int64_t t_ns = 0;         // sensor time of the picture
  std::int64_t frame_index = 0;  // the sender's frame counter: a gap at the receiver is a loss
};

// Copies an Annex B access unit into `out` with the stamp's SEI NAL unit inserted before the first
// slice (after any SPS/PPS/AUD). `out` is reused: no allocation once it has grown.
void stampAccessUnit(std::span<const std::uint8_t> access_unit, const FrameStamp& stamp,
                     std::vector<std::uint8_t>& out);

// The stamp of an Annex B access unit, if it carries one (searched up to its first slice).
std::optional<FrameStamp> readStamp(std::span<const std::uint8_t> access_unit);

// True when the access unit's first slice is an IDR slice: decoding can start (again) there.
bool isIdrAccessUnit(std::span<const std::uint8_t> access_unit);

}  // namespace voca::network
