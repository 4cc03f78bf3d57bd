#include "voca/frontend/patch_kernels_avx2.h"

#if VOCA_AVX2_KERNELS
#include <immintrin.h>

#include <cstdint>

#include "voca/frontend/patch_kernels.h"
#endif

namespace voca::patch_kernels {

#if VOCA_AVX2_KERNELS

bool avx2Available() {
  static const bool available = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;  // also checks that the OS saves the wide registers
  }();
  return available;
}

namespace {

// (p[0], p[1]) of each of the eight pointers at data + offset[k], as two eight-lane vectors.
[[gnu::target("avx2"), gnu::always_inline]] inline void gatherPairs8(const float* data, const std::int32_t* offset,
                                                                     __m256& first, __m256& second) {
  __m128 pair[8];
  for (int k = 0; k < 8; ++k) pair[k] = _mm_castpd_ps(_mm_load_sd(reinterpret_cast<const double*>(data + offset[k])));
  // Lanes 0-3 of the result come from points 0-3, lanes 4-7 from points 4-7.
  const __m256 points01 = _mm256_set_m128(_mm_movelh_ps(pair[4], pair[5]), _mm_movelh_ps(pair[0], pair[1]));
  const __m256 points23 = _mm256_set_m128(_mm_movelh_ps(pair[6], pair[7]), _mm_movelh_ps(pair[2], pair[3]));
  first = _mm256_shuffle_ps(points01, points23, _MM_SHUFFLE(2, 0, 2, 0));
  second = _mm256_shuffle_ps(points01, points23, _MM_SHUFFLE(3, 1, 3, 1));
}

// acc + low half, then + high half: the order in which the four-lane kernels add points i..i+3, i+4..i+7.
[[gnu::target("avx2"), gnu::always_inline]] inline __m128 addHalves(__m128 acc, __m256 v) {
  return _mm_add_ps(_mm_add_ps(acc, _mm256_castps256_ps128(v)), _mm256_extractf128_ps(v, 1));
}

}  // namespace

// The operations of sampleWarped<Sse2> (warpPoints, cellOffsets, bilinear) on eight lanes, in the same order.
[[gnu::target("avx2")]] float sampleWarpedAvx2(const float* data, std::ptrdiff_t stride, const PatchPattern& pattern,
                                               int n, float c, float s, float tx, float ty, float* out,
                                               const std::array<float, PatchPattern::kMaxSize>* step, float* dots) {
  using V = simd4::Sse2;
  const __m256 vc = _mm256_set1_ps(c), vs = _mm256_set1_ps(s), vtx = _mm256_set1_ps(tx), vty = _mm256_set1_ps(ty);
  const __m256 vstride = _mm256_set1_ps(static_cast<float>(stride));
  __m128 total = _mm_setzero_ps(), dot0 = total, dot1 = total, dot2 = total;
  int i = 0;
  for (; i + 8 <= n; i += 8) {
    const __m256 qx = _mm256_loadu_ps(pattern.x.data() + i), qy = _mm256_loadu_ps(pattern.y.data() + i);
    const __m256 x = _mm256_add_ps(_mm256_sub_ps(_mm256_mul_ps(vc, qx), _mm256_mul_ps(vs, qy)), vtx);
    const __m256 y = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(vs, qx), _mm256_mul_ps(vc, qy)), vty);
    const __m256 ix = _mm256_cvtepi32_ps(_mm256_cvttps_epi32(x)), iy = _mm256_cvtepi32_ps(_mm256_cvttps_epi32(y));
    const __m256 fx = _mm256_sub_ps(x, ix), fy = _mm256_sub_ps(y, iy);
    alignas(32) std::int32_t offset[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(offset),
                       _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(iy, vstride), ix)));
    __m256 top_left, top_right, bottom_left, bottom_right;
    gatherPairs8(data, offset, top_left, top_right);
    gatherPairs8(data + stride, offset, bottom_left, bottom_right);
    const __m256 top = _mm256_add_ps(top_left, _mm256_mul_ps(fx, _mm256_sub_ps(top_right, top_left)));
    const __m256 bottom = _mm256_add_ps(bottom_left, _mm256_mul_ps(fx, _mm256_sub_ps(bottom_right, bottom_left)));
    const __m256 v = _mm256_add_ps(top, _mm256_mul_ps(fy, _mm256_sub_ps(bottom, top)));
    if (out != nullptr) _mm256_storeu_ps(out + i, v);
    if (step != nullptr) {
      dot0 = addHalves(dot0, _mm256_mul_ps(_mm256_loadu_ps(step[0].data() + i), v));
      dot1 = addHalves(dot1, _mm256_mul_ps(_mm256_loadu_ps(step[1].data() + i), v));
      dot2 = addHalves(dot2, _mm256_mul_ps(_mm256_loadu_ps(step[2].data() + i), v));
    }
    total = addHalves(total, v);
  }
  // A last group of four (52 = 6 * 8 + 4) as sampleWarped<Sse2> does it.
  for (; i < n; i += 4) {
    __m128 x, y;
    warpPoints<V>(pattern, i, V::set1(c), V::set1(s), V::set1(tx), V::set1(ty), x, y);
    const __m128 v = bilinear<V>(data, stride, x, y);
    if (out != nullptr) V::store(out + i, v);
    if (step != nullptr) {
      dot0 = V::add(dot0, V::mul(V::load(step[0].data() + i), v));
      dot1 = V::add(dot1, V::mul(V::load(step[1].data() + i), v));
      dot2 = V::add(dot2, V::mul(V::load(step[2].data() + i), v));
    }
    total = V::add(total, v);
  }
  if (step != nullptr) {
    dots[0] = V::sum(dot0);
    dots[1] = V::sum(dot1);
    dots[2] = V::sum(dot2);
  }
  return V::sum(total);
}

#else

bool avx2Available() { return false; }

#endif

}  // namespace voca::patch_kernels
