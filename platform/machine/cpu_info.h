#pragma once
// What machine a measurement ran on, for benchmark reports.

#include <string>

namespace voca::platform {

// The CPU's model name from /proc/cpuinfo ("model name" on x86, "Model" or "Hardware" on most ARM
// kernels), or "unknown CPU".
std::string cpuModel();

}  // namespace voca::platform
