#include "voca/synth/texture.h"

#include <algorithm>
#include <cmath>

namespace voca::synth {

namespace {

constexpr float kTwoPi = 6.28318530717958647692f;

// Unit gradients at 16 evenly spaced angles: enough directions that the lattice does not show.
struct GradientTable {
  float x[16];
  float y[16];
  GradientTable() {
    for (int i = 0; i < 16; ++i) {
      x[i] = std::cos(kTwoPi * (static_cast<float>(i) + 0.5f) / 16.0f);
      y[i] = std::sin(kTwoPi * (static_cast<float>(i) + 0.5f) / 16.0f);
    }
  }
};
const GradientTable kGradients;

// A fixed pseudo-random permutation of 0..255, stored twice so that sums of two entries need no wrap.
struct PermutationTable {
  std::uint8_t table[512];
  PermutationTable() {
    std::uint8_t p[256];
    for (int i = 0; i < 256; ++i) p[i] = static_cast<std::uint8_t>(i);
    std::uint32_t h = 0x1234567u;
    for (int i = 255; i > 0; --i) {  // Fisher-Yates with a hash chain: the same table on every platform
      h = hash32(h + 0x9e3779b9u);
      std::swap(p[i], p[h % static_cast<std::uint32_t>(i + 1)]);
    }
    for (int i = 0; i < 512; ++i) table[i] = p[i & 255];
  }
};
const PermutationTable kPermutation;

float smoothstep(float edge0, float edge1, float x) {
  const float t = std::clamp((x - edge0) / (edge1 - edge0), 0.0f, 1.0f);
  return t * t * (3.0f - 2.0f * t);
}

// Length of [a, b] inside the filter window [x - half, x + half], divided by the window width:
// the exact box-filtered indicator of an interval.
float intervalCoverage(float x, float half, float a, float b) {
  const float overlap = std::min(x + half, b) - std::max(x - half, a);
  return std::clamp(overlap / (2.0f * half), 0.0f, 1.0f);
}

std::uint32_t cellHash(std::uint32_t seed, int i, int j) {
  return hash32(seed ^ (static_cast<std::uint32_t>(i) * 0x8da6b343u) ^ (static_cast<std::uint32_t>(j) * 0xd8163841u));
}

// Rectangles, one candidate per cell, blended over `albedo`. The rectangle keeps the underlying
// noise detail (scaled) so that its inside is not flat: trackers need texture everywhere.
float rectangleLayer(float albedo, float base, float u, float v, float footprint, float cell, float density,
                     std::uint32_t seed) {
  const float mean_coverage = density * 0.3f;
  const float fade = smoothstep(0.2f * cell, 0.45f * cell, footprint);
  const float mean_delta = mean_coverage * (0.5f - albedo);
  if (fade >= 1.0f) return albedo + mean_delta;
  const int i = static_cast<int>(std::floor(u / cell));
  const int j = static_cast<int>(std::floor(v / cell));
  std::uint32_t h = cellHash(seed, i, j);
  float delta = 0.0f;
  if (unitFloat(h) < density) {
    h = hash32(h);
    const float w = (0.25f + 0.7f * unitFloat(h)) * cell;
    h = hash32(h);
    const float hgt = (0.25f + 0.7f * unitFloat(h)) * cell;
    h = hash32(h);
    const float x0 = static_cast<float>(i) * cell + unitFloat(h) * (cell - w);
    h = hash32(h);
    const float y0 = static_cast<float>(j) * cell + unitFloat(h) * (cell - hgt);
    h = hash32(h);
    // Dark or bright against the base, so that edges and corners have strong contrast.
    const float level = (h & 1u) ? 0.04f + 0.25f * unitFloat(hash32(h)) : 0.7f + 0.26f * unitFloat(hash32(h));
    const float half = 0.5f * footprint;
    const float coverage = intervalCoverage(u, half, x0, x0 + w) * intervalCoverage(v, half, y0, y0 + hgt);
    const float target = level + 0.6f * (albedo - base);
    delta = coverage * (target - albedo);
  }
  return albedo + (1.0f - fade) * delta + fade * mean_delta;
}

float blobLayer(float albedo, float u, float v, float footprint, float cell, float density, std::uint32_t seed) {
  // E[r^2] for r uniform in [0.1, 0.35] cell is 0.0558 cell^2, hence the mean covered fraction.
  const float mean_coverage = density * 3.14159265f * 0.0558f;
  const float fade = smoothstep(0.1f * cell, 0.3f * cell, footprint);
  const float mean_delta = mean_coverage * (0.5f - albedo);
  if (fade >= 1.0f) return albedo + mean_delta;
  const int i = static_cast<int>(std::floor(u / cell));
  const int j = static_cast<int>(std::floor(v / cell));
  std::uint32_t h = cellHash(seed, i, j);
  float delta = 0.0f;
  if (unitFloat(h) < density) {
    h = hash32(h);
    const float r = (0.1f + 0.25f * unitFloat(h)) * cell;
    h = hash32(h);
    const float cx = static_cast<float>(i) * cell + r + unitFloat(h) * (cell - 2.0f * r);
    h = hash32(h);
    const float cy = static_cast<float>(j) * cell + r + unitFloat(h) * (cell - 2.0f * r);
    h = hash32(h);
    const float level = (h & 1u) ? 0.05f + 0.2f * unitFloat(hash32(h)) : 0.75f + 0.2f * unitFloat(hash32(h));
    const float d = std::hypot(u - cx, v - cy);
    // Box filter of a straight edge, a good approximation while the footprint is below the radius.
    const float coverage = std::clamp((r - d) / footprint + 0.5f, 0.0f, 1.0f);
    delta = coverage * (level - albedo);
  }
  return albedo + (1.0f - fade) * delta + fade * mean_delta;
}

// Labels: a pale rectangle with rows of dark 3x5-block glyphs, like printed text seen from afar.
float textLayer(float albedo, float u, float v, float footprint, float block, float cell, float density,
                std::uint32_t seed) {
  constexpr int kGlyphW = 4;  // 3 blocks + 1 space
  constexpr int kGlyphH = 7;  // 5 blocks + 2 line spacing
  const int i = static_cast<int>(std::floor(u / cell));
  const int j = static_cast<int>(std::floor(v / cell));
  std::uint32_t h = cellHash(seed, i, j);
  if (unitFloat(h) >= density) return albedo;
  h = hash32(h);
  const float w = (0.5f + 0.4f * unitFloat(h)) * cell;
  h = hash32(h);
  const float hgt = (0.2f + 0.4f * unitFloat(h)) * cell;
  h = hash32(h);
  const float x0 = static_cast<float>(i) * cell + unitFloat(h) * (cell - w);
  h = hash32(h);
  const float y0 = static_cast<float>(j) * cell + unitFloat(h) * (cell - hgt);
  const float half = 0.5f * footprint;
  const float paper = intervalCoverage(u, half, x0, x0 + w) * intervalCoverage(v, half, y0, y0 + hgt);
  if (paper <= 0.0f) return albedo;
  const float paper_level = 0.88f + 0.15f * (albedo - 0.5f);
  float result = albedo + paper * (paper_level - albedo);

  // Ink: blocks of a glyph grid starting two blocks inside the label.
  const int cols = static_cast<int>((w / block - 4.0f) / kGlyphW);
  const int rows = static_cast<int>((hgt / block - 4.0f) / kGlyphH);
  if (cols <= 0 || rows <= 0) return result;
  const float ink_level = 0.08f;
  const float mean_ink = 0.85f * 15.0f / 28.0f * 0.55f;  // filled glyph fraction x bits set x cell area
  const float fade = smoothstep(0.4f * block, 0.9f * block, footprint);
  float ink = mean_ink;
  const float tx0 = x0 + 2.0f * block;
  const float ty0 = y0 + 2.0f * block;
  const bool inside_text = u + half > tx0 && u - half < tx0 + static_cast<float>(cols * kGlyphW) * block &&
                           v + half > ty0 && v - half < ty0 + static_cast<float>(rows * kGlyphH) * block;
  if (!inside_text) return result;
  if (fade < 1.0f) {
    const float bx = (u - tx0) / block;
    const float by = (v - ty0) / block;
    const float hb = half / block;
    float covered = 0.0f;
    for (int iy = static_cast<int>(std::floor(by - hb)); iy <= static_cast<int>(std::floor(by + hb)); ++iy) {
      if (iy < 0 || iy >= rows * kGlyphH || iy % kGlyphH >= 5) continue;
      const float oy = std::min(by + hb, static_cast<float>(iy + 1)) - std::max(by - hb, static_cast<float>(iy));
      for (int ix = static_cast<int>(std::floor(bx - hb)); ix <= static_cast<int>(std::floor(bx + hb)); ++ix) {
        if (ix < 0 || ix >= cols * kGlyphW || ix % kGlyphW >= 3) continue;
        const std::uint32_t glyph = hash32(h ^ cellHash(seed + 7u, ix / kGlyphW, iy / kGlyphH));
        if ((glyph >> 28) < 2u) continue;  // a space, about one glyph in eight
        const int bit = (iy % kGlyphH) * 3 + ix % kGlyphW;
        if (((glyph >> bit) & 1u) == 0u) continue;
        const float ox = std::min(bx + hb, static_cast<float>(ix + 1)) - std::max(bx - hb, static_cast<float>(ix));
        covered += std::max(ox, 0.0f) * std::max(oy, 0.0f);
      }
    }
    ink = (1.0f - fade) * covered / (4.0f * hb * hb) + fade * mean_ink;
  }
  return result + paper * ink * (ink_level - result);
}

}  // namespace

std::uint32_t hash32(std::uint32_t x) {
  // A well-mixing 32-bit integer finaliser (xorshift-multiply, bias-tested constants).
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

std::uint32_t hashCombine(std::uint32_t a, std::uint32_t b) {
  return hash32(a ^ (b + 0x9e3779b9u + (a << 6) + (a >> 2)));
}

std::uint64_t hash64(std::uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ull;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebull;
  x ^= x >> 31;
  return x;
}

float gradientNoise(float x, float y, std::uint32_t seed) {
  const float fx0 = std::floor(x);
  const float fy0 = std::floor(y);
  const int ix = static_cast<int>(fx0);
  const int iy = static_cast<int>(fy0);
  const float fx = x - fx0;
  const float fy = y - fy0;
  // Lattice hash by two permutation-table look-ups (period 256 cells, shifted by the seed): much
  // cheaper than a multiply-based hash, and each octave is rotated and offset, so the period
  // never shows.
  const std::uint8_t* perm = kPermutation.table;
  const unsigned seed_x = seed & 255u;
  const unsigned seed_y = (seed >> 8) & 255u;
  const unsigned px0 = perm[(static_cast<unsigned>(ix) + seed_x) & 255u];
  const unsigned px1 = perm[(static_cast<unsigned>(ix) + 1u + seed_x) & 255u];
  const unsigned jy = static_cast<unsigned>(iy) + seed_y;
  auto corner = [&](unsigned px, unsigned cy, float dx, float dy) {
    const unsigned g = perm[(px + cy) & 511u] & 15u;
    return kGradients.x[g] * dx + kGradients.y[g] * dy;
  };
  const float n00 = corner(px0, jy & 255u, fx, fy);
  const float n10 = corner(px1, jy & 255u, fx - 1.0f, fy);
  const float n01 = corner(px0, (jy + 1u) & 255u, fx, fy - 1.0f);
  const float n11 = corner(px1, (jy + 1u) & 255u, fx - 1.0f, fy - 1.0f);
  // Quintic fade: continuous second derivative, no creases at cell borders.
  const float sx = fx * fx * fx * (fx * (fx * 6.0f - 15.0f) + 10.0f);
  const float sy = fy * fy * fy * (fy * (fy * 6.0f - 15.0f) + 10.0f);
  const float a = n00 + sx * (n10 - n00);
  const float b = n01 + sx * (n11 - n01);
  return 1.4142135f * (a + sy * (b - a));  // unit gradients peak at 1/sqrt(2)
}

ProceduralTexture::ProceduralTexture(const TextureParams& params) : params_(params) {
  float wavelength = params.noise_max_wavelength_m;
  float amp = 1.0f;
  float energy = 0.0f;
  octaves_ = 0;
  while (wavelength >= params.noise_min_wavelength_m && octaves_ < 16) {
    energy += amp * amp;
    amp *= params.noise_persistence;
    wavelength *= 0.5f;
    ++octaves_;
  }
  // Normalise the summed octaves to unit standard deviation (up to the noise's own spread), so
  // noise_amp means the same thing whatever the spectrum.
  noise_norm_ = energy > 0.0f ? 1.0f / std::sqrt(energy) : 0.0f;
}

float ProceduralTexture::noise(float u, float v, float footprint_m) const {
  float wavelength = params_.noise_max_wavelength_m;
  float amp = 1.0f;
  float sum = 0.0f;
  // Each octave is rotated and shifted against the previous one so lattice axes never line up.
  constexpr float kCos = 0.79863551f;  // cos(37 deg)
  constexpr float kSin = 0.60181502f;
  float x = u;
  float y = v;
  for (int k = 0; k < octaves_; ++k) {
    // An octave is fully resolved when its wavelength spans four footprints and dropped at two
    // (the Nyquist limit); in between it fades, which replaces it by its zero mean.
    const float weight = smoothstep(2.0f, 4.0f, wavelength / footprint_m);
    if (weight <= 0.0f) break;
    const float inv = 1.0f / wavelength;
    sum += amp * weight * gradientNoise(x * inv, y * inv, params_.seed + static_cast<std::uint32_t>(k) * 101u);
    const float xr = kCos * x - kSin * y + 17.3f;
    y = kSin * x + kCos * y - 5.1f;
    x = xr;
    amp *= params_.noise_persistence;
    wavelength *= 0.5f;
  }
  return sum * noise_norm_;
}

float ProceduralTexture::sample(float u, float v, float footprint_m) const {
  const float footprint = std::max(footprint_m, 1e-6f);
  const TextureParams& p = params_;
  float albedo = p.base + p.noise_amp * noise(u, v, footprint);
  if (p.rect_cell_m > 0.0f) {
    albedo = rectangleLayer(albedo, p.base, u, v, footprint, p.rect_cell_m, p.rect_density, p.seed ^ 0x51ed27u);
  }
  if (p.blob_cell_m > 0.0f) {
    albedo = blobLayer(albedo, u, v, footprint, p.blob_cell_m, p.blob_density, p.seed ^ 0xb10b5u);
  }
  if (p.rect_small_cell_m > 0.0f) {
    albedo =
        rectangleLayer(albedo, p.base, u, v, footprint, p.rect_small_cell_m, p.rect_small_density, p.seed ^ 0x7a11e5u);
  }
  if (p.text_block_m > 0.0f) {
    albedo = textLayer(albedo, u, v, footprint, p.text_block_m, p.text_line_cell_m, p.text_density, p.seed ^ 0x7e47u);
  }
  return std::clamp(albedo, 0.02f, 0.98f);
}

}  // namespace voca::synth
