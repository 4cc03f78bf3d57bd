#pragma once
// Procedural surface textures for the synthetic scene: multi-scale gradient noise, blobs, rectangles
// (posters, tiles) and text-like glyph rows, all evaluated with a footprint-aware filter.
//
// Every layer is a function of surface coordinates (u, v) in metres and of the filter width
// footprint_m (the size of the area one image sample covers on the surface). Detail finer than the
// footprint fades to its local mean instead of aliasing, and hard edges are box-filtered
// analytically, so the renderer needs only one sample per pixel away from silhouettes.

#include <cstdint>

namespace voca::synth {

// Deterministic integer hashes used by the textures, the scene layout and the sensor noise.
std::uint32_t hash32(std::uint32_t x);
std::uint32_t hashCombine(std::uint32_t a, std::uint32_t b);
std::uint64_t hash64(std::uint64_t x);
// Uniform in [0, 1) from a hash.
inline float unitFloat(std::uint32_t h) { return static_cast<float>(h >> 8) * (1.0f / 16777216.0f); }

// 2-D gradient noise in about [-1, 1], C2 (quintic fade), zero mean.
float gradientNoise(float x, float y, std::uint32_t seed);

// One material: a base level with a noise spectrum plus optional overlay layers. Sizes in metres.
struct TextureParams {
  std::uint32_t seed = 1;
  float base = 0.5f;        // mean albedo, [0, 1]
  float noise_amp = 0.25f;  // amplitude of the largest noise octave
  float noise_max_wavelength_m = 1.5f;
  float noise_min_wavelength_m = 0.002f;
  float noise_persistence = 0.8f;  // amplitude ratio between successive octaves (wavelength halves)
  // Rectangles: one per cell with probability rect_density, random size and albedo.
  float rect_cell_m = 0.0f;  // 0 disables the layer
  float rect_density = 0.6f;
  float rect_small_cell_m = 0.0f;  // a second, finer rectangle layer (tiles, stickers)
  float rect_small_density = 0.3f;
  // Discs.
  float blob_cell_m = 0.0f;
  float blob_density = 0.5f;
  // Text-like glyph rows inside label boxes: glyph block size (one of the 3x5 cells of a glyph).
  float text_block_m = 0.0f;
  float text_line_cell_m = 0.5f;  // one label per cell of this size, with probability text_density
  float text_density = 0.5f;
};

// A procedural texture; cheap to copy, immutable after construction.
class ProceduralTexture {
 public:
  ProceduralTexture() = default;
  explicit ProceduralTexture(const TextureParams& params);

  // Albedo in [0, 1] at surface coordinates (u, v) metres, box-filtered over footprint_m.
  float sample(float u, float v, float footprint_m) const;
  const TextureParams& params() const { return params_; }

 private:
  float noise(float u, float v, float footprint_m) const;

  TextureParams params_;
  int octaves_ = 0;
  float noise_norm_ = 1.0f;
};

}  // namespace voca::synth
