#pragma once
// Stereo pairing of two free-running or triggered cameras by their capture timestamps: the oldest
// waiting frame of each camera either forms a pair (within the tolerance) or the older one is left
// unpaired, so a camera that skipped a frame never shifts every later pair by one.

#include <cstdint>

namespace voca::capture {

enum class PairDecision { kPair, kDropLeft, kDropRight };

// t_left, t_right: the oldest waiting frame of each camera, on one clock.
PairDecision decidePair(std::int64_t t_left_ns, std::int64_t t_right_ns, std::int64_t tolerance_ns);

// The default tolerance: just under half a frame interval, so each frame pairs with its nearest
// partner at most once even when unsynchronised cameras run at arbitrary phase; 10 ms when the
// rate is unknown.
std::int64_t defaultPairTolerance(double rate_hz);

}  // namespace voca::capture
