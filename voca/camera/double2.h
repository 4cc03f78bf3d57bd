#pragma once

#include <bit>
#include <cmath>
#include <cstdint>

namespace voca {

namespace camera_detail {

// Two doubles in one register (SSE2 on x86-64, NEON on AArch64): +, -, *, / and comparisons act lane
// by lane, each lane correctly rounded like the scalar operation, so a computation written once for
// double and once for Double2 with the same operations gives the same bits in every lane. A
// comparison gives a Mask2 lane of all ones or zeros.
using Double2 = double __attribute__((vector_size(16)));
using Mask2 = std::int64_t __attribute__((vector_size(16)));

inline Double2 select(Mask2 mask, Double2 if_set, Double2 if_clear) {
  return std::bit_cast<Double2>((std::bit_cast<Mask2>(if_set) & mask) | (std::bit_cast<Mask2>(if_clear) & ~mask));
}
inline Double2 abs(Double2 x) {
  return std::bit_cast<Double2>(std::bit_cast<Mask2>(x) & ~std::bit_cast<Mask2>(Double2{-0.0, -0.0}));
}
inline Double2 sqrt(Double2 x) { return Double2{std::sqrt(x[0]), std::sqrt(x[1])}; }

}  // namespace camera_detail

}  // namespace voca
