#pragma once
// The per-frame budget the stage benches (backend, decode, frontend) report against: the median
// within the target and the tail, p99, within twice the median (a stage that meets its median but
// stalls now and then still delays frames in a live run).

namespace voca::cli {

inline const char* budgetVerdict(double median_ms, double p99_ms, double target_median_ms) {
  if (median_ms > target_median_ms) return "missed";
  if (p99_ms > 2.0 * median_ms) return "missed (p99)";
  return "met";
}

}  // namespace voca::cli
