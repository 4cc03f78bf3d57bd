#include "voca/synth/renderer.h"

#include <algorithm>
#include <cmath>
#include <span>

namespace voca::synth {

namespace {

// Grazing surfaces spread a pixel over a long strip; the filter follows the strip's long axis
// (no aliasing) but is capped so that floors seen at a shallow angle keep some detail.
constexpr float kMinCosIncidence = 0.15f;

struct CameraPose {
  Eigen::Matrix3f R;
  Eigen::Vector3f t;
};

float sampleRay(const Scene& scene, const CameraPose& pose, const Eigen::Vector3f& bearing, float angle, int* surface) {
  const Eigen::Vector3f dir = (pose.R * bearing).normalized();
  Hit hit;
  if (!scene.intersect(pose.t, dir, hit)) {
    if (surface != nullptr) *surface = -1;
    return 0.0f;
  }
  if (surface != nullptr) *surface = hit.surface;
  const float cos_incidence = std::max(std::abs(hit.normal.dot(dir)), kMinCosIncidence);
  return scene.radiance(hit, hit.t * angle / cos_incidence);
}

}  // namespace

RayTable::RayTable(int width, int height, const Unproject& unproject)
    : width_(width),
      height_(height),
      bearings_(static_cast<std::size_t>(width) * height, Eigen::Vector3f::Zero()),
      pixel_angle_(static_cast<std::size_t>(width) * height, 0.0f),
      valid_(static_cast<std::size_t>(width) * height, 0) {
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      Eigen::Vector3d bearing;
      if (unproject(Eigen::Vector2d(x, y), bearing) && std::isfinite(bearing.squaredNorm()) &&
          bearing.squaredNorm() > 0.0) {
        bearings_[index(x, y)] = bearing.normalized().cast<float>();
        valid_[index(x, y)] = 1;
      }
    }
  }
  // The angle between neighbouring pixel rays: the chord of unit vectors equals the angle to
  // well below a percent at pixel scale.
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      if (!valid(x, y)) continue;
      float angle = 0.0f;
      const int nx = (x + 1 < width && valid(x + 1, y)) ? x + 1 : x - 1;
      const int ny = (y + 1 < height && valid(x, y + 1)) ? y + 1 : y - 1;
      if (nx >= 0 && valid(nx, y)) angle = std::max(angle, (bearing(nx, y) - bearing(x, y)).norm());
      if (ny >= 0 && valid(x, ny)) angle = std::max(angle, (bearing(x, ny) - bearing(x, y)).norm());
      pixel_angle_[index(x, y)] = angle > 0.0f ? angle : 1e-3f;
    }
  }
}

Eigen::Vector3f RayTable::bearingAt(int x, int y, float dx, float dy) const {
  const Eigen::Vector3f& b00 = bearing(x, y);
  // Step towards the offset; at the border (or next to an invalid ray) extrapolate from the other side.
  int nx = dx >= 0.0f ? x + 1 : x - 1;
  float fx = std::abs(dx);
  if (nx < 0 || nx >= width_ || !valid(nx, y)) {
    nx = 2 * x - nx;
    fx = -fx;
  }
  int ny = dy >= 0.0f ? y + 1 : y - 1;
  float fy = std::abs(dy);
  if (ny < 0 || ny >= height_ || !valid(x, ny)) {
    ny = 2 * y - ny;
    fy = -fy;
  }
  Eigen::Vector3f b = b00;
  const bool has_x = nx >= 0 && nx < width_ && valid(nx, y);
  const bool has_y = ny >= 0 && ny < height_ && valid(x, ny);
  if (has_x) b += fx * (bearing(nx, y) - b00);
  if (has_y) b += fy * (bearing(x, ny) - b00);
  if (has_x && has_y && valid(nx, ny)) b += fx * fy * (bearing(nx, ny) - bearing(nx, y) - bearing(x, ny) + b00);
  return b.normalized();
}

void renderRows(const Scene& scene, const RayTable& rays, const SE3d& T_world_cam, const RenderSettings& settings,
                ImageView<std::uint8_t> out, int y_begin, int y_end) {
  renderRows(scene, rays, std::span<const SE3d>(&T_world_cam, 1), settings, out, y_begin, y_end);
}

void renderRows(const Scene& scene, const RayTable& rays, std::span<const SE3d> exposure_poses,
                const RenderSettings& settings, ImageView<std::uint8_t> out, int y_begin, int y_end) {
  const int width = rays.width();
  const int height = rays.height();

  // Lens PSF: a sampled, normalised Gaussian truncated at 3 sigma (radius 0 disables it).
  const float sigma = std::max(settings.psf_sigma_px, 0.0f);
  const int radius = sigma > 0.0f ? static_cast<int>(std::ceil(3.0f * sigma)) : 0;
  std::vector<float> kernel(static_cast<std::size_t>(2 * radius + 1), 1.0f);
  if (radius > 0) {
    float total = 0.0f;
    for (int d = -radius; d <= radius; ++d) {
      kernel[static_cast<std::size_t>(d + radius)] = std::exp(-0.5f * static_cast<float>(d * d) / (sigma * sigma));
      total += kernel[static_cast<std::size_t>(d + radius)];
    }
    for (float& w : kernel) w /= total;
  }

  // Irradiance is needed `radius` rows either side of the output (the PSF's support), and centre
  // samples one row further (edge detection looks at the 4-neighbours).
  const int irr0 = std::max(y_begin - radius, 0);
  const int irr1 = std::min(y_end + radius, height);
  const int row0 = std::max(irr0 - 1, 0);
  const int row1 = std::min(irr1 + 1, height);
  const std::size_t rows = static_cast<std::size_t>(std::max(row1 - row0, 0));
  std::vector<float> value(rows * width, 0.0f);
  std::vector<int> surface(rows * width, -1);
  // Pixel irradiance, averaged over the poses the camera passes through while the shutter is open:
  // the centre sample, or n x n stratified samples where an edge may cross the pixel.
  const int n = std::max(settings.supersample, 1);
  const float inv_n = 1.0f / static_cast<float>(n);
  std::vector<float> irradiance(static_cast<std::size_t>(std::max(irr1 - irr0, 0)) * width, 0.0f);
  for (const SE3d& T_world_cam : exposure_poses) {
    const CameraPose pose{T_world_cam.rotationMatrix().cast<float>(), T_world_cam.translation().cast<float>()};
    for (int y = row0; y < row1; ++y) {
      const std::size_t base = static_cast<std::size_t>(y - row0) * width;
      for (int x = 0; x < width; ++x) {
        if (!rays.valid(x, y)) {
          surface[base + x] = -2;
          continue;
        }
        value[base + x] = sampleRay(scene, pose, rays.bearing(x, y), rays.pixelAngle(x, y), &surface[base + x]);
      }
    }

    for (int y = irr0; y < irr1; ++y) {
      const std::size_t base = static_cast<std::size_t>(y - row0) * width;
      float* irr_row = irradiance.data() + static_cast<std::size_t>(y - irr0) * width;
      for (int x = 0; x < width; ++x) {
        const int id = surface[base + x];
        if (id == -2) continue;
        float v = value[base + x];
        // A different surface in a 4-neighbour means an edge may cross this pixel: integrate it.
        bool edge = false;
        if (x > 0 && surface[base + x - 1] != id) edge = true;
        if (x + 1 < width && surface[base + x + 1] != id) edge = true;
        if (y > 0 && surface[base + x - width] != id) edge = true;
        if (y + 1 < height && surface[base + x + width] != id) edge = true;
        if (edge && n > 1) {
          const float angle = rays.pixelAngle(x, y) * inv_n;
          float sum = 0.0f;
          for (int sy = 0; sy < n; ++sy) {
            for (int sx = 0; sx < n; ++sx) {
              const float dx = (static_cast<float>(sx) + 0.5f) * inv_n - 0.5f;
              const float dy = (static_cast<float>(sy) + 0.5f) * inv_n - 0.5f;
              sum += sampleRay(scene, pose, rays.bearingAt(x, y, dx, dy), angle, nullptr);
            }
          }
          v = sum * inv_n * inv_n;
        }
        irr_row[x] += v;
      }
    }
  }
  // Exposure: the mean over the shutter's poses, times the sensor gain (a darker scene or a shorter
  // exposure gives less signal against the same noise). Both factors are 1 by default: exact.
  const float exposure_scale = settings.gain / static_cast<float>(std::max<std::size_t>(exposure_poses.size(), 1));
  for (float& v : irradiance) v *= exposure_scale;

  // Separable PSF, border pixels replicated: every output still depends only on its coordinates.
  std::vector<float> blurred_x(irradiance.size(), 0.0f);
  for (int y = irr0; y < irr1; ++y) {
    const float* in = irradiance.data() + static_cast<std::size_t>(y - irr0) * width;
    float* bx = blurred_x.data() + static_cast<std::size_t>(y - irr0) * width;
    for (int x = 0; x < width; ++x) {
      float sum = 0.0f;
      for (int d = -radius; d <= radius; ++d) {
        sum += kernel[static_cast<std::size_t>(d + radius)] * in[std::clamp(x + d, 0, width - 1)];
      }
      bx[x] = sum;
    }
  }

  const std::uint64_t image_key =
      hash64(settings.noise_seed ^ hash64(settings.frame_index * 8u +
                                          static_cast<std::uint64_t>(settings.camera_index) + 0x243f6a8885a308d3ull));
  for (int y = y_begin; y < y_end; ++y) {
    std::uint8_t* out_row = out.row(y);
    for (int x = 0; x < width; ++x) {
      float v = 0.0f;
      for (int d = -radius; d <= radius; ++d) {
        const int yy = std::clamp(y + d, 0, height - 1);
        v += kernel[static_cast<std::size_t>(d + radius)] * blurred_x[static_cast<std::size_t>(yy - irr0) * width + x];
      }
      if (!rays.valid(x, y)) v = 0.0f;
      if (settings.noise_sigma > 0.0f) {
        // Counter-based Gaussian (Box-Muller on a per-pixel hash): independent of the row split.
        const std::uint64_t h = hash64(image_key + static_cast<std::uint64_t>(y) * width + x);
        const float u1 = (static_cast<float>(h & 0xffffffu) + 0.5f) * (1.0f / 16777216.0f);
        const float u2 = static_cast<float>((h >> 32) & 0xffffffu) * (1.0f / 16777216.0f);
        v += settings.noise_sigma * std::sqrt(-2.0f * std::log(u1)) * std::cos(6.28318531f * u2);
      }
      out_row[x] = static_cast<std::uint8_t>(static_cast<int>(std::clamp(v, 0.0f, 255.0f) + 0.5f));
    }
  }
}

float rayDepth(const Scene& scene, const RayTable& rays, const SE3d& T_world_cam, int x, int y) {
  if (!rays.valid(x, y)) return 0.0f;
  const Eigen::Vector3f dir = (T_world_cam.rotationMatrix().cast<float>() * rays.bearing(x, y)).normalized();
  Hit hit;
  if (!scene.intersect(T_world_cam.translation().cast<float>(), dir, hit)) return 0.0f;
  return hit.t;
}

}  // namespace voca::synth
