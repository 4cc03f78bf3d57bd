#pragma once
// Counting replacements of the global operator new/delete, for tests that prove a hot path does not
// allocate (platform/memory/counting_operator_new.h). Include in exactly one source file of a test
// executable (they replace the program's operators). Only C++ allocations are seen: C libraries
// (libavcodec's av_malloc, libpng) call malloc.

#include "platform/memory/counting_operator_new.h"

namespace voca::test {
inline std::atomic<long>& g_allocations = platform::g_operator_new_calls;
}  // namespace voca::test
