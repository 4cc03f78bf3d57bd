#pragma once
// The pyramid's horizontal reduction, four output pixels at a time, as a template over a simd4
// backend (see simd4.h); tests compare the native and the portable backend.

#include "voca/frontend/simd4.h"

namespace voca::pyramid_kernels {

// out[x] = (s[2x-2] + s[2x+2] + 4 (s[2x-1] + s[2x+1]) + 6 s[2x]) / 16 for x in [begin, end), with
// every s index inside the row (the caller handles the clamped border columns).
template <class V>
int reduceRow(const float* s, float* out, int begin, int end) {
  using F = typename V::F;
  const F four = V::set1(4.f), six = V::set1(6.f), sixteenth = V::set1(1.f / 16.f);
  int x = begin;
  for (; x + 4 <= end; x += 4) {
    F m2, m1, c0, p1, p2, unused;
    V::deinterleave(s + 2 * x - 2, m2, m1);  // s[2x-2], s[2x-1] for four x
    V::deinterleave(s + 2 * x, c0, p1);
    V::deinterleave(s + 2 * x + 2, p2, unused);
    const F sum = V::add(V::add(V::add(m2, p2), V::mul(four, V::add(m1, p1))), V::mul(six, c0));
    V::store(out + x, V::mul(sum, sixteenth));
  }
  return x;  // the first x not done (fewer than four left)
}

}  // namespace voca::pyramid_kernels
