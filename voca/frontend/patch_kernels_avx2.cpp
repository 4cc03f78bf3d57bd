#include "voca/frontend/patch_kernels_avx2.h"

#if VOCA_AVX2_KERNELS
#include <immintrin.h>

#include <cstdint>
#include <cstring>

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

// (p[k][0], p[k][1]) of eight pointers as two eight-lane vectors: first lane k = p[k][0], second
// lane k = p[k][1].
[[gnu::target("avx2"), gnu::always_inline]] inline void gatherPairs8(const float* const p[8], __m256& first,
                                                                     __m256& second) {
  __m128 pair[8];
  for (int k = 0; k < 8; ++k) {
    // Two floats as one 64-bit load; memcpy, not a double* cast, which would break aliasing rules
    // (and the compiler's assumptions with them).
    double two_floats;
    std::memcpy(&two_floats, p[k], sizeof two_floats);
    pair[k] = _mm_castpd_ps(_mm_set_sd(two_floats));
  }
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

// Elements 0..3 of the eight rows at row[k], transposed: out[j] lane k = row[k][j] (each 128-bit
// half of the registers is one SSE2 transpose: lanes 0-3 rows 0-3, lanes 4-7 rows 4-7).
[[gnu::target("avx2"), gnu::always_inline]] inline void gatherRows8(const float* const row[8], __m256 out[4]) {
  __m256 r[4];
  for (int k = 0; k < 4; ++k) r[k] = _mm256_set_m128(_mm_loadu_ps(row[k + 4]), _mm_loadu_ps(row[k]));
  const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpacklo_ps(r[2], r[3]);
  const __m256 t2 = _mm256_unpackhi_ps(r[0], r[1]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
  out[0] = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
  out[1] = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
  out[2] = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
  out[3] = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2));
}

// warpPoints<Sse2> on eight lanes: the pattern's points i..i+7 rotated by (c, s) and moved by (tx, ty).
[[gnu::target("avx2"), gnu::always_inline]] inline void warpPoints8(const PatchPattern& pattern, int i, __m256 vc,
                                                                    __m256 vs, __m256 vtx, __m256 vty, __m256& x,
                                                                    __m256& y) {
  const __m256 qx = _mm256_loadu_ps(pattern.x.data() + i), qy = _mm256_loadu_ps(pattern.y.data() + i);
  x = _mm256_add_ps(_mm256_sub_ps(_mm256_mul_ps(vc, qx), _mm256_mul_ps(vs, qy)), vtx);
  y = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(vs, qx), _mm256_mul_ps(vc, qy)), vty);
}

// bilinear<Sse2> on eight lanes, in the same order: cell offsets, the two rows' pairs, then x, then y.
[[gnu::target("avx2"), gnu::always_inline]] inline __m256 bilinear8(const float* data, std::ptrdiff_t stride, __m256 x,
                                                                    __m256 y) {
  const __m256 ix = _mm256_cvtepi32_ps(_mm256_cvttps_epi32(x)), iy = _mm256_cvtepi32_ps(_mm256_cvttps_epi32(y));
  const __m256 fx = _mm256_sub_ps(x, ix), fy = _mm256_sub_ps(y, iy);
  alignas(32) std::int32_t offset[8];
  _mm256_store_si256(
      reinterpret_cast<__m256i*>(offset),
      _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(iy, _mm256_set1_ps(static_cast<float>(stride))), ix)));
  __m256 top_left, top_right, bottom_left, bottom_right;
  const float* cell[8];
  for (int k = 0; k < 8; ++k) cell[k] = data + offset[k];
  gatherPairs8(cell, top_left, top_right);
  for (auto& p : cell) p += stride;
  gatherPairs8(cell, bottom_left, bottom_right);
  const __m256 top = _mm256_add_ps(top_left, _mm256_mul_ps(fx, _mm256_sub_ps(top_right, top_left)));
  const __m256 bottom = _mm256_add_ps(bottom_left, _mm256_mul_ps(fx, _mm256_sub_ps(bottom_right, bottom_left)));
  return _mm256_add_ps(top, _mm256_mul_ps(fy, _mm256_sub_ps(bottom, top)));
}

}  // namespace

// The operations of sampleTemplate<Sse2> (valueAndGradient, thetaDerivative) on eight lanes, in the same order.
[[gnu::target("avx2")]] float sampleTemplateAvx2(const float* base, std::ptrdiff_t stride, const PatchPattern& pattern,
                                                 float fx, float fy, float* value, float* d_tx, float* d_ty,
                                                 float* d_theta) {
  using V = simd4::Sse2;
  const float w00_s = (1.f - fx) * (1.f - fy), w10_s = fx * (1.f - fy);
  const float w01_s = (1.f - fx) * fy, w11_s = fx * fy;
  const __m256 w00 = _mm256_set1_ps(w00_s), w10 = _mm256_set1_ps(w10_s);
  const __m256 w01 = _mm256_set1_ps(w01_s), w11 = _mm256_set1_ps(w11_s);
  const __m256 half = _mm256_set1_ps(0.5f);
  __m128 total = _mm_setzero_ps();
  int i = 0;
  for (; i + 8 <= pattern.size; i += 8) {
    const float* row0[8];  // top-left pixel of each point's bilinear cell
    for (int k = 0; k < 8; ++k) {
      const auto j = static_cast<std::size_t>(i + k);
      row0[k] = base + static_cast<std::ptrdiff_t>(pattern.y[j]) * stride + static_cast<std::ptrdiff_t>(pattern.x[j]);
    }
    const float* from[8];
    __m256 a[4], b[4];  // a[j] = row0[j - 1], b[j] = row1[j - 1], j = 0..3
    for (int k = 0; k < 8; ++k) from[k] = row0[k] - 1;
    gatherRows8(from, a);
    for (int k = 0; k < 8; ++k) from[k] = row0[k] + stride - 1;
    gatherRows8(from, b);
    __m256 above0, above1, below0, below1;  // row0[-stride], row0[1 - stride], row1[stride], row1[stride + 1]
    for (int k = 0; k < 8; ++k) from[k] = row0[k] - stride;
    gatherPairs8(from, above0, above1);
    for (int k = 0; k < 8; ++k) from[k] = row0[k] + 2 * stride;
    gatherPairs8(from, below0, below1);
    const __m256 v = _mm256_add_ps(
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(w00, a[1]), _mm256_mul_ps(w10, a[2])), _mm256_mul_ps(w01, b[1])),
        _mm256_mul_ps(w11, b[2]));
    const __m256 gx =
        _mm256_mul_ps(half, _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(w00, _mm256_sub_ps(a[2], a[0])),
                                                                      _mm256_mul_ps(w10, _mm256_sub_ps(a[3], a[1]))),
                                                        _mm256_mul_ps(w01, _mm256_sub_ps(b[2], b[0]))),
                                          _mm256_mul_ps(w11, _mm256_sub_ps(b[3], b[1]))));
    const __m256 gy =
        _mm256_mul_ps(half, _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(w00, _mm256_sub_ps(b[1], above0)),
                                                                      _mm256_mul_ps(w10, _mm256_sub_ps(b[2], above1))),
                                                        _mm256_mul_ps(w01, _mm256_sub_ps(below0, a[1]))),
                                          _mm256_mul_ps(w11, _mm256_sub_ps(below1, a[2]))));
    const __m256 qx = _mm256_loadu_ps(pattern.x.data() + i), qy = _mm256_loadu_ps(pattern.y.data() + i);
    _mm256_storeu_ps(value + i, v);
    _mm256_storeu_ps(d_tx + i, gx);
    _mm256_storeu_ps(d_ty + i, gy);
    _mm256_storeu_ps(d_theta + i, _mm256_sub_ps(_mm256_mul_ps(gy, qx), _mm256_mul_ps(gx, qy)));
    total = addHalves(total, v);
  }
  // A last group of four (52 = 6 * 8 + 4) by the four-lane kernel's own loop.
  accumulateTemplate<V>(base, stride, pattern, i, fx, fy, value, d_tx, d_ty, d_theta, total);
  return V::sum(total);
}

namespace {

// sampleWarpedAvx2 for one combination of its optional outputs. The callers pass either `out` (a
// residual) or `step` (an alignment step): a loop without the other one's branches and pointers
// keeps its sums in registers. The same operations in the same order, so the same bits.
template <bool kOut, bool kStep>
[[gnu::target("avx2"), gnu::always_inline]] inline float sampleWarpedAvx2For(
    const float* data, std::ptrdiff_t stride, const PatchPattern& pattern, int n, float c, float s, float tx, float ty,
    float* out, const std::array<float, PatchPattern::kMaxSize>* step, float* dots) {
  using V = simd4::Sse2;
  const __m256 vc = _mm256_set1_ps(c), vs = _mm256_set1_ps(s), vtx = _mm256_set1_ps(tx), vty = _mm256_set1_ps(ty);
  __m128 total = _mm_setzero_ps(), dot0 = total, dot1 = total, dot2 = total;
  int i = 0;
  for (; i + 8 <= n; i += 8) {
    __m256 x, y;
    warpPoints8(pattern, i, vc, vs, vtx, vty, x, y);
    const __m256 v = bilinear8(data, stride, x, y);
    if constexpr (kOut) _mm256_storeu_ps(out + i, v);
    if constexpr (kStep) {
      dot0 = addHalves(dot0, _mm256_mul_ps(_mm256_loadu_ps(step[0].data() + i), v));
      dot1 = addHalves(dot1, _mm256_mul_ps(_mm256_loadu_ps(step[1].data() + i), v));
      dot2 = addHalves(dot2, _mm256_mul_ps(_mm256_loadu_ps(step[2].data() + i), v));
    }
    total = addHalves(total, v);
  }
  WarpedSums<V> sums{total, dot0, dot1, dot2};
  // A last group of four (52 = 6 * 8 + 4) by the four-lane kernel's own loop.
  accumulateWarped<V>(data, stride, pattern, i, n, c, s, tx, ty, kOut ? out : nullptr, kStep ? step : nullptr, sums);
  return finishWarped<V>(sums, kStep ? step : nullptr, dots);
}

}  // namespace

// The operations of sampleWarped<Sse2> (warpPoints, cellOffsets, bilinear) on eight lanes, in the same order.
[[gnu::target("avx2")]] float sampleWarpedAvx2(const float* data, std::ptrdiff_t stride, const PatchPattern& pattern,
                                               int n, float c, float s, float tx, float ty, float* out,
                                               const std::array<float, PatchPattern::kMaxSize>* step, float* dots) {
  if (step != nullptr) {
    if (out != nullptr) return sampleWarpedAvx2For<true, true>(data, stride, pattern, n, c, s, tx, ty, out, step, dots);
    return sampleWarpedAvx2For<false, true>(data, stride, pattern, n, c, s, tx, ty, out, step, dots);
  }
  if (out != nullptr) return sampleWarpedAvx2For<true, false>(data, stride, pattern, n, c, s, tx, ty, out, step, dots);
  return sampleWarpedAvx2For<false, false>(data, stride, pattern, n, c, s, tx, ty, out, step, dots);
}

// The operations of sampleWarpedMasked<Sse2> (warpPoints, sampleable, bilinear at the substitute
// cell) on eight lanes, in the same order. Each lane's sample depends on that lane alone, so the
// values and the sampled bits equal the four-lane kernel's; a group of eight with no lane inside
// writes -1 without reading, as the four-lane kernel does per group of four.
[[gnu::target("avx2")]] std::uint64_t sampleWarpedMaskedAvx2(const FloatView& image, const PatchPattern& pattern, int n,
                                                             float c, float s, float tx, float ty, const float* keep,
                                                             float* out) {
  using V = simd4::Sse2;
  const std::ptrdiff_t stride = image.stride;
  const __m256 vc = _mm256_set1_ps(c), vs = _mm256_set1_ps(s), vtx = _mm256_set1_ps(tx), vty = _mm256_set1_ps(ty);
  const __m256 one = _mm256_set1_ps(1.f), zero = _mm256_setzero_ps(), invalid = _mm256_set1_ps(-1.f);
  const __m256 x_end = _mm256_set1_ps(static_cast<float>(image.width - 2));
  const __m256 y_end = _mm256_set1_ps(static_cast<float>(image.height - 2));
  std::uint64_t sampled = 0;
  int i = 0;
  for (; i + 8 <= n; i += 8) {
    __m256 x, y;
    warpPoints8(pattern, i, vc, vs, vtx, vty, x, y);
    // Ordered comparisons (false on NaN), as _mm_cmple_ps / _mm_cmplt_ps.
    const __m256 inside = _mm256_and_ps(
        _mm256_cmp_ps(zero, _mm256_loadu_ps(keep + i), _CMP_LE_OS),
        _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(one, x, _CMP_LE_OS), _mm256_cmp_ps(one, y, _CMP_LE_OS)),
                      _mm256_and_ps(_mm256_cmp_ps(x, x_end, _CMP_LT_OS), _mm256_cmp_ps(y, y_end, _CMP_LT_OS))));
    const auto lanes = static_cast<unsigned>(_mm256_movemask_ps(inside));
    if (lanes == 0) {
      _mm256_storeu_ps(out + i, invalid);
      continue;
    }
    sampled |= static_cast<std::uint64_t>(lanes) << i;
    // A lane outside reads the cell at (1, 1) instead, which exists since some lane is inside.
    const __m256 sx = _mm256_blendv_ps(one, x, inside), sy = _mm256_blendv_ps(one, y, inside);
    const __m256 v = bilinear8(image.data, stride, sx, sy);
    _mm256_storeu_ps(out + i, _mm256_blendv_ps(invalid, v, inside));
  }
  // A last group of four (52 = 6 * 8 + 4) by the four-lane kernel itself.
  if (i < n) {
    sampled |= sampleWarpedMasked<V>(image, pattern, n, c, s, tx, ty, keep, out, i);
  }
  return sampled;
}

#else

bool avx2Available() { return false; }

#endif

}  // namespace voca::patch_kernels
