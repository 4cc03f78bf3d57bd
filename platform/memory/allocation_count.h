#pragma once
// The process-wide count of operator new calls, kept by the counting replacements of
// counting_operator_new.h. An executable that does not include that header counts nothing, and
// operatorNewCounted() tells a caller so. Only C++ allocations are seen: C libraries (libavcodec's
// av_malloc, libpng) call malloc.

#include <atomic>
#include <cstdint>

namespace voca::platform {

inline std::atomic<long> g_operator_new_calls{0};
inline std::atomic<bool> g_operator_new_counted{false};

inline bool operatorNewCounted() { return g_operator_new_counted.load(std::memory_order_relaxed); }
inline std::int64_t operatorNewCalls() { return g_operator_new_calls.load(std::memory_order_relaxed); }

}  // namespace voca::platform
