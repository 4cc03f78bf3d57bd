#include "voca/frontend/patch.h"

#include "voca/frontend/patch_kernels.h"
#include "voca/frontend/patch_kernels_avx2.h"

#include <Eigen/LU>
#include <algorithm>
#include <bit>
#include <cmath>

namespace voca {

namespace {

// Rows of odd coordinates, spacing 2: each row lists its y and the largest |x|.
PatchPattern makePattern(std::initializer_list<std::pair<int, int>> rows) {
  PatchPattern pattern;
  for (const auto& [row_y, max_x] : rows) {
    for (int px = -max_x; px <= max_x; px += 2) {
      pattern.x[static_cast<std::size_t>(pattern.size)] = static_cast<float>(px);
      pattern.y[static_cast<std::size_t>(pattern.size)] = static_cast<float>(row_y);
      pattern.max_abs =
          std::max({pattern.max_abs, std::abs(static_cast<float>(px)), std::abs(static_cast<float>(row_y))});
      pattern.max_norm = std::max(pattern.max_norm, std::hypot(static_cast<float>(px), static_cast<float>(row_y)));
      ++pattern.size;
    }
  }
  return pattern;
}

// True when every point of the square of half-size `reach` around (x, y) can be sampled (see
// canSample): a patch whose points lie within that reach needs no per-point test.
bool squareInside(const FloatView& image, float x, float y, float reach) {
  return canSample(image, x - reach, y - reach) && canSample(image, x + reach, y + reach);
}

// The sum of the sampled points' values, added one point after the other (the order the per-point
// samplers used, which the results depend on bit for bit). A point not sampled adds +0, which leaves
// the sum's bits as they are (it starts at +0 and samples are >= 0), without a branch the border's
// irregular masks would mispredict.
float sumInPointOrder(const std::array<float, PatchPattern::kMaxSize>& values, std::uint64_t sampled, int n) {
  float sum = 0.f;
  for (int i = 0; i < n; ++i) sum += ((sampled >> i) & 1u) != 0 ? values[static_cast<std::size_t>(i)] : 0.f;
  return sum;
}

// patch_kernels::sampleWarped in the fastest variant this CPU runs; every variant gives the same bits.
float sampleWarpedFastest(const float* data, std::ptrdiff_t stride, const PatchPattern& pattern, int n, float c,
                          float s, float tx, float ty, float* out,
                          const std::array<float, PatchPattern::kMaxSize>* step, float* dots) {
#if VOCA_AVX2_KERNELS
  static const bool use_avx2 = patch_kernels::avx2Available();
  if (use_avx2) return patch_kernels::sampleWarpedAvx2(data, stride, pattern, n, c, s, tx, ty, out, step, dots);
#endif
  return patch_kernels::sampleWarped<simd4::Native>(data, stride, pattern, n, c, s, tx, ty, out, step, dots);
}

// patch_kernels::sampleWarpedMasked in the fastest variant this CPU runs; every variant gives the same bits.
std::uint64_t sampleWarpedMaskedFastest(const FloatView& image, const PatchPattern& pattern, int n, float c, float s,
                                        float tx, float ty, const float* keep, float* out) {
#if VOCA_AVX2_KERNELS
  static const bool use_avx2 = patch_kernels::avx2Available();
  if (use_avx2) return patch_kernels::sampleWarpedMaskedAvx2(image, pattern, n, c, s, tx, ty, keep, out);
#endif
  return patch_kernels::sampleWarpedMasked<simd4::Native>(image, pattern, n, c, s, tx, ty, keep, out);
}

// patch_kernels::sampleTemplate in the fastest variant this CPU runs; every variant gives the same bits.
float sampleTemplateFastest(const float* base, std::ptrdiff_t stride, const PatchPattern& pattern, float fx, float fy,
                            float* value, float* d_tx, float* d_ty, float* d_theta) {
#if VOCA_AVX2_KERNELS
  static const bool use_avx2 = patch_kernels::avx2Available();
  if (use_avx2) return patch_kernels::sampleTemplateAvx2(base, stride, pattern, fx, fy, value, d_tx, d_ty, d_theta);
#endif
  return patch_kernels::sampleTemplate<simd4::Native>(base, stride, pattern, fx, fy, value, d_tx, d_ty, d_theta);
}

}  // namespace

const PatchPattern& pattern24() {
  static const PatchPattern pattern = makePattern({{-5, 1}, {-3, 3}, {-1, 5}, {1, 5}, {3, 3}, {5, 1}});
  return pattern;
}

const PatchPattern& pattern52() {
  static const PatchPattern pattern = makePattern({{-7, 3}, {-5, 5}, {-3, 7}, {-1, 7}, {1, 7}, {3, 7}, {5, 5}, {7, 3}});
  return pattern;
}

const PatchPattern* patternBySize(int size) {
  if (size == 24) return &pattern24();
  if (size == 52) return &pattern52();
  return nullptr;
}

void PatchTemplate::build(const FloatView& image, const Eigen::Vector2f& center, const PatchPattern& pattern,
                          PatchJacobian* jacobian) {
  size = pattern.size;
  valid = false;
  const int n = size;
  std::array<float, PatchPattern::kMaxSize> jpix[3];
  alignas(32) PatchJacobian jac;
  float sum = 0.f;
  int count = 0;
  const float half = pattern.max_abs;
  if (squareInside(image, center.x(), center.y(), half)) {
    // Fast path, the whole patch inside: pattern offsets are integers, so every sample has the same
    // bilinear weights and only the base pointer moves.
    const int ix = static_cast<int>(center.x()), iy = static_cast<int>(center.y());
    const float* base = image.data + static_cast<std::ptrdiff_t>(iy) * image.stride + ix;
    sum = sampleTemplateFastest(base, image.stride, pattern, center.x() - static_cast<float>(ix),
                                center.y() - static_cast<float>(iy), value.data(), jpix[0].data(), jpix[1].data(),
                                jpix[2].data());
    count = n;
  } else {
    // Near the border every point gets its own weights and its own test.
    const std::uint64_t sampled = patch_kernels::sampleTemplateMasked<simd4::Native>(
        image, pattern, center.x(), center.y(), value.data(), jpix[0].data(), jpix[1].data(), jpix[2].data());
    sum = sumInPointOrder(value, sampled, n);
    count = std::popcount(sampled);
  }
  all_points_valid = count == n;
  if (2 * count <= n || !(sum > 1e-3f * static_cast<float>(count))) return;
  const float mean = sum / static_cast<float>(count);
  const float inv_mean = 1.f / mean;
  float jsum[3];
  for (int c = 0; c < 3; ++c)
    jsum[c] = patch_kernels::sum<simd4::Native>(jpix[c].data(), n) / static_cast<float>(count);
  // n_i = v_i / mean with mean = sum_j v_j / count, so
  // d n_i = (d v_i - n_i * mean_j(d v_j)) / mean.
  patch_kernels::normaliseTemplate<simd4::Native>(n, inv_mean, jsum, value.data(), jpix, jac.data());
  if (jacobian != nullptr) *jacobian = jac;
  // H = J^T J, its six distinct entries in one pass over the Jacobian rows.
  float h[3][3];
  patch_kernels::gram3<simd4::Native>(jac.data(), n, h);
  Eigen::Matrix3d hessian;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) hessian(a, b) = h[a][b];
  const double trace = hessian.trace();
  const double det = hessian.determinant();
  // Scale-free test for an untextured (rank-deficient) patch.
  if (!(trace > 0.0) || !(det > 1e-9 * trace * trace * trace)) return;
  // The inverse in double (H may be poorly conditioned), the rows of H^-1 J^T in float, with their
  // dot products with the values (invalid points have a zero step, so their -1 marker adds nothing).
  const Eigen::Matrix3f inverse_matrix = hessian.inverse().cast<float>();
  float inverse[3][3];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) inverse[r][c] = inverse_matrix(r, c);
  patch_kernels::stepRows<simd4::Native>(inverse, jac.data(), value.data(), n, step, step_dot_value);
  for (int i = n; i < PatchPattern::kMaxSize; ++i) {
    const auto k = static_cast<std::size_t>(i);
    value[k] = -1.f;
    step[0][k] = step[1][k] = step[2][k] = 0.f;
  }
  valid = true;
}

int patchResidual(const FloatView& target, const PatchTemplate& tmpl, const PatchPattern& pattern, const SE2f& T,
                  std::array<float, PatchPattern::kMaxSize>& residual) {
  const int n = tmpl.size;
  const float c = T.unitComplex().x(), s = T.unitComplex().y();
  const float tx = T.translation().x(), ty = T.translation().y();
  float sum = 0.f;
  int count = 0;
  if (tmpl.all_points_valid && squareInside(target, tx, ty, pattern.max_norm)) {
    // Fast path, every point valid on both sides: no per-point tests.
    sum = sampleWarpedFastest(target.data, target.stride, pattern, n, c, s, tx, ty, residual.data(), nullptr, nullptr);
    count = n;
    if (!(sum > 1e-3f * static_cast<float>(count))) return 0;
    const float inv_mean = static_cast<float>(count) / sum;
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      residual[k] = residual[k] * inv_mean - tmpl.value[k];
    }
    return count;
  }
  const std::uint64_t sampled =
      sampleWarpedMaskedFastest(target, pattern, n, c, s, tx, ty, tmpl.value.data(), residual.data());
  sum = sumInPointOrder(residual, sampled, n);
  count = std::popcount(sampled);
  if (count == 0 || !(sum > 1e-3f * static_cast<float>(count))) return 0;
  const float inv_mean = static_cast<float>(count) / sum;
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    residual[k] = residual[k] >= 0.f ? residual[k] * inv_mean - tmpl.value[k] : 0.f;
  }
  return count;
}

AlignStatus alignPatch(const FloatView& target, const PatchTemplate& tmpl, const PatchPattern& pattern,
                       const AlignParams& params, SE2f& T, bool coarse) {
  if (!tmpl.valid) return AlignStatus::kTemplateInvalid;
  alignas(32) std::array<float, PatchPattern::kMaxSize> residual;
  const int n = tmpl.size;
  const float max_step2 = params.max_step_px * params.max_step_px;
  const float min_step = coarse ? params.coarse_min_step_px : params.min_step_px;
  const float min_step2 = min_step * min_step;
  for (int iteration = 0; iteration < params.max_iterations; ++iteration) {
    float inc[3];
    const float tx = T.translation().x(), ty = T.translation().y();
    if (tmpl.all_points_valid && squareInside(target, tx, ty, pattern.max_norm)) {
      // Every point inside: one pass samples the target and forms H^-1 J^T r directly, as
      // sum_i step_i (I_i / mean - value_i) = (sum_i step_i I_i) / mean - sum_i step_i value_i.
      float dots[3];
      const float sum = sampleWarpedFastest(target.data, target.stride, pattern, n, T.unitComplex().x(),
                                            T.unitComplex().y(), tx, ty, nullptr, tmpl.step, dots);
      if (!(sum > 1e-3f * static_cast<float>(n))) return AlignStatus::kTooFewPoints;
      const float inv_mean = static_cast<float>(n) / sum;
      for (int r = 0; r < 3; ++r) inc[r] = inv_mean * dots[r] - tmpl.step_dot_value[r];
    } else {
      const int used = patchResidual(target, tmpl, pattern, T, residual);
      if (2 * used <= n) return AlignStatus::kTooFewPoints;
      for (int r = 0; r < 3; ++r) inc[r] = patch_kernels::dot<simd4::Native>(tmpl.step[r].data(), residual.data(), n);
    }
    if (!std::isfinite(inc[0]) || !std::isfinite(inc[1]) || !std::isfinite(inc[2])) return AlignStatus::kNonFinite;
    const float step2 = inc[0] * inc[0] + inc[1] * inc[1];
    if (step2 > max_step2 || std::abs(inc[2]) > 1.f) return AlignStatus::kHugeStep;
    T *= SE2f::exp(Eigen::Vector3f(-inc[0], -inc[1], -inc[2]));
    if (!canSample(target, T.translation().x(), T.translation().y())) return AlignStatus::kOutside;
    if (step2 < min_step2) break;
  }
  return AlignStatus::kConverged;
}

void buildPyramidPatch(const ImagePyramid& pyramid, const Eigen::Vector2f& px, const PatchPattern& pattern,
                       std::span<PatchTemplate> levels, std::size_t first_level) {
  for (std::size_t level = first_level; level < levels.size(); ++level) {
    levels[level].build(pyramid.level(static_cast<int>(level)), px / static_cast<float>(1 << level), pattern);
  }
}

void prefetchPyramidPatch(const ImagePyramid& pyramid, const Eigen::Vector2f& px, const PatchPattern& pattern,
                          float margin, int num_levels) {
  constexpr int kLineFloats = 64 / static_cast<int>(sizeof(float));  // a typical cache line
  for (int level = 0; level < std::min(num_levels, pyramid.numLevels()); ++level) {
    const FloatView image = pyramid.level(level);
    const float scale = 1.f / static_cast<float>(1 << level);
    // The bilinear cells and gradient neighbourhoods reach one pixel before and two after a point.
    const float reach = pattern.max_norm + margin * scale;
    const float x = px.x() * scale, y = px.y() * scale;
    if (!(std::abs(x) < 1e6f && std::abs(y) < 1e6f)) return;  // not finite or absurd: nothing to fetch
    const int x0 = std::clamp(static_cast<int>(std::floor(x - reach)) - 1, 0, image.width - 1);
    const int x1 = std::clamp(static_cast<int>(std::ceil(x + reach)) + 2, 0, image.width - 1);
    const int y0 = std::clamp(static_cast<int>(std::floor(y - reach)) - 1, 0, image.height - 1);
    const int y1 = std::clamp(static_cast<int>(std::ceil(y + reach)) + 2, 0, image.height - 1);
    for (int row = y0; row <= y1; ++row) {
      const float* line = image.data + static_cast<std::ptrdiff_t>(row) * image.stride;
      for (int col = x0; col <= x1; col += kLineFloats) __builtin_prefetch(line + col);
      __builtin_prefetch(line + x1);
    }
  }
}

AlignStatus trackPatch(std::span<const PatchTemplate> from, const ImagePyramid& to, const PatchPattern& pattern,
                       const AlignParams& params, SE2f& T, int min_level) {
  for (int level = static_cast<int>(from.size()) - 1; level >= min_level; --level) {
    const PatchTemplate& tmpl = from[static_cast<std::size_t>(level)];
    if (!tmpl.valid) {
      // A coarse level may lack texture or room near the border: the finer levels still decide.
      if (level > 0) continue;
      return AlignStatus::kTemplateInvalid;
    }
    const float scale = static_cast<float>(1 << level);
    const SE2f start = T;
    T.translation() /= scale;
    const AlignStatus status = alignPatch(to.level(level), tmpl, pattern, params, T, level > 0);
    T.translation() *= scale;
    if (status == AlignStatus::kConverged) continue;
    if (level > 0 && params.skip_coarse_outside &&
        (status == AlignStatus::kTooFewPoints || status == AlignStatus::kOutside)) {
      T = start;  // the finer levels start where this one did
      continue;
    }
    return status;
  }
  return AlignStatus::kConverged;
}

AlignStatus trackPatch(const ImagePyramid& from, const ImagePyramid& to, const Eigen::Vector2f& from_px,
                       const PatchPattern& pattern, const AlignParams& params, int num_levels, SE2f& T) {
  std::array<PatchTemplate, ImagePyramid::kMaxLevels> levels;
  const std::span<PatchTemplate> used(levels.data(), static_cast<std::size_t>(num_levels));
  buildPyramidPatch(from, from_px, pattern, used);
  return trackPatch(used, to, pattern, params, T);
}

}  // namespace voca
