#pragma once
// Quantiles of a sample, the one definition every report uses (timings, errors, image motion).
// Linear interpolation between the closest ranks (Hyndman & Fan type 7, numpy's default), so the
// median of an even count is the mean of the middle two and q = 0 / q = 1 are the minimum / maximum.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <stdexcept>
#include <vector>

namespace voca {

// The q-quantile (0 <= q <= 1) of `values`, which it reorders. An empty sample has no quantile:
// the answer is NaN (prints as "nan", never a plausible-looking 0). q outside [0, 1] throws.
inline double quantileInPlace(std::span<double> values, double q) {
  if (!(q >= 0.0 && q <= 1.0)) throw std::domain_error("quantile: q must lie in [0, 1]");
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double rank = q * static_cast<double>(values.size() - 1);
  const auto lower = static_cast<std::size_t>(std::floor(rank));
  const auto lower_it = values.begin() + static_cast<std::ptrdiff_t>(lower);
  std::nth_element(values.begin(), lower_it, values.end());
  const double low = *lower_it;
  const double fraction = rank - static_cast<double>(lower);
  if (fraction == 0.0) return low;
  // The next rank is the smallest value above the lower one (nth_element partitioned them there).
  const double high = *std::min_element(lower_it + 1, values.end());
  // (1 - t) * a + t * b: at t = 0.5 this is exactly 0.5 * (a + b), the usual even-count median.
  return (1.0 - fraction) * low + fraction * high;
}

// The q-quantile of a copy of `values` (the caller's order is kept).
inline double quantile(std::vector<double> values, double q) { return quantileInPlace(values, q); }

inline double median(std::vector<double> values) { return quantileInPlace(values, 0.5); }

}  // namespace voca
