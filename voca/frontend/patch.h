#pragma once
// SE(2) inverse-compositional patch alignment on one pyramid level, with mean-normalised
// intensities (the KLT core of the frontend).

#include <Eigen/Core>
#include <array>
#include <span>

#include "voca/frontend/pyramid.h"
#include "voca/geometry/se2.h"

namespace voca {

// Sample offsets of a patch around its centre, in pixels of the level it is sampled on.
// Pattern52: 52 points on a 2 px grid inside a 15x15 area; Pattern24: 24 points inside 11x11.
struct PatchPattern {
  static constexpr int kMaxSize = 52;
  int size = 0;
  std::array<float, kMaxSize> x{};
  std::array<float, kMaxSize> y{};
  float max_abs = 0.f;   // largest |x| or |y|: bounds the unrotated patch
  float max_norm = 0.f;  // largest |(x, y)|: bounds the patch under any rotation
};

const PatchPattern& pattern24();
const PatchPattern& pattern52();
// The pattern with this many points (24 or 52), or nullptr.
const PatchPattern* patternBySize(int size);

// True when (x, y) can be sampled with its interpolated central-difference gradient: the 4x4
// neighbourhood of the bilinear cell lies inside the image.
inline bool canSample(const FloatView& image, float x, float y) {
  return x >= 1.f && y >= 1.f && x < static_cast<float>(image.width - 2) && y < static_cast<float>(image.height - 2);
}
// Bilinear interpolation; (0, 0) is the centre of the top-left pixel. Requires canSample().
inline float sampleBilinear(const FloatView& image, float x, float y) {
  const int ix = static_cast<int>(x), iy = static_cast<int>(y);  // x, y >= 1: truncation is floor
  const float fx = x - static_cast<float>(ix), fy = y - static_cast<float>(iy);
  const float* r0 = image.data + static_cast<std::ptrdiff_t>(iy) * image.stride + ix;
  const float* r1 = r0 + image.stride;
  const float top = r0[0] + fx * (r0[1] - r0[0]);
  const float bottom = r1[0] + fx * (r1[1] - r1[0]);
  return top + fy * (bottom - top);
}

// Bilinear interpolation of the value and of the central-difference gradient. Requires canSample().
inline Eigen::Vector3f sampleWithGradient(const FloatView& image, float x, float y) {
  const int ix = static_cast<int>(x), iy = static_cast<int>(y);
  const float fx = x - static_cast<float>(ix), fy = y - static_cast<float>(iy);
  const std::ptrdiff_t s = image.stride;
  const float* r0 = image.data + static_cast<std::ptrdiff_t>(iy) * s + ix;
  const float* r1 = r0 + s;
  const float w00 = (1.f - fx) * (1.f - fy), w10 = fx * (1.f - fy), w01 = (1.f - fx) * fy, w11 = fx * fy;
  const float value = w00 * r0[0] + w10 * r0[1] + w01 * r1[0] + w11 * r1[1];
  // Central differences at the four corners, interpolated with the same weights: smoother than the
  // piecewise-constant derivative of the bilinear surface, which helps convergence.
  const float gx =
      0.5f * (w00 * (r0[1] - r0[-1]) + w10 * (r0[2] - r0[0]) + w01 * (r1[1] - r1[-1]) + w11 * (r1[2] - r1[0]));
  const float gy =
      0.5f * (w00 * (r1[0] - r0[-s]) + w10 * (r1[1] - r0[1 - s]) + w01 * (r1[s] - r0[0]) + w11 * (r1[s + 1] - r0[1]));
  return {value, gx, gy};
}

// The Jacobian of a template's normalised residual with respect to an SE(2) increment (tx, ty, theta)
// applied on the right of the warp, one row per parameter.
using PatchJacobian = std::array<std::array<float, PatchPattern::kMaxSize>, 3>;

// The template side of the alignment: mean-normalised intensities of the pattern around a point in
// the reference image and H^-1 J^T (J: the PatchJacobian). Pattern points whose neighbourhood leaves
// the image are marked invalid and contribute nothing. Arrays are contiguous, of fixed size, so the
// per-iteration loops are plain vectorisable float loops. The Jacobian itself is not kept: the
// alignment needs only H^-1 J^T, and a template is written once per point, level and frame and read
// the next frame, so its size is memory traffic.
struct PatchTemplate {
  int size = 0;
  alignas(32) std::array<float, PatchPattern::kMaxSize> value{};    // normalised, -1 = invalid
  alignas(32) std::array<float, PatchPattern::kMaxSize> step[3]{};  // rows of H^-1 J^T
  float step_dot_value[3]{};  // step[r] . value: lets an iteration skip forming the residual
  bool valid = false;
  bool all_points_valid = false;  // no point marked invalid: residuals may skip the per-point test

  // Samples the template at `center` (level pixels). valid is false when fewer than half of the
  // points can be sampled, the patch is black or H is singular (no texture). `jacobian`, when given,
  // receives J (for tests).
  void build(const FloatView& image, const Eigen::Vector2f& center, const PatchPattern& pattern,
             PatchJacobian* jacobian = nullptr);
};

// Normalised residual of the target patch under warp T (pattern offset q -> R q + t in the target
// level): r_i = I(T q_i) / mean - value_i for points valid on both sides, 0 otherwise. Returns the
// number of residuals used (0 when the target patch is black).
int patchResidual(const FloatView& target, const PatchTemplate& tmpl, const PatchPattern& pattern, const SE2f& T,
                  std::array<float, PatchPattern::kMaxSize>& residual);

// Why an alignment stopped.
enum class AlignStatus : std::uint8_t { kConverged, kTemplateInvalid, kTooFewPoints, kNonFinite, kHugeStep, kOutside };

struct AlignParams {
  int max_iterations = 5;
  // A step whose translation exceeds this (level pixels) means the linearisation is meaningless.
  float max_step_px = 20.f;
  // Iterations stop early once the step's translation is below this (level pixels) on level 0, and
  // below coarse_min_step_px on coarser levels, whose result the finer levels refine anyway.
  float min_step_px = 2e-3f;
  float coarse_min_step_px = 0.05f;
  // A coarse level (not level 0) whose alignment loses more than half of the pattern, or steps
  // outside the image, is skipped from where it started instead of failing the track: near the image
  // border the coarse levels' patches (the pattern times 2^level) run out of image long before level
  // 0's does. Off = fail, as Basalt does.
  bool skip_coarse_outside = false;
};

// Refines T (pattern offset -> target level pixels) on one level by inverse-compositional Gauss-Newton,
// T <- T exp(-H^-1 J^T r). Fails on non-finite or huge steps, fewer than half of the pattern points
// inside the target, or the patch centre leaving the target image.
AlignStatus alignPatch(const FloatView& target, const PatchTemplate& tmpl, const PatchPattern& pattern,
                       const AlignParams& params, SE2f& T, bool coarse = false);

// The templates of one point on the levels of a pyramid: levels[l] at px / 2^l in level l, for
// first_level <= l < levels.size(). Built once and used for every guess tracked from that point; a
// level depends on nothing but its image and px, so levels built later equal those built at once.
void buildPyramidPatch(const ImagePyramid& pyramid, const Eigen::Vector2f& px, const PatchPattern& pattern,
                       std::span<PatchTemplate> levels, std::size_t first_level = 0);

// Asks the memory system for the pixels that patches near px (level-0 pixels, within `margin` level-0
// pixels of it) read on levels 0 .. num_levels-1 of the pyramid, without waiting for them. Purely a
// speed hint: tracking reads scattered patches of images larger than the cache, and a patch fetched
// while the previous point is being tracked is not waited for. Changes no result.
void prefetchPyramidPatch(const ImagePyramid& pyramid, const Eigen::Vector2f& px, const PatchPattern& pattern,
                          float margin, int num_levels);

// Coarse-to-fine alignment of prebuilt templates into pyramid `to`: T is initialised by the caller
// (translation = guessed level-0 position, rotation usually identity) and holds the converged warp in
// level-0 pixels on success. A coarse level whose template is invalid (no texture or too close to the
// border at that scale) is skipped; an invalid level-0 template fails. With min_level > 0 only the
// levels from min_level up run (T is then the warp the finer levels would start from): running levels
// >= k and then levels < k gives the same T as one call over all levels.
AlignStatus trackPatch(std::span<const PatchTemplate> from, const ImagePyramid& to, const PatchPattern& pattern,
                       const AlignParams& params, SE2f& T, int min_level = 0);

// Coarse-to-fine alignment over pyramids: the template around `from_px` (level-0 pixels) in `from`,
// the warp T initialised by the caller (translation = guessed level-0 position in `to`, rotation
// usually identity); on success T holds the converged warp in level-0 pixels. Uses levels
// num_levels-1 .. 0 of both pyramids.
AlignStatus trackPatch(const ImagePyramid& from, const ImagePyramid& to, const Eigen::Vector2f& from_px,
                       const PatchPattern& pattern, const AlignParams& params, int num_levels, SE2f& T);

}  // namespace voca
