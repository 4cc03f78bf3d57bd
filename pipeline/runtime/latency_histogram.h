#pragma once
// A fixed-memory latency histogram (log-linear buckets: exact below 128 ns, 64 buckets per power of
// two above, so a reported percentile is within 0.8 % of the true value). Recording never allocates,
// so every frame of an unbounded live run can be counted; the run summary and `voca profile` on a
// saved trace compute their percentiles with this same class and so print the same numbers.

#include <array>
#include <cstdint>

namespace voca::pipeline {

class LatencyHistogram {
 public:
  void record(std::int64_t ns);
  void merge(const LatencyHistogram& other);

  std::int64_t count() const { return count_; }
  std::int64_t maxNs() const { return max_; }
  std::int64_t minNs() const { return count_ > 0 ? min_ : 0; }
  double meanNs() const { return count_ > 0 ? static_cast<double>(sum_) / static_cast<double>(count_) : 0.0; }
  // The value below which a fraction q of the samples lie (q in [0, 1]; the midpoint of the bucket
  // holding the sample of rank round(q * (count - 1))); 0 when empty. q = 1 gives the exact maximum.
  std::int64_t quantileNs(double q) const;

 private:
  static constexpr int kExactBelow = 128;
  static constexpr int kSubBuckets = 64;
  static constexpr int kMaxExponent = 44;  // 2^44 ns ~ 4.9 hours; larger values share the last bucket
  static constexpr int kBuckets = kExactBelow + (kMaxExponent - 6) * kSubBuckets;
  static int bucketOf(std::int64_t ns);
  static std::int64_t bucketLow(int bucket);
  static std::int64_t bucketWidth(int bucket);

  std::array<std::int64_t, kBuckets> counts_{};
  std::int64_t count_ = 0;
  std::int64_t sum_ = 0;
  std::int64_t min_ = 0;
  std::int64_t max_ = 0;
};

}  // namespace voca::pipeline
