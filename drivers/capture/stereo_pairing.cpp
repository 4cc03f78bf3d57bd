#include "drivers/capture/stereo_pairing.h"

#include <cmath>

namespace voca::capture {

PairDecision decidePair(std::int64_t t_left_ns, std::int64_t t_right_ns, std::int64_t tolerance_ns) {
  const std::int64_t difference = t_left_ns - t_right_ns;
  if (difference <= tolerance_ns && difference >= -tolerance_ns) return PairDecision::kPair;
  // The older frame cannot pair with anything that comes later from the other camera.
  return difference < 0 ? PairDecision::kDropLeft : PairDecision::kDropRight;
}

std::int64_t defaultPairTolerance(double rate_hz) {
  if (rate_hz <= 0.0) return 10'000'000;
  return static_cast<std::int64_t>(std::llround(0.5e9 / rate_hz)) - 1000;
}

}  // namespace voca::capture
