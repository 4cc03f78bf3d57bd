#pragma once
// The clocks the pipeline measures with: one monotonic clock for every stage timestamp (never the
// wall clock, which can jump) and the calling thread's CPU time (not inflated when other processes
// share the cores).

#include <cstdint>
#include <ctime>

namespace voca::platform {

// Nanoseconds of CLOCK_MONOTONIC: the same clock V4L2 stamps captured buffers with.
// Nanoseconds as milliseconds, the unit reports and viewers show latency in.
constexpr double nsToMs(std::int64_t ns) { return static_cast<double>(ns) * 1e-6; }

inline std::int64_t monotonicNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

// Nanoseconds of CPU time the calling thread has used.
inline std::int64_t threadCpuNs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

}  // namespace voca::platform
