// The KLT inner loops (voca/frontend/patch_kernels.h, pyramid_kernels.h): the native SIMD backend (SSE2 on x86-64,
// NEON on ARM; this test also runs under qemu-aarch64 in CI) against the portable one, and both
// against the scalar per-point samplers of patch.h.

#include <doctest/doctest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "voca/frontend/patch.h"
#include "voca/frontend/patch_kernels.h"
#include "voca/frontend/patch_kernels_avx2.h"
#include "voca/frontend/pyramid_kernels.h"
#include "voca/frontend/simd4.h"

using namespace voca;
namespace kernels = voca::patch_kernels;

namespace {

// A float image of smooth random structure plus pixel noise, so interpolation and gradients see
// every kind of local shape; values stay positive like intensities.
FloatImage randomImage(int width, int height, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  FloatImage image(width, height);
  const float a = 0.05f + 0.2f * unit(rng), b = 0.05f + 0.2f * unit(rng);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      image(x, y) = 120.f + 60.f * std::sin(a * static_cast<float>(x) + b * static_cast<float>(y)) + 40.f * unit(rng);
  return image;
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

}  // namespace

TEST_CASE("simd4: the native backend is the one this build should use") {
  MESSAGE("native backend: " << std::string(simd4::Native::kName));
#if defined(__ARM_NEON)
  CHECK(std::string(simd4::Native::kName) == "neon");
#elif defined(__SSE2__)
  CHECK(std::string(simd4::Native::kName) == "sse2");
#else
  CHECK(std::string(simd4::Native::kName) == "portable");
#endif
}

TEST_CASE("simd4: lane operations agree with the portable backend bit for bit") {
  using N = simd4::Native;
  using P = simd4::Portable;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> dist(-300.f, 300.f);
  for (int trial = 0; trial < 200; ++trial) {
    float a[4], b[4], n_out[4], p_out[4];
    for (int k = 0; k < 4; ++k) {
      a[k] = dist(rng);
      b[k] = dist(rng);
    }
    N::store(n_out, N::add(N::mul(N::load(a), N::load(b)), N::truncate(N::sub(N::load(a), N::load(b)))));
    P::store(p_out, P::add(P::mul(P::load(a), P::load(b)), P::truncate(P::sub(P::load(a), P::load(b)))));
    for (int k = 0; k < 4; ++k) CHECK(sameBits(n_out[k], p_out[k]));
    CHECK(sameBits(N::sum(N::load(a)), P::sum(P::load(a))));
    std::int32_t n_int[4], p_int[4];
    N::toInt(N::load(a), n_int);
    P::toInt(P::load(a), p_int);
    for (int k = 0; k < 4; ++k) CHECK(n_int[k] == p_int[k]);
  }
  // Known answers: truncation goes towards zero, the sum is (a0 + a1) + (a2 + a3).
  const float values[4] = {1.75f, -1.75f, 2.5f, 1e8f};
  float truncated[4];
  N::store(truncated, N::truncate(N::load(values)));
  CHECK(truncated[0] == 1.f);
  CHECK(truncated[1] == -1.f);
  CHECK(truncated[2] == 2.f);
  CHECK(N::sum(N::load(values)) == (1.75f + -1.75f) + (2.5f + 1e8f));
  // Gathers: lane k reads from pointer k.
  const float rows[4][4] = {{1, 2, 3, 4}, {5, 6, 7, 8}, {9, 10, 11, 12}, {13, 14, 15, 16}};
  const float* p[4] = {rows[0], rows[1], rows[2], rows[3]};
  N::F columns[4], first, second;
  N::gather4(p, columns);
  N::gather2(p, first, second);
  float out[4];
  for (int j = 0; j < 4; ++j) {
    N::store(out, columns[j]);
    for (int k = 0; k < 4; ++k) CHECK(out[k] == rows[k][j]);
  }
  N::store(out, second);
  for (int k = 0; k < 4; ++k) CHECK(out[k] == rows[k][1]);
}

TEST_CASE("patch kernels: template sampling, native == portable, and both match sampleWithGradient") {
  const FloatImage image = randomImage(96, 80, 11);
  const FloatView view = image.view();
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> pos(10.f, 70.f);
  for (const PatchPattern* pattern : {&pattern24(), &pattern52()}) {
    for (int trial = 0; trial < 100; ++trial) {
      const Eigen::Vector2f centre(pos(rng), pos(rng));
      const int ix = static_cast<int>(centre.x()), iy = static_cast<int>(centre.y());
      const float fx = centre.x() - static_cast<float>(ix), fy = centre.y() - static_cast<float>(iy);
      const float* base = &view(ix, iy);
      std::array<float, PatchPattern::kMaxSize> nv, ntx, nty, nth, pv, ptx, pty, pth;
      const float n_sum = kernels::sampleTemplate<simd4::Native>(base, view.stride, *pattern, fx, fy, nv.data(),
                                                                 ntx.data(), nty.data(), nth.data());
      const float p_sum = kernels::sampleTemplate<simd4::Portable>(base, view.stride, *pattern, fx, fy, pv.data(),
                                                                   ptx.data(), pty.data(), pth.data());
      CHECK(sameBits(n_sum, p_sum));
      double reference_sum = 0.0;
      for (int i = 0; i < pattern->size; ++i) {
        const auto k = static_cast<std::size_t>(i);
        CHECK(sameBits(nv[k], pv[k]));
        CHECK(sameBits(ntx[k], ptx[k]));
        CHECK(sameBits(nty[k], pty[k]));
        CHECK(sameBits(nth[k], pth[k]));
        // The per-point scalar sampler computes the same interpolation with weights formed per
        // point; float rounding differs by a few ulps of values up to ~250.
        const Eigen::Vector3f ref = sampleWithGradient(view, centre.x() + pattern->x[k], centre.y() + pattern->y[k]);
        CHECK(std::abs(nv[k] - ref[0]) < 1e-3f);
        CHECK(std::abs(ntx[k] - ref[1]) < 1e-3f);
        CHECK(std::abs(nty[k] - ref[2]) < 1e-3f);
        CHECK(std::abs(nth[k] - (-ref[1] * pattern->y[k] + ref[2] * pattern->x[k])) < 1e-2f);
        reference_sum += ref[0];
      }
      CHECK(std::abs(n_sum - reference_sum) < 1e-2);
    }
  }
}

TEST_CASE("patch kernels: warped sampling and fused dot products, native == portable == sampleBilinear") {
  const FloatImage image = randomImage(120, 90, 5);
  const FloatView view = image.view();
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> pos(15.f, 70.f), angle(-0.8f, 0.8f), weight(-2.f, 2.f);
  std::array<float, PatchPattern::kMaxSize> step[3];
  for (auto& row : step)
    for (float& w : row) w = weight(rng);
  for (const PatchPattern* pattern : {&pattern24(), &pattern52()}) {
    const int n = pattern->size;
    for (int trial = 0; trial < 100; ++trial) {
      const float theta = angle(rng), c = std::cos(theta), s = std::sin(theta);
      const float tx = pos(rng), ty = pos(rng);
      std::array<float, PatchPattern::kMaxSize> n_out, p_out;
      float n_dots[3], p_dots[3];
      const float n_sum = kernels::sampleWarped<simd4::Native>(view.data, view.stride, *pattern, n, c, s, tx, ty,
                                                               n_out.data(), step, n_dots);
      const float p_sum = kernels::sampleWarped<simd4::Portable>(view.data, view.stride, *pattern, n, c, s, tx, ty,
                                                                 p_out.data(), step, p_dots);
      CHECK(sameBits(n_sum, p_sum));
      for (int r = 0; r < 3; ++r) CHECK(sameBits(n_dots[r], p_dots[r]));
      double dots[3] = {0.0, 0.0, 0.0};
      for (int i = 0; i < n; ++i) {
        const auto k = static_cast<std::size_t>(i);
        CHECK(sameBits(n_out[k], p_out[k]));
        const float x = c * pattern->x[k] - s * pattern->y[k] + tx;
        const float y = s * pattern->x[k] + c * pattern->y[k] + ty;
        // Same expression, same operation order: identical to the scalar sampler.
        CHECK(sameBits(n_out[k], sampleBilinear(view, x, y)));
        for (int r = 0; r < 3; ++r) dots[r] += static_cast<double>(step[r][k]) * n_out[k];
      }
      // Float accumulation of up to 52 products of size ~500 against a double one.
      for (int r = 0; r < 3; ++r) CHECK(std::abs(n_dots[r] - dots[r]) < 0.05);
      // Without outputs the sum is the same.
      CHECK(sameBits(kernels::sampleWarped<simd4::Native>(view.data, view.stride, *pattern, n, c, s, tx, ty, nullptr,
                                                          nullptr, nullptr),
                     n_sum));
    }
  }
}

TEST_CASE("patch kernels: the AVX2 warped sampling equals the portable kernel bit for bit") {
#if VOCA_AVX2_KERNELS
  if (!kernels::avx2Available()) {
    MESSAGE("this CPU has no AVX2: the AVX2 kernel is not run (the tracker uses sampleWarped<Native>)");
    return;
  }
  // Rotations up to 0.8 rad put the eight lanes of a step on different rows and cells; 24 points
  // leave no tail group, 52 one group of four.
  const FloatImage image = randomImage(120, 90, 31);
  const FloatView view = image.view();
  std::mt19937 rng(37);
  std::uniform_real_distribution<float> pos(15.f, 70.f), angle(-0.8f, 0.8f), weight(-2.f, 2.f);
  std::array<float, PatchPattern::kMaxSize> step[3];
  for (auto& row : step)
    for (float& w : row) w = weight(rng);
  int compared = 0;
  for (const PatchPattern* pattern : {&pattern24(), &pattern52()}) {
    const int n = pattern->size;
    for (int trial = 0; trial < 200; ++trial) {
      const float theta = trial % 4 == 0 ? 0.f : angle(rng), c = std::cos(theta), s = std::sin(theta);
      const float tx = pos(rng), ty = pos(rng);
      std::array<float, PatchPattern::kMaxSize> a_out{}, p_out{};
      float a_dots[3], p_dots[3];
      const float a_sum =
          kernels::sampleWarpedAvx2(view.data, view.stride, *pattern, n, c, s, tx, ty, a_out.data(), step, a_dots);
      const float p_sum = kernels::sampleWarped<simd4::Portable>(view.data, view.stride, *pattern, n, c, s, tx, ty,
                                                                 p_out.data(), step, p_dots);
      CHECK(sameBits(a_sum, p_sum));
      for (int r = 0; r < 3; ++r) CHECK(sameBits(a_dots[r], p_dots[r]));
      for (int i = 0; i < n; ++i)
        CHECK(sameBits(a_out[static_cast<std::size_t>(i)], p_out[static_cast<std::size_t>(i)]));
      // Every combination of the outputs (each its own loop): the tracker's two uses, samples only
      // (patchResidual) and dot products only (alignPatch), and the sum alone.
      std::array<float, PatchPattern::kMaxSize> samples_only{};
      CHECK(sameBits(kernels::sampleWarpedAvx2(view.data, view.stride, *pattern, n, c, s, tx, ty, samples_only.data(),
                                               nullptr, nullptr),
                     p_sum));
      for (int i = 0; i < n; ++i)
        CHECK(sameBits(samples_only[static_cast<std::size_t>(i)], p_out[static_cast<std::size_t>(i)]));
      CHECK(sameBits(
          kernels::sampleWarpedAvx2(view.data, view.stride, *pattern, n, c, s, tx, ty, nullptr, step, a_dots), p_sum));
      for (int r = 0; r < 3; ++r) CHECK(sameBits(a_dots[r], p_dots[r]));
      CHECK(sameBits(
          kernels::sampleWarpedAvx2(view.data, view.stride, *pattern, n, c, s, tx, ty, nullptr, nullptr, nullptr),
          p_sum));
      ++compared;
    }
  }
  CHECK(compared == 400);
#else
  CHECK_FALSE(kernels::avx2Available());
#endif
}

TEST_CASE("patch kernels: the AVX2 template sampling equals the portable kernel bit for bit") {
#if VOCA_AVX2_KERNELS
  if (!kernels::avx2Available()) {
    MESSAGE("this CPU has no AVX2: the AVX2 kernel is not run (the tracker uses sampleTemplate<Native>)");
    return;
  }
  const FloatImage image = randomImage(96, 80, 41);
  const FloatView view = image.view();
  std::mt19937 rng(43);
  std::uniform_real_distribution<float> pos(10.f, 70.f);
  int compared = 0;
  for (const PatchPattern* pattern : {&pattern24(), &pattern52()}) {
    for (int trial = 0; trial < 200; ++trial) {
      // Every fourth centre on integer pixels: the weights are then 0 and 1.
      const Eigen::Vector2f centre = trial % 4 == 0 ? Eigen::Vector2f(std::floor(pos(rng)), std::floor(pos(rng)))
                                                    : Eigen::Vector2f(pos(rng), pos(rng));
      const int ix = static_cast<int>(centre.x()), iy = static_cast<int>(centre.y());
      const float fx = centre.x() - static_cast<float>(ix), fy = centre.y() - static_cast<float>(iy);
      const float* base = &view(ix, iy);
      std::array<float, PatchPattern::kMaxSize> av, atx, aty, ath, pv, ptx, pty, pth;
      const float a_sum = kernels::sampleTemplateAvx2(base, view.stride, *pattern, fx, fy, av.data(), atx.data(),
                                                      aty.data(), ath.data());
      const float p_sum = kernels::sampleTemplate<simd4::Portable>(base, view.stride, *pattern, fx, fy, pv.data(),
                                                                   ptx.data(), pty.data(), pth.data());
      CHECK(sameBits(a_sum, p_sum));
      for (int i = 0; i < pattern->size; ++i) {
        const auto k = static_cast<std::size_t>(i);
        CHECK(sameBits(av[k], pv[k]));
        CHECK(sameBits(atx[k], ptx[k]));
        CHECK(sameBits(aty[k], pty[k]));
        CHECK(sameBits(ath[k], pth[k]));
      }
      ++compared;
    }
  }
  CHECK(compared == 400);
#else
  CHECK_FALSE(kernels::avx2Available());
#endif
}

TEST_CASE("patch kernels: masked template sampling, native == portable == per-point sampleWithGradient") {
  // Centres from outside the image to past its far border, so patches are cut by every edge.
  const FloatImage image = randomImage(64, 48, 21);
  const FloatView view = image.view();
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> px(-6.f, 70.f), py(-6.f, 54.f);
  int partial = 0;
  for (const PatchPattern* pattern : {&pattern24(), &pattern52()}) {
    for (int trial = 0; trial < 300; ++trial) {
      const float cx = px(rng), cy = py(rng);
      std::array<float, PatchPattern::kMaxSize> nv, ntx, nty, nth, pv, ptx, pty, pth;
      const std::uint64_t n_mask = kernels::sampleTemplateMasked<simd4::Native>(view, *pattern, cx, cy, nv.data(),
                                                                                ntx.data(), nty.data(), nth.data());
      const std::uint64_t p_mask = kernels::sampleTemplateMasked<simd4::Portable>(view, *pattern, cx, cy, pv.data(),
                                                                                  ptx.data(), pty.data(), pth.data());
      CHECK(n_mask == p_mask);
      int inside = 0;
      for (int i = 0; i < pattern->size; ++i) {
        const auto k = static_cast<std::size_t>(i);
        CHECK(sameBits(nv[k], pv[k]));
        CHECK(sameBits(ntx[k], ptx[k]));
        CHECK(sameBits(nty[k], pty[k]));
        CHECK(sameBits(nth[k], pth[k]));
        // Bit for bit what the per-point sampler gives, with the same validity test.
        const float x = cx + pattern->x[k], y = cy + pattern->y[k];
        const bool ok = canSample(view, x, y);
        CHECK(((n_mask >> i) & 1u) == (ok ? 1u : 0u));
        if (!ok) {
          CHECK(nv[k] == -1.f);
          CHECK((ntx[k] == 0.f && nty[k] == 0.f && nth[k] == 0.f));
          continue;
        }
        ++inside;
        const Eigen::Vector3f ref = sampleWithGradient(view, x, y);
        CHECK(sameBits(nv[k], ref[0]));
        CHECK(sameBits(ntx[k], ref[1]));
        CHECK(sameBits(nty[k], ref[2]));
        CHECK(sameBits(nth[k], -ref[1] * pattern->y[k] + ref[2] * pattern->x[k]));
      }
      partial += inside > 0 && inside < pattern->size;
    }
  }
  CHECK(partial > 50);  // the trials do cut patches at the border
}

TEST_CASE("patch kernels: masked warped sampling, native == portable == per-point sampleBilinear") {
  const FloatImage image = randomImage(64, 48, 8);
  const FloatView view = image.view();
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> px(-6.f, 70.f), py(-6.f, 54.f), angle(-0.8f, 0.8f), unit(0.f, 1.f);
  int partial = 0;
  for (const PatchPattern* pattern : {&pattern24(), &pattern52()}) {
    const int n = pattern->size;
    for (int trial = 0; trial < 300; ++trial) {
      const float theta = angle(rng), c = std::cos(theta), s = std::sin(theta);
      const float tx = px(rng), ty = py(rng);
      // Template values, some marked invalid (-1) as PatchTemplate does.
      std::array<float, PatchPattern::kMaxSize> keep;
      for (float& v : keep) v = unit(rng) < 0.2f ? -1.f : 0.5f + unit(rng);
      std::array<float, PatchPattern::kMaxSize> n_out, p_out;
      const std::uint64_t n_mask =
          kernels::sampleWarpedMasked<simd4::Native>(view, *pattern, n, c, s, tx, ty, keep.data(), n_out.data());
      const std::uint64_t p_mask =
          kernels::sampleWarpedMasked<simd4::Portable>(view, *pattern, n, c, s, tx, ty, keep.data(), p_out.data());
      CHECK(n_mask == p_mask);
      int sampled = 0;
      for (int i = 0; i < n; ++i) {
        const auto k = static_cast<std::size_t>(i);
        CHECK(sameBits(n_out[k], p_out[k]));
        const float x = c * pattern->x[k] - s * pattern->y[k] + tx;
        const float y = s * pattern->x[k] + c * pattern->y[k] + ty;
        const bool ok = keep[k] >= 0.f && canSample(view, x, y);
        CHECK(((n_mask >> i) & 1u) == (ok ? 1u : 0u));
        CHECK(sameBits(n_out[k], ok ? sampleBilinear(view, x, y) : -1.f));
        sampled += ok;
      }
      partial += sampled > 0 && sampled < n;
    }
  }
  CHECK(partial > 50);
}

TEST_CASE("patch kernels: the AVX2 masked warped sampling equals the portable kernel bit for bit") {
#if VOCA_AVX2_KERNELS
  if (!kernels::avx2Available()) {
    MESSAGE("this CPU has no AVX2: the AVX2 kernel is not run (the tracker uses sampleWarpedMasked<Native>)");
    return;
  }
  // Centres from outside the image to inside, so groups of eight fall wholly out, wholly in and
  // across the border; some template points invalid (-1) as PatchTemplate marks them.
  const FloatImage image = randomImage(64, 48, 51);
  const FloatView view = image.view();
  std::mt19937 rng(53);
  std::uniform_real_distribution<float> px(-10.f, 74.f), py(-10.f, 58.f), angle(-0.8f, 0.8f), unit(0.f, 1.f);
  int partial = 0, empty = 0, full = 0;
  for (const PatchPattern* pattern : {&pattern24(), &pattern52()}) {
    const int n = pattern->size;
    for (int trial = 0; trial < 400; ++trial) {
      const float theta = trial % 4 == 0 ? 0.f : angle(rng), c = std::cos(theta), s = std::sin(theta);
      const float tx = px(rng), ty = py(rng);
      std::array<float, PatchPattern::kMaxSize> keep;
      for (float& v : keep) v = trial % 3 == 0 ? 1.f : (unit(rng) < 0.2f ? -1.f : 0.5f + unit(rng));
      std::array<float, PatchPattern::kMaxSize> a_out, p_out;
      a_out.fill(7.f);
      p_out.fill(7.f);
      const std::uint64_t a_mask =
          kernels::sampleWarpedMaskedAvx2(view, *pattern, n, c, s, tx, ty, keep.data(), a_out.data());
      const std::uint64_t p_mask =
          kernels::sampleWarpedMasked<simd4::Portable>(view, *pattern, n, c, s, tx, ty, keep.data(), p_out.data());
      CHECK(a_mask == p_mask);
      for (int i = 0; i < n; ++i)
        CHECK(sameBits(a_out[static_cast<std::size_t>(i)], p_out[static_cast<std::size_t>(i)]));
      const int sampled = std::popcount(p_mask);
      partial += sampled > 0 && sampled < n;
      empty += sampled == 0;
      full += sampled == n;
    }
  }
  // Every kind of group was met.
  CHECK(partial > 100);
  CHECK(empty > 10);
  CHECK(full > 10);
#else
  CHECK_FALSE(kernels::avx2Available());
#endif
}

TEST_CASE("patch kernels: template normalisation, native == portable == the per-point formula") {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> unit(0.f, 1.f), grad(-50.f, 50.f);
  for (int trial = 0; trial < 50; ++trial) {
    std::array<float, PatchPattern::kMaxSize> value, jpix[3], n_jac[3], p_jac[3];
    for (std::size_t k = 0; k < value.size(); ++k) {
      value[k] = unit(rng) < 0.15f ? -1.f : 255.f * unit(rng);  // -1 marks an invalid point
      for (auto& row : jpix) row[k] = grad(rng);
    }
    const float jsum[3] = {grad(rng), grad(rng), grad(rng)};
    const float inv_mean = 1.f / (50.f + 100.f * unit(rng));
    std::array<float, PatchPattern::kMaxSize> n_value = value, p_value = value;
    kernels::normaliseTemplate<simd4::Native>(52, inv_mean, jsum, n_value.data(), jpix, n_jac);
    kernels::normaliseTemplate<simd4::Portable>(52, inv_mean, jsum, p_value.data(), jpix, p_jac);
    for (std::size_t k = 0; k < 52; ++k) {
      const bool ok = value[k] >= 0.f;
      const float expected = ok ? value[k] * inv_mean : -1.f;
      CHECK(sameBits(n_value[k], expected));
      CHECK(sameBits(p_value[k], expected));
      for (int c = 0; c < 3; ++c) {
        const float expected_jac = ok ? (jpix[c][k] - expected * jsum[c]) * inv_mean : 0.f;
        CHECK(sameBits(n_jac[c][k], expected_jac));
        CHECK(sameBits(p_jac[c][k], expected_jac));
      }
    }
  }
}

TEST_CASE("patch kernels: fused H = J^T J and H^-1 J^T rows, native == portable == separate dots") {
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> unit(0.f, 1.f), grad(-5.f, 5.f);
  for (const int n : {24, 52}) {
    for (int trial = 0; trial < 50; ++trial) {
      std::array<float, PatchPattern::kMaxSize> jac[3], value;
      for (std::size_t k = 0; k < value.size(); ++k) {
        value[k] = unit(rng) < 0.15f ? -1.f : 2.f * unit(rng);
        for (auto& row : jac) row[k] = grad(rng);
      }
      float n_h[3][3], p_h[3][3];
      kernels::gram3<simd4::Native>(jac, n, n_h);
      kernels::gram3<simd4::Portable>(jac, n, p_h);
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
          const float expected = kernels::dot<simd4::Portable>(jac[a].data(), jac[b].data(), n);
          CHECK(sameBits(n_h[a][b], expected));
          CHECK(sameBits(p_h[a][b], expected));
        }
      }
      float inverse[3][3];
      for (auto& row : inverse)
        for (float& x : row) x = grad(rng);
      std::array<float, PatchPattern::kMaxSize> n_step[3], p_step[3];
      float n_dots[3], p_dots[3];
      kernels::stepRows<simd4::Native>(inverse, jac, value.data(), n, n_step, n_dots);
      kernels::stepRows<simd4::Portable>(inverse, jac, value.data(), n, p_step, p_dots);
      for (int r = 0; r < 3; ++r) {
        for (int i = 0; i < n; ++i) {
          const auto k = static_cast<std::size_t>(i);
          const float expected = inverse[r][0] * jac[0][k] + inverse[r][1] * jac[1][k] + inverse[r][2] * jac[2][k];
          CHECK(sameBits(n_step[r][k], expected));
          CHECK(sameBits(p_step[r][k], expected));
        }
        const float expected_dot = kernels::dot<simd4::Portable>(p_step[r].data(), value.data(), n);
        CHECK(sameBits(n_dots[r], expected_dot));
        CHECK(sameBits(p_dots[r], expected_dot));
      }
    }
  }
}

TEST_CASE("simd4: comparisons, select and lane bits agree with the portable backend") {
  using N = simd4::Native;
  using P = simd4::Portable;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float a[4] = {1.f, 2.f, nan, -3.f}, b[4] = {2.f, 2.f, 0.f, -4.f};
  const float x[4] = {10.f, 20.f, 30.f, 40.f}, y[4] = {-1.f, -2.f, -3.f, -4.f};
  // a < b: lane 0 only; a <= b: lanes 0 and 1; NaN compares false.
  CHECK(N::bits(N::lessThan(N::load(a), N::load(b))) == 0b0001u);
  CHECK(N::bits(N::lessEqual(N::load(a), N::load(b))) == 0b0011u);
  CHECK(P::bits(P::lessThan(P::load(a), P::load(b))) == 0b0001u);
  CHECK(P::bits(P::lessEqual(P::load(a), P::load(b))) == 0b0011u);
  CHECK(N::bits(N::both(N::lessEqual(N::load(a), N::load(b)), N::lessThan(N::load(b), N::load(a)))) == 0u);
  CHECK(N::bits(N::lessEqual(N::load(b), N::load(a))) == 0b1010u);
  float out[4];
  N::store(out, N::select(N::lessEqual(N::load(a), N::load(b)), N::load(x), N::load(y)));
  CHECK((out[0] == 10.f && out[1] == 20.f && out[2] == -3.f && out[3] == -4.f));
  P::store(out, P::select(P::lessEqual(P::load(a), P::load(b)), P::load(x), P::load(y)));
  CHECK((out[0] == 10.f && out[1] == 20.f && out[2] == -3.f && out[3] == -4.f));
}

TEST_CASE("patch kernels: dot and sum, native == portable, against a double reference") {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> dist(-10.f, 10.f);
  std::array<float, PatchPattern::kMaxSize> a, b;
  for (int trial = 0; trial < 50; ++trial) {
    for (std::size_t k = 0; k < a.size(); ++k) {
      a[k] = dist(rng);
      b[k] = dist(rng);
    }
    for (int n : {4, 24, 52}) {
      const float nd = kernels::dot<simd4::Native>(a.data(), b.data(), n);
      CHECK(sameBits(nd, kernels::dot<simd4::Portable>(a.data(), b.data(), n)));
      const float ns = kernels::sum<simd4::Native>(a.data(), n);
      CHECK(sameBits(ns, kernels::sum<simd4::Portable>(a.data(), n)));
      double rd = 0.0, rs = 0.0;
      for (int i = 0; i < n; ++i) {
        rd += static_cast<double>(a[static_cast<std::size_t>(i)]) * b[static_cast<std::size_t>(i)];
        rs += a[static_cast<std::size_t>(i)];
      }
      CHECK(std::abs(nd - rd) < 1e-3);
      CHECK(std::abs(ns - rs) < 1e-4);
    }
  }
}

TEST_CASE("pyramid kernel: row reduction, native == portable == the [1 4 6 4 1]/16 formula") {
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> dist(0.f, 255.f);
  std::vector<float> row(101);
  for (float& v : row) v = dist(rng);
  // Outputs x in [1, 46): reads s[2x - 2] .. s[2x + 9] of the last block, inside the 101 values.
  std::vector<float> native(50, -1.f), portable(50, -1.f);
  const int native_end = pyramid_kernels::reduceRow<simd4::Native>(row.data(), native.data(), 1, 46);
  const int portable_end = pyramid_kernels::reduceRow<simd4::Portable>(row.data(), portable.data(), 1, 46);
  CHECK(native_end == 45);  // blocks of four from 1: the 45th output is left to the caller
  CHECK(portable_end == native_end);
  for (int x = 1; x < native_end; ++x) {
    const float* c = row.data() + 2 * x;
    const float expected = (c[-2] + c[2] + 4.f * (c[-1] + c[1]) + 6.f * c[0]) * (1.f / 16.f);
    CHECK(sameBits(native[static_cast<std::size_t>(x)], expected));
    CHECK(sameBits(portable[static_cast<std::size_t>(x)], expected));
  }
  CHECK(native[0] == -1.f);  // nothing written outside [begin, end)
  CHECK(native[45] == -1.f);
}
