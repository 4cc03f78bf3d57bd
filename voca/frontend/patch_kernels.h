#pragma once
// The KLT inner loops, four pattern points at a time, as templates over a simd4 backend. patch.cpp
// runs them with simd4::Native; tests run them with simd4::Portable as well and require identical
// results. Point counts are multiples of four (both patterns are).

#include <cstddef>
#include <cstdint>

#include "voca/frontend/patch.h"
#include "voca/frontend/simd4.h"

namespace voca::patch_kernels {

// The helpers below are forced inline: called out of line they pass their vectors through memory,
// which costs more than the work they do.

// The value and central-difference gradient of four points at once, each from the 4x4 neighbourhood
// whose second row and column start at row0[k] (the top-left pixel of its bilinear cell), with
// bilinear weights per lane. The same operations in the same order as sampleWithGradient.
template <class V>
[[gnu::always_inline]] inline void valueAndGradient(const float* const row0[4], std::ptrdiff_t stride,
                                                    typename V::F w00, typename V::F w10, typename V::F w01,
                                                    typename V::F w11, typename V::F& v, typename V::F& gx,
                                                    typename V::F& gy) {
  using F = typename V::F;
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
  const F half = V::set1(0.5f);
  v = V::add(V::add(V::add(V::mul(w00, a[1]), V::mul(w10, a[2])), V::mul(w01, b[1])), V::mul(w11, b[2]));
  gx = V::mul(half, V::add(V::add(V::add(V::mul(w00, V::sub(a[2], a[0])), V::mul(w10, V::sub(a[3], a[1]))),
                                  V::mul(w01, V::sub(b[2], b[0]))),
                           V::mul(w11, V::sub(b[3], b[1]))));
  gy = V::mul(half, V::add(V::add(V::add(V::mul(w00, V::sub(b[1], above0)), V::mul(w10, V::sub(b[2], above1))),
                                  V::mul(w01, V::sub(below0, a[1]))),
                           V::mul(w11, V::sub(below1, a[2]))));
}

// d I(centre + R(theta) q + t) / d theta at identity = -gx qy + gy qx (the same bits as gy qx - gx qy).
template <class V>
[[gnu::always_inline]] inline typename V::F thetaDerivative(typename V::F gx, typename V::F gy, typename V::F qx,
                                                            typename V::F qy) {
  return V::sub(V::mul(gy, qx), V::mul(gx, qy));
}

// sampleTemplate's loop from point `first` (a multiple of four) on, adding the samples to total: the
// AVX2 kernel runs the group of four its groups of eight leave through this same loop.
template <class V>
[[gnu::always_inline]] inline void accumulateTemplate(const float* base, std::ptrdiff_t stride,
                                                      const PatchPattern& pattern, int first, float fx, float fy,
                                                      float* value, float* d_tx, float* d_ty, float* d_theta,
                                                      typename V::F& total) {
  using F = typename V::F;
  const F w00 = V::set1((1.f - fx) * (1.f - fy)), w10 = V::set1(fx * (1.f - fy));
  const F w01 = V::set1((1.f - fx) * fy), w11 = V::set1(fx * fy);
  for (int i = first; i < pattern.size; i += 4) {
    const float* row0[4];  // top-left pixel of each point's bilinear cell
    for (int k = 0; k < 4; ++k) {
      const auto j = static_cast<std::size_t>(i + k);
      row0[k] = base + static_cast<std::ptrdiff_t>(pattern.y[j]) * stride + static_cast<std::ptrdiff_t>(pattern.x[j]);
    }
    F v, gx, gy;
    valueAndGradient<V>(row0, stride, w00, w10, w01, w11, v, gx, gy);
    const F qx = V::load(pattern.x.data() + i), qy = V::load(pattern.y.data() + i);
    V::store(value + i, v);
    V::store(d_tx + i, gx);
    V::store(d_ty + i, gy);
    V::store(d_theta + i, thetaDerivative<V>(gx, gy, qx, qy));
    total = V::add(total, v);
  }
}

// Samples the pattern around base (the pixel at the integer part of the patch centre; every point
// and its gradient neighbourhood inside the image) with the bilinear weights of the fractional part
// (fx, fy), which all points share because pattern offsets are integers. Writes the intensity and
// the derivatives of intensity with respect to (tx, ty, theta) of the warp; returns the sum of the
// intensities. The gradient is the central difference at the four cell corners, interpolated with
// the same weights (see sampleWithGradient).
template <class V>
float sampleTemplate(const float* base, std::ptrdiff_t stride, const PatchPattern& pattern, float fx, float fy,
                     float* value, float* d_tx, float* d_ty, float* d_theta) {
  typename V::F total = V::set1(0.f);
  accumulateTemplate<V>(base, stride, pattern, 0, fx, fy, value, d_tx, d_ty, d_theta, total);
  return V::sum(total);
}

// Lanes of the points (x, y) that canSample(image, x, y) accepts.
template <class V>
[[gnu::always_inline]] inline typename V::M sampleable(const FloatView& image, typename V::F x, typename V::F y) {
  const typename V::F one = V::set1(1.f);
  const typename V::F x_end = V::set1(static_cast<float>(image.width - 2));
  const typename V::F y_end = V::set1(static_cast<float>(image.height - 2));
  return V::both(V::both(V::lessEqual(one, x), V::lessEqual(one, y)),
                 V::both(V::lessThan(x, x_end), V::lessThan(y, y_end)));
}

// Offsets of the top-left pixels of the bilinear cells of (x, y) (x, y >= 1 or replaced), with the
// fractional parts.
template <class V>
[[gnu::always_inline]] inline void cellOffsets(typename V::F x, typename V::F y, std::ptrdiff_t stride,
                                               std::int32_t* offset, typename V::F& fx, typename V::F& fy) {
  const typename V::F ix = V::truncate(x), iy = V::truncate(y);  // x, y >= 1: truncation is floor
  fx = V::sub(x, ix);
  fy = V::sub(y, iy);
  // Pixel offsets in float are exact below 2^24 (images up to 16 Mpixel).
  V::toInt(V::add(V::mul(iy, V::set1(static_cast<float>(stride))), ix), offset);
}

// sampleTemplate for a patch centred at (cx, cy) that may reach past the image border: every point
// gets its own bilinear weights, as sampleWithGradient forms them. Points that canSample rejects get
// value -1 and zero derivatives. Returns the points sampled, bit i for point i.
template <class V>
std::uint64_t sampleTemplateMasked(const FloatView& image, const PatchPattern& pattern, float cx, float cy,
                                   float* value, float* d_tx, float* d_ty, float* d_theta) {
  using F = typename V::F;
  const F vcx = V::set1(cx), vcy = V::set1(cy);
  const F one = V::set1(1.f), zero = V::set1(0.f), invalid = V::set1(-1.f);
  std::uint64_t sampled = 0;
  for (int i = 0; i < pattern.size; i += 4) {
    const F qx = V::load(pattern.x.data() + i), qy = V::load(pattern.y.data() + i);
    const F x = V::add(vcx, qx), y = V::add(vcy, qy);
    const typename V::M inside = sampleable<V>(image, x, y);
    const unsigned lanes = V::bits(inside);
    if (lanes == 0) {
      V::store(value + i, invalid);
      V::store(d_tx + i, zero);
      V::store(d_ty + i, zero);
      V::store(d_theta + i, zero);
      continue;
    }
    sampled |= static_cast<std::uint64_t>(lanes) << i;
    // A lane outside reads the cell at (1, 1) instead, which exists since some lane is inside.
    F fx, fy;
    std::int32_t offset[4];
    cellOffsets<V>(V::select(inside, x, one), V::select(inside, y, one), image.stride, offset, fx, fy);
    const float* row0[4] = {image.data + offset[0], image.data + offset[1], image.data + offset[2],
                            image.data + offset[3]};
    const F one_fx = V::sub(one, fx), one_fy = V::sub(one, fy);
    F v, gx, gy;
    valueAndGradient<V>(row0, image.stride, V::mul(one_fx, one_fy), V::mul(fx, one_fy), V::mul(one_fx, fy),
                        V::mul(fx, fy), v, gx, gy);
    V::store(value + i, V::select(inside, v, invalid));
    V::store(d_tx + i, V::select(inside, gx, zero));
    V::store(d_ty + i, V::select(inside, gy, zero));
    V::store(d_theta + i, V::select(inside, thetaDerivative<V>(gx, gy, qx, qy), zero));
  }
  return sampled;
}

// Bilinear samples at four points (x, y >= 1, cells inside the image), as sampleBilinear computes them.
template <class V>
[[gnu::always_inline]] inline typename V::F bilinear(const float* data, std::ptrdiff_t stride, typename V::F x,
                                                     typename V::F y) {
  using F = typename V::F;
  F fx, fy;
  std::int32_t offset[4];
  cellOffsets<V>(x, y, stride, offset, fx, fy);
  const float* cell[4] = {data + offset[0], data + offset[1], data + offset[2], data + offset[3]};
  F top_left, top_right, bottom_left, bottom_right;
  V::gather2(cell, top_left, top_right);
  for (auto& p : cell) p += stride;
  V::gather2(cell, bottom_left, bottom_right);
  const F top = V::add(top_left, V::mul(fx, V::sub(top_right, top_left)));
  const F bottom = V::add(bottom_left, V::mul(fx, V::sub(bottom_right, bottom_left)));
  return V::add(top, V::mul(fy, V::sub(bottom, top)));
}

// Pattern points i..i+3 under the warp q -> R q + t, R = [c -s; s c].
template <class V>
[[gnu::always_inline]] inline void warpPoints(const PatchPattern& pattern, int i, typename V::F c, typename V::F s,
                                              typename V::F tx, typename V::F ty, typename V::F& x, typename V::F& y) {
  const typename V::F qx = V::load(pattern.x.data() + i), qy = V::load(pattern.y.data() + i);
  x = V::add(V::sub(V::mul(c, qx), V::mul(s, qy)), tx);
  y = V::add(V::add(V::mul(s, qx), V::mul(c, qy)), ty);
}

// Running sums of sampleWarped, one lane per point position in a group of four.
template <class V>
struct WarpedSums {
  typename V::F total = V::set1(0.f), dot0 = total, dot1 = total, dot2 = total;
};

// sampleWarped's loop from point `first` (a multiple of four) on, adding to sums: the AVX2 kernel
// runs the groups of four its groups of eight leave through this same loop.
template <class V>
[[gnu::always_inline]] inline void accumulateWarped(const float* data, std::ptrdiff_t stride,
                                                    const PatchPattern& pattern, int first, int n, float c, float s,
                                                    float tx, float ty, float* out,
                                                    const std::array<float, PatchPattern::kMaxSize>* step,
                                                    WarpedSums<V>& sums) {
  using F = typename V::F;
  const F vc = V::set1(c), vs = V::set1(s), vtx = V::set1(tx), vty = V::set1(ty);
  for (int i = first; i < n; i += 4) {
    F x, y;
    warpPoints<V>(pattern, i, vc, vs, vtx, vty, x, y);
    const F v = bilinear<V>(data, stride, x, y);
    if (out != nullptr) V::store(out + i, v);
    if (step != nullptr) {
      sums.dot0 = V::add(sums.dot0, V::mul(V::load(step[0].data() + i), v));
      sums.dot1 = V::add(sums.dot1, V::mul(V::load(step[1].data() + i), v));
      sums.dot2 = V::add(sums.dot2, V::mul(V::load(step[2].data() + i), v));
    }
    sums.total = V::add(sums.total, v);
  }
}

// The lane sums of `sums`: dots[r] when step is not null; returns the sum of the samples.
template <class V>
[[gnu::always_inline]] inline float finishWarped(const WarpedSums<V>& sums,
                                                 const std::array<float, PatchPattern::kMaxSize>* step, float* dots) {
  if (step != nullptr) {
    dots[0] = V::sum(sums.dot0);
    dots[1] = V::sum(sums.dot1);
    dots[2] = V::sum(sums.dot2);
  }
  return V::sum(sums.total);
}

// Bilinear samples of the pattern under the warp q -> R q + t, R = [c -s; s c], all points inside
// the image with their 2x2 cells (canSample). Writes the samples to out when it is not null and
// returns their sum; when step is not null, also accumulates dots[r] = sum_i step[r][i] sample_i.
template <class V>
float sampleWarped(const float* data, std::ptrdiff_t stride, const PatchPattern& pattern, int n, float c, float s,
                   float tx, float ty, float* out, const std::array<float, PatchPattern::kMaxSize>* step, float* dots) {
  WarpedSums<V> sums;
  accumulateWarped<V>(data, stride, pattern, 0, n, c, s, tx, ty, out, step, sums);
  return finishWarped<V>(sums, step, dots);
}

// sampleWarped for a patch that may reach past the image border or hold invalid points: point i is
// sampled when keep[i] >= 0 (a template value; -1 marks an invalid point) and canSample accepts its
// warped position. out[i] is its sample, or -1. Returns the points sampled, bit i for point i.
// Points before `first` (a multiple of four) are left alone.
template <class V>
std::uint64_t sampleWarpedMasked(const FloatView& image, const PatchPattern& pattern, int n, float c, float s, float tx,
                                 float ty, const float* keep, float* out, int first = 0) {
  using F = typename V::F;
  const F vc = V::set1(c), vs = V::set1(s), vtx = V::set1(tx), vty = V::set1(ty);
  const F one = V::set1(1.f), zero = V::set1(0.f), invalid = V::set1(-1.f);
  std::uint64_t sampled = 0;
  for (int i = first; i < n; i += 4) {
    F x, y;
    warpPoints<V>(pattern, i, vc, vs, vtx, vty, x, y);
    const typename V::M inside = V::both(V::lessEqual(zero, V::load(keep + i)), sampleable<V>(image, x, y));
    const unsigned lanes = V::bits(inside);
    if (lanes == 0) {
      V::store(out + i, invalid);
      continue;
    }
    sampled |= static_cast<std::uint64_t>(lanes) << i;
    // A lane outside reads the cell at (1, 1) instead, which exists since some lane is inside.
    const F v = bilinear<V>(image.data, image.stride, V::select(inside, x, one), V::select(inside, y, one));
    V::store(out + i, V::select(inside, v, invalid));
  }
  return sampled;
}

// The template's mean normalisation, point by point: value_i <- value_i * inv_mean and
// jac[c]_i = (jpix[c]_i - value_i * jsum[c]) * inv_mean for valid points (value >= 0); invalid ones
// keep -1 and get zero rows.
template <class V>
void normaliseTemplate(int n, float inv_mean, const float* jsum, float* value,
                       const std::array<float, PatchPattern::kMaxSize>* jpix,
                       std::array<float, PatchPattern::kMaxSize>* jac) {
  using F = typename V::F;
  const F inv = V::set1(inv_mean), zero = V::set1(0.f), invalid = V::set1(-1.f);
  const F sum0 = V::set1(jsum[0]), sum1 = V::set1(jsum[1]), sum2 = V::set1(jsum[2]);
  for (int i = 0; i < n; i += 4) {
    const F raw = V::load(value + i);
    const typename V::M ok = V::lessEqual(zero, raw);
    const F v = V::mul(raw, inv);
    V::store(value + i, V::select(ok, v, invalid));
    V::store(jac[0].data() + i, V::select(ok, V::mul(V::sub(V::load(jpix[0].data() + i), V::mul(v, sum0)), inv), zero));
    V::store(jac[1].data() + i, V::select(ok, V::mul(V::sub(V::load(jpix[1].data() + i), V::mul(v, sum1)), inv), zero));
    V::store(jac[2].data() + i, V::select(ok, V::mul(V::sub(V::load(jpix[2].data() + i), V::mul(v, sum2)), inv), zero));
  }
}

// The six distinct entries of H = J^T J in one pass over the three Jacobian rows: h[a][b] (a <= b,
// mirrored into h[b][a]) equals dot<V>(jac[a], jac[b], n) bit for bit (same lanes, same order).
template <class V>
void gram3(const std::array<float, PatchPattern::kMaxSize>* jac, int n, float h[3][3]) {
  using F = typename V::F;
  F h00 = V::set1(0.f), h01 = h00, h02 = h00, h11 = h00, h12 = h00, h22 = h00;
  for (int i = 0; i < n; i += 4) {
    const F j0 = V::load(jac[0].data() + i), j1 = V::load(jac[1].data() + i), j2 = V::load(jac[2].data() + i);
    h00 = V::add(h00, V::mul(j0, j0));
    h01 = V::add(h01, V::mul(j0, j1));
    h02 = V::add(h02, V::mul(j0, j2));
    h11 = V::add(h11, V::mul(j1, j1));
    h12 = V::add(h12, V::mul(j1, j2));
    h22 = V::add(h22, V::mul(j2, j2));
  }
  h[0][0] = V::sum(h00);
  h[0][1] = h[1][0] = V::sum(h01);
  h[0][2] = h[2][0] = V::sum(h02);
  h[1][1] = V::sum(h11);
  h[1][2] = h[2][1] = V::sum(h12);
  h[2][2] = V::sum(h22);
}

// The rows of H^-1 J^T, step[r]_i = (inverse[r][0] jac[0]_i + inverse[r][1] jac[1]_i) +
// inverse[r][2] jac[2]_i, and step_dot_value[r] = dot<V>(step[r], value, n) bit for bit, in one pass.
template <class V>
void stepRows(const float inverse[3][3], const std::array<float, PatchPattern::kMaxSize>* jac, const float* value,
              int n, std::array<float, PatchPattern::kMaxSize>* step, float* step_dot_value) {
  using F = typename V::F;
  F w[3][3];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) w[r][c] = V::set1(inverse[r][c]);
  F acc[3] = {V::set1(0.f), V::set1(0.f), V::set1(0.f)};
  for (int i = 0; i < n; i += 4) {
    const F j0 = V::load(jac[0].data() + i), j1 = V::load(jac[1].data() + i), j2 = V::load(jac[2].data() + i);
    const F v = V::load(value + i);
    for (int r = 0; r < 3; ++r) {
      const F row = V::add(V::add(V::mul(w[r][0], j0), V::mul(w[r][1], j1)), V::mul(w[r][2], j2));
      V::store(step[r].data() + i, row);
      acc[r] = V::add(acc[r], V::mul(row, v));
    }
  }
  for (int r = 0; r < 3; ++r) step_dot_value[r] = V::sum(acc[r]);
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
