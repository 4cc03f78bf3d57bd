#pragma once
// Resident memory of this process (VmRSS), read without allocating: a long run samples it from a
// pipeline thread in its steady state, where an allocation would be a finding of its own.

#include <cstdint>

namespace voca::platform {

struct ResidentMemory {
  std::int64_t bytes = -1;         // all resident pages; -1 where they cannot be read
  std::int64_t shared_bytes = -1;  // of these, pages backed by files (program and library code, tables)
                                   // or shared memory: they grow as code is first run, not as memory leaks
  std::int64_t anonymousBytes() const { return bytes - shared_bytes; }  // heap, stacks, anonymous maps
};

// This process's resident memory now (/proc/self/statm).
ResidentMemory residentMemory();

}  // namespace voca::platform
