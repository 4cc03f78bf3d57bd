#pragma once
// AVX2 variants of the KLT's hottest loops (patch_kernels::sampleWarped, about 40 % of the
// frontend's time, sampleWarpedMasked near borders, and sampleTemplate), eight pattern points per step, chosen at run
// time on x86-64 CPUs that have AVX2 while the rest of the build stays at the SSE2 baseline. It keeps the four-lane
// accumulators and adds each half of an eight-lane step to them in point order, so its results equal the SSE2, NEON and
// portable kernels' bit for bit (tests/test_patch_kernels.cpp).

#include <array>
#include <cstddef>
#include <cstdint>

#include "voca/frontend/patch.h"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define VOCA_AVX2_KERNELS 1
#else
#define VOCA_AVX2_KERNELS 0
#endif

namespace voca::patch_kernels {

// True when this build has the AVX2 kernels and the CPU (and the OS, for the wider registers) runs them.
bool avx2Available();

#if VOCA_AVX2_KERNELS
// sampleWarped<V> and sampleTemplate<V> (patch_kernels.h), same arguments and the same results bit
// for bit. Only to be called when avx2Available().
float sampleWarpedAvx2(const float* data, std::ptrdiff_t stride, const PatchPattern& pattern, int n, float c, float s,
                       float tx, float ty, float* out, const std::array<float, PatchPattern::kMaxSize>* step,
                       float* dots);
// sampleWarpedMasked<V>, same arguments and results (the values and the sampled bits).
std::uint64_t sampleWarpedMaskedAvx2(const FloatView& image, const PatchPattern& pattern, int n, float c, float s,
                                     float tx, float ty, const float* keep, float* out);
float sampleTemplateAvx2(const float* base, std::ptrdiff_t stride, const PatchPattern& pattern, float fx, float fy,
                         float* value, float* d_tx, float* d_ty, float* d_theta);
#endif

}  // namespace voca::patch_kernels
