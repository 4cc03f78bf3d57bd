#pragma once
// The KLT inner loops, four pattern points at a time, as templates over a simd4 backend. patch.cpp
// runs them with simd4::Native; tests run them with simd4::Portable as well and require identical
// results. Point counts are multiples of four (both patterns are).

#include <cstddef>
#include <cstdint>

#include "voca/frontend/patch.h"
#include "voca/frontend/simd4.h"

namespace voca::patch_kernels {

// Samples the pattern around base (the pixel at the integer part of the patch centre; every point
// and its gradient neighbourhood inside the image) with the bilinear weights of the fractional part
// (fx, fy), which all points share because pattern offsets are integers. Writes the intensity and
// the derivatives of intensity with respect to (tx, ty, theta) of the warp; returns the sum of the
// intensities. The gradient is the central difference at the four cell corners, interpolated with
// the same weights (see sampleWithGradient).
template <class V>
float sampleTemplate(const float* base, std::ptrdiff_t stride, const PatchPattern& pattern, float fx, float fy,
                     float* value, float* d_tx, float* d_ty, float* d_theta) {
  using F = typename V::F;
  const F w00 = V::set1((1.f - fx) * (1.f - fy)), w10 = V::set1(fx * (1.f - fy));
  const F w01 = V::set1((1.f - fx) * fy), w11 = V::set1(fx * fy);
  const F half = V::set1(0.5f);
  F total = V::set1(0.f);
  for (int i = 0; i < pattern.size; i += 4) {
    const float* row0[4];  // top-left pixel of each point's bilinear cell
    for (int k = 0; k < 4; ++k) {
      const auto j = static_cast<std::size_t>(i + k);
      row0[k] = base + static_cast<std::ptrdiff_t>(pattern.y[j]) * stride + static_cast<std::ptrdiff_t>(pattern.x[j]);
    }
    const float* from[4];
    F a[4], b[4];  // a[j] = row0[j - 1], b[j] = row1[j - 1], j = 0..3
    for (int k = 0; k < 4; ++k) from[k] = row0[k] - 1;
    V::gather4(from, a);
    for (int k = 0; k < 4; ++k) from[k] = row0[k] + stride - 1;
    V::gather4(from, b);
    F above0, above1, below0, below1;  // row0[-stride], row0[1 - stride], row1[stride], row1[stride + 1]
    for (int k = 0; k < 4; ++k) from[k] = row0[k] - stride;
    V::gather2(from, above0, above1);
    for (int k = 0; k < 4; ++k) from[k] = row0[k] + 2 * stride;
    V::gather2(from, below0, below1);

    const F v = V::add(V::add(V::add(V::mul(w00, a[1]), V::mul(w10, a[2])), V::mul(w01, b[1])), V::mul(w11, b[2]));
    const F gx = V::mul(half, V::add(V::add(V::add(V::mul(w00, V::sub(a[2], a[0])), V::mul(w10, V::sub(a[3], a[1]))),
                                            V::mul(w01, V::sub(b[2], b[0]))),
                                     V::mul(w11, V::sub(b[3], b[1]))));
    const F gy =
        V::mul(half, V::add(V::add(V::add(V::mul(w00, V::sub(b[1], above0)), V::mul(w10, V::sub(b[2], above1))),
                                   V::mul(w01, V::sub(below0, a[1]))),
                            V::mul(w11, V::sub(below1, a[2]))));
    // d I(centre + R(theta) q + t) / d theta at identity = -gx qy + gy qx.
    const F qx = V::load(pattern.x.data() + i), qy = V::load(pattern.y.data() + i);
    V::store(value + i, v);
    V::store(d_tx + i, gx);
    V::store(d_ty + i, gy);
    V::store(d_theta + i, V::sub(V::mul(gy, qx), V::mul(gx, qy)));
    total = V::add(total, v);
  }
  return V::sum(total);
}

// Bilinear samples of the pattern under the warp q -> R q + t, R = [c -s; s c], all points inside
// the image with their 2x2 cells (canSample). Writes the samples to out when it is not null and
// returns their sum; when step is not null, also accumulates dots[r] = sum_i step[r][i] sample_i.
template <class V>
float sampleWarped(const float* data, std::ptrdiff_t stride, const PatchPattern& pattern, int n, float c, float s,
                   float tx, float ty, float* out, const std::array<float, PatchPattern::kMaxSize>* step, float* dots) {
  using F = typename V::F;
  const F vc = V::set1(c), vs = V::set1(s), vtx = V::set1(tx), vty = V::set1(ty);
  const F vstride = V::set1(static_cast<float>(stride));
  F total = V::set1(0.f), dot0 = total, dot1 = total, dot2 = total;
  for (int i = 0; i < n; i += 4) {
    const F qx = V::load(pattern.x.data() + i), qy = V::load(pattern.y.data() + i);
    const F x = V::add(V::sub(V::mul(vc, qx), V::mul(vs, qy)), vtx);
    const F y = V::add(V::add(V::mul(vs, qx), V::mul(vc, qy)), vty);
    const F ix = V::truncate(x), iy = V::truncate(y);  // x, y >= 1: truncation is floor
    const F fx = V::sub(x, ix), fy = V::sub(y, iy);
    // Pixel offsets in float are exact below 2^24 (images up to 16 Mpixel).
    std::int32_t offset[4];
    V::toInt(V::add(V::mul(iy, vstride), ix), offset);
    const float* cell[4] = {data + offset[0], data + offset[1], data + offset[2], data + offset[3]};
    F top_left, top_right, bottom_left, bottom_right;
    V::gather2(cell, top_left, top_right);
    for (auto& p : cell) p += stride;
    V::gather2(cell, bottom_left, bottom_right);
    const F top = V::add(top_left, V::mul(fx, V::sub(top_right, top_left)));
    const F bottom = V::add(bottom_left, V::mul(fx, V::sub(bottom_right, bottom_left)));
    const F v = V::add(top, V::mul(fy, V::sub(bottom, top)));
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

// sum_i a_i b_i over n points.
template <class V>
float dot(const float* a, const float* b, int n) {
  typename V::F acc = V::set1(0.f);
  for (int i = 0; i < n; i += 4) acc = V::add(acc, V::mul(V::load(a + i), V::load(b + i)));
  return V::sum(acc);
}

// sum_i a_i over n points.
template <class V>
float sum(const float* a, int n) {
  typename V::F acc = V::set1(0.f);
  for (int i = 0; i < n; i += 4) acc = V::add(acc, V::load(a + i));
  return V::sum(acc);
}

}  // namespace voca::patch_kernels
