#pragma once
// Four-lane float vectors for the KLT inner loops, with one backend per instruction set: SSE2 (the
// x86-64 baseline), NEON (AArch64, and 32-bit ARM built with NEON) and a portable one in plain C++.
// Kernels are templates over the backend (see patch_kernels.h), so the portable path is compiled
// and tested on every machine next to the native one.
//
// Every backend performs the same IEEE operations in the same order (separate multiply and add, no
// fused multiply-add; ISO C++ mode keeps the compiler from contracting the portable code), so the
// native and portable kernels give bit-identical results. The tests rely on that.

#include <cstdint>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__ARM_NEON)
#include <arm_neon.h>
#endif

namespace voca::simd4 {

// Plain C++: what every build can run, and the reference the native backends are tested against.
struct Portable {
  static constexpr const char* kName = "portable";
  struct F {
    float v[4];
  };
  // A lane mask: the outcome of a comparison per lane.
  struct M {
    bool v[4];
  };

  static F load(const float* p) { return {{p[0], p[1], p[2], p[3]}}; }
  static void store(float* p, F a) { std::memcpy(p, a.v, sizeof(a.v)); }
  static F set1(float s) { return {{s, s, s, s}}; }
  static F add(F a, F b) { return {{a.v[0] + b.v[0], a.v[1] + b.v[1], a.v[2] + b.v[2], a.v[3] + b.v[3]}}; }
  static F sub(F a, F b) { return {{a.v[0] - b.v[0], a.v[1] - b.v[1], a.v[2] - b.v[2], a.v[3] - b.v[3]}}; }
  static F mul(F a, F b) { return {{a.v[0] * b.v[0], a.v[1] * b.v[1], a.v[2] * b.v[2], a.v[3] * b.v[3]}}; }
  // Rounds towards zero, as the float-to-int conversion of C++ and of SSE2/NEON does.
  static F truncate(F a) {
    F r;
    for (int k = 0; k < 4; ++k) r.v[k] = static_cast<float>(static_cast<std::int32_t>(a.v[k]));
    return r;
  }
  static void toInt(F a, std::int32_t* out) {
    for (int k = 0; k < 4; ++k) out[k] = static_cast<std::int32_t>(a.v[k]);
  }
  // ((a0 + a1) + (a2 + a3)), the order the native backends use.
  static float sum(F a) { return (a.v[0] + a.v[1]) + (a.v[2] + a.v[3]); }
  // Ordered comparisons: false when either side is NaN, as in scalar C++.
  static M lessThan(F a, F b) { return {{a.v[0] < b.v[0], a.v[1] < b.v[1], a.v[2] < b.v[2], a.v[3] < b.v[3]}}; }
  static M lessEqual(F a, F b) { return {{a.v[0] <= b.v[0], a.v[1] <= b.v[1], a.v[2] <= b.v[2], a.v[3] <= b.v[3]}}; }
  static M both(M a, M b) { return {{a.v[0] && b.v[0], a.v[1] && b.v[1], a.v[2] && b.v[2], a.v[3] && b.v[3]}}; }
  // Lane k of a where the mask is set, of b elsewhere.
  static F select(M m, F a, F b) {
    return {{m.v[0] ? a.v[0] : b.v[0], m.v[1] ? a.v[1] : b.v[1], m.v[2] ? a.v[2] : b.v[2], m.v[3] ? a.v[3] : b.v[3]}};
  }
  // Bit k set when lane k of the mask is.
  static unsigned bits(M m) {
    return static_cast<unsigned>(m.v[0]) | static_cast<unsigned>(m.v[1]) << 1 | static_cast<unsigned>(m.v[2]) << 2 |
           static_cast<unsigned>(m.v[3]) << 3;
  }
  // first = (p0[0], p1[0], p2[0], p3[0]), second = (p0[1], ..., p3[1]).
  static void gather2(const float* const p[4], F& first, F& second) {
    for (int k = 0; k < 4; ++k) {
      first.v[k] = p[k][0];
      second.v[k] = p[k][1];
    }
  }
  // out[j] = (p0[j], p1[j], p2[j], p3[j]) for j = 0..3: four rows of four, transposed.
  static void gather4(const float* const p[4], F out[4]) {
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) out[j].v[k] = p[k][j];
  }
  // even = (p[0], p[2], p[4], p[6]), odd = (p[1], p[3], p[5], p[7]).
  static void deinterleave(const float* p, F& even, F& odd) {
    for (int k = 0; k < 4; ++k) {
      even.v[k] = p[2 * k];
      odd.v[k] = p[2 * k + 1];
    }
  }
};

#if defined(__SSE2__)
struct Sse2 {
  static constexpr const char* kName = "sse2";
  using F = __m128;
  using M = __m128;  // all bits set in lanes where a comparison holds

  static F load(const float* p) { return _mm_loadu_ps(p); }
  static void store(float* p, F a) { _mm_storeu_ps(p, a); }
  static F set1(float s) { return _mm_set1_ps(s); }
  static F add(F a, F b) { return _mm_add_ps(a, b); }
  static F sub(F a, F b) { return _mm_sub_ps(a, b); }
  static F mul(F a, F b) { return _mm_mul_ps(a, b); }
  static F truncate(F a) { return _mm_cvtepi32_ps(_mm_cvttps_epi32(a)); }
  static void toInt(F a, std::int32_t* out) { _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm_cvttps_epi32(a)); }
  static float sum(F a) {
    const F pairs =
        _mm_add_ps(_mm_shuffle_ps(a, a, _MM_SHUFFLE(2, 2, 0, 0)), _mm_shuffle_ps(a, a, _MM_SHUFFLE(3, 3, 1, 1)));
    return _mm_cvtss_f32(_mm_add_ss(pairs, _mm_movehl_ps(pairs, pairs)));
  }
  static M lessThan(F a, F b) { return _mm_cmplt_ps(a, b); }
  static M lessEqual(F a, F b) { return _mm_cmple_ps(a, b); }
  static M both(M a, M b) { return _mm_and_ps(a, b); }
  static F select(M m, F a, F b) { return _mm_or_ps(_mm_and_ps(m, a), _mm_andnot_ps(m, b)); }
  static unsigned bits(M m) { return static_cast<unsigned>(_mm_movemask_ps(m)); }
  static F load2(const float* p) { return _mm_castpd_ps(_mm_load_sd(reinterpret_cast<const double*>(p))); }
  static void gather2(const float* const p[4], F& first, F& second) {
    const F lo = _mm_movelh_ps(load2(p[0]), load2(p[1]));  // a0 b0 a1 b1
    const F hi = _mm_movelh_ps(load2(p[2]), load2(p[3]));  // a2 b2 a3 b3
    first = _mm_shuffle_ps(lo, hi, _MM_SHUFFLE(2, 0, 2, 0));
    second = _mm_shuffle_ps(lo, hi, _MM_SHUFFLE(3, 1, 3, 1));
  }
  static void gather4(const float* const p[4], F out[4]) {
    F r0 = _mm_loadu_ps(p[0]), r1 = _mm_loadu_ps(p[1]), r2 = _mm_loadu_ps(p[2]), r3 = _mm_loadu_ps(p[3]);
    _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
    out[0] = r0;
    out[1] = r1;
    out[2] = r2;
    out[3] = r3;
  }
  static void deinterleave(const float* p, F& even, F& odd) {
    const F lo = _mm_loadu_ps(p), hi = _mm_loadu_ps(p + 4);
    even = _mm_shuffle_ps(lo, hi, _MM_SHUFFLE(2, 0, 2, 0));
    odd = _mm_shuffle_ps(lo, hi, _MM_SHUFFLE(3, 1, 3, 1));
  }
};
#endif

#if defined(__ARM_NEON)
struct Neon {
  static constexpr const char* kName = "neon";
  using F = float32x4_t;
  using M = uint32x4_t;  // all bits set in lanes where a comparison holds

  static F load(const float* p) { return vld1q_f32(p); }
  static void store(float* p, F a) { vst1q_f32(p, a); }
  static F set1(float s) { return vdupq_n_f32(s); }
  static F add(F a, F b) { return vaddq_f32(a, b); }
  static F sub(F a, F b) { return vsubq_f32(a, b); }
  // vmulq then vaddq, never vfmaq/vmlaq: a fused multiply-add would round differently from the
  // portable path.
  static F mul(F a, F b) { return vmulq_f32(a, b); }
  static F truncate(F a) { return vcvtq_f32_s32(vcvtq_s32_f32(a)); }
  static void toInt(F a, std::int32_t* out) { vst1q_s32(out, vcvtq_s32_f32(a)); }
  static float sum(F a) {
    const float32x2_t pairs = vpadd_f32(vget_low_f32(a), vget_high_f32(a));  // a0+a1, a2+a3
    return vget_lane_f32(pairs, 0) + vget_lane_f32(pairs, 1);
  }
  static M lessThan(F a, F b) { return vcltq_f32(a, b); }
  static M lessEqual(F a, F b) { return vcleq_f32(a, b); }
  static M both(M a, M b) { return vandq_u32(a, b); }
  static F select(M m, F a, F b) { return vbslq_f32(m, a, b); }
  static unsigned bits(M m) {
    // Lane k keeps bit k; two pairwise additions (also on 32-bit ARM, which lacks vaddvq) sum them.
    static const std::uint32_t kLaneBits[4] = {1u, 2u, 4u, 8u};
    const uint32x4_t lane_bits = vandq_u32(m, vld1q_u32(kLaneBits));
    uint32x2_t pairs = vpadd_u32(vget_low_u32(lane_bits), vget_high_u32(lane_bits));
    pairs = vpadd_u32(pairs, pairs);
    return vget_lane_u32(pairs, 0);
  }
  static void gather2(const float* const p[4], F& first, F& second) {
    const float32x4x2_t split = vuzpq_f32(vcombine_f32(vld1_f32(p[0]), vld1_f32(p[1])),   // a0 b0 a1 b1
                                          vcombine_f32(vld1_f32(p[2]), vld1_f32(p[3])));  // a2 b2 a3 b3
    first = split.val[0];
    second = split.val[1];
  }
  static void gather4(const float* const p[4], F out[4]) {
    const float32x4x2_t t01 = vtrnq_f32(vld1q_f32(p[0]), vld1q_f32(p[1]));  // (a0 b0 a2 b2), (a1 b1 a3 b3)
    const float32x4x2_t t23 = vtrnq_f32(vld1q_f32(p[2]), vld1q_f32(p[3]));
    out[0] = vcombine_f32(vget_low_f32(t01.val[0]), vget_low_f32(t23.val[0]));
    out[1] = vcombine_f32(vget_low_f32(t01.val[1]), vget_low_f32(t23.val[1]));
    out[2] = vcombine_f32(vget_high_f32(t01.val[0]), vget_high_f32(t23.val[0]));
    out[3] = vcombine_f32(vget_high_f32(t01.val[1]), vget_high_f32(t23.val[1]));
  }
  static void deinterleave(const float* p, F& even, F& odd) {
    const float32x4x2_t split = vld2q_f32(p);
    even = split.val[0];
    odd = split.val[1];
  }
};
#endif

// The backend the library uses on this build.
#if defined(__ARM_NEON)
using Native = Neon;
#elif defined(__SSE2__)
using Native = Sse2;
#else
using Native = Portable;
#endif

}  // namespace voca::simd4
