#include "pipeline/runtime/latency_histogram.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace voca::pipeline {

int LatencyHistogram::bucketOf(std::int64_t ns) {
  if (ns < kExactBelow) return static_cast<int>(std::max<std::int64_t>(ns, 0));
  const auto value = static_cast<std::uint64_t>(ns);
  const int exponent = std::bit_width(value) - 1;  // >= 7
  if (exponent >= kMaxExponent) return kBuckets - 1;
  const int sub = static_cast<int>((value >> (exponent - 6)) & (kSubBuckets - 1));
  return kExactBelow + (exponent - 7) * kSubBuckets + sub;
}

std::int64_t LatencyHistogram::bucketLow(int bucket) {
  if (bucket < kExactBelow) return bucket;
  const int exponent = 7 + (bucket - kExactBelow) / kSubBuckets;
  const int sub = (bucket - kExactBelow) % kSubBuckets;
  return (std::int64_t{1} << exponent) + static_cast<std::int64_t>(sub) * (std::int64_t{1} << (exponent - 6));
}

std::int64_t LatencyHistogram::bucketWidth(int bucket) {
  if (bucket < kExactBelow) return 1;
  const int exponent = 7 + (bucket - kExactBelow) / kSubBuckets;
  return std::int64_t{1} << (exponent - 6);
}

void LatencyHistogram::record(std::int64_t ns) {
  ns = std::max<std::int64_t>(ns, 0);
  ++counts_[static_cast<std::size_t>(bucketOf(ns))];
  min_ = count_ == 0 ? ns : std::min(min_, ns);
  max_ = std::max(max_, ns);
  sum_ += ns;
  ++count_;
}

void LatencyHistogram::merge(const LatencyHistogram& other) {
  if (other.count_ == 0) return;
  for (std::size_t i = 0; i < counts_.size(); ++i) counts_[i] += other.counts_[i];
  min_ = count_ == 0 ? other.min_ : std::min(min_, other.min_);
  max_ = std::max(max_, other.max_);
  sum_ += other.sum_;
  count_ += other.count_;
}

std::int64_t LatencyHistogram::quantileNs(double q) const {
  if (count_ == 0) return 0;
  q = std::clamp(q, 0.0, 1.0);
  const auto rank = static_cast<std::int64_t>(std::llround(q * static_cast<double>(count_ - 1)));
  if (rank >= count_ - 1) return max_;
  if (rank == 0) return min_;
  std::int64_t seen = 0;
  for (int b = 0; b < kBuckets; ++b) {
    seen += counts_[static_cast<std::size_t>(b)];
    if (seen > rank) {
      const std::int64_t mid = bucketLow(b) + bucketWidth(b) / 2;
      return std::clamp(mid, min_, max_);
    }
  }
  return max_;
}

}  // namespace voca::pipeline
