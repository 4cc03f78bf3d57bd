#pragma once
// Resident memory of this process (VmRSS), read without allocating: a long run samples it from a
// pipeline thread in its steady state, where an allocation would be a finding of its own.

#include <cstdint>

namespace voca::platform {

// Bytes of this process resident in RAM now (/proc/self/statm); -1 where that cannot be read.
std::int64_t residentBytes();

}  // namespace voca::platform
