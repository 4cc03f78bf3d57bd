#pragma once
// Ray-casting renderer: per-pixel camera rays (computed once through any camera model), one
// footprint-filtered sample per pixel plus stratified supersampling where a silhouette or crease
// crosses the pixel, a Gaussian lens PSF, seeded Gaussian sensor noise, 8-bit gray output.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "voca/core/image.h"
#include "voca/geometry/se3.h"
#include "voca/synth/scene.h"

namespace voca::synth {

// Unit bearing of every pixel centre of a fixed camera, in the camera frame, plus the angle one
// pixel spans there (the sample footprint). Pixel (x, y) has its centre at image coordinates (x, y).
class RayTable {
 public:
  // Returns false when the pixel has no valid ray (outside a fisheye's field of view).
  using Unproject = std::function<bool(const Eigen::Vector2d& uv, Eigen::Vector3d& bearing)>;

  RayTable() = default;
  RayTable(int width, int height, const Unproject& unproject);

  int width() const { return width_; }
  int height() const { return height_; }
  bool valid(int x, int y) const { return valid_[index(x, y)] != 0; }
  const Eigen::Vector3f& bearing(int x, int y) const { return bearings_[index(x, y)]; }
  float pixelAngle(int x, int y) const { return pixel_angle_[index(x, y)]; }
  // Bearing at a sub-pixel offset (|dx|, |dy| <= 0.5) from pixel (x, y)'s centre, interpolated
  // from the neighbouring pixel rays; exact to second order in the offset, far below a pixel.
  Eigen::Vector3f bearingAt(int x, int y, float dx, float dy) const;

 private:
  std::size_t index(int x, int y) const { return static_cast<std::size_t>(y) * width_ + x; }

  int width_ = 0;
  int height_ = 0;
  std::vector<Eigen::Vector3f> bearings_;
  std::vector<float> pixel_angle_;
  std::vector<std::uint8_t> valid_;
};

// How one image is rendered.
struct RenderSettings {
  float noise_sigma = 2.0f;  // gray levels, Gaussian, independent per pixel and frame
  std::uint64_t noise_seed = 0;
  std::uint64_t frame_index = 0;  // with camera_index, selects the noise field of this image
  int camera_index = 0;
  int supersample = 3;  // n x n stratified samples in pixels crossed by an edge
  // Optical blur (lens PSF), Gaussian sigma in pixels, applied to the pixel irradiance before noise.
  // Real optics leave almost no contrast at Nyquist; without it pixel-scale texture detail and
  // box-filtered edges reach the sampling limit, where any sub-pixel interpolation (KLT's bilinear
  // one included) is biased. 0 (the default for now) keeps renders byte-identical to before.
  float psf_sigma_px = 0.0f;
  // Sensor gain on the irradiance, before noise: < 1 renders a dark, low-contrast scene (less signal
  // against the same noise), as dim light or a short exposure does.
  float gain = 1.0f;
};

// Renders rows [y_begin, y_end) of a camera at pose T_world_cam into out (same size as the ray
// table). Rows are independent and every pixel's value depends only on its own coordinates, so
// splitting an image into row ranges (across threads, say) gives the same bytes as one call.
void renderRows(const Scene& scene, const RayTable& rays, const SE3d& T_world_cam, const RenderSettings& settings,
                ImageView<std::uint8_t> out, int y_begin, int y_end);

// The same with motion blur: the irradiance is averaged over the camera poses sampled while the
// shutter is open (in time order, equally spaced), then blurred by the PSF and given noise once.
void renderRows(const Scene& scene, const RayTable& rays, std::span<const SE3d> exposure_poses,
                const RenderSettings& settings, ImageView<std::uint8_t> out, int y_begin, int y_end);

// Distance along each pixel's centre ray to the first surface (0 where there is no valid ray);
// for tests and image-motion measurements.
float rayDepth(const Scene& scene, const RayTable& rays, const SE3d& T_world_cam, int x, int y);

}  // namespace voca::synth
