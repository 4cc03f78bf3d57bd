#pragma once
// Synthetic inputs for the frontend tests: a smooth random texture that can be rendered at any
// sub-pixel shift exactly, and a pinhole stereo rig.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "voca/calib/calibration.h"
#include "voca/core/image.h"

namespace voca::test {

// Sum of random plane waves around gray 128: I(x, y) = 128 + sum a_k sin(u_k x + v_k y + phi_k).
// Separable evaluation (sin(a + b) = sin a cos b + cos a sin b) keeps rendering cheap. Wavelengths
// between min and max give texture at several scales (corners for the detector, basins for KLT).
class WaveTexture {
 public:
  WaveTexture(std::uint32_t seed, int num_waves = 48, double min_wavelength_px = 6.0, double max_wavelength_px = 60.0,
              double total_amplitude = 110.0) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int k = 0; k < num_waves; ++k) {
      const double wavelength = min_wavelength_px * std::pow(max_wavelength_px / min_wavelength_px, unit(rng));
      const double angle = 2.0 * M_PI * unit(rng);
      const double omega = 2.0 * M_PI / wavelength;
      waves_.push_back({omega * std::cos(angle), omega * std::sin(angle), 2.0 * M_PI * unit(rng),
                        total_amplitude / std::sqrt(static_cast<double>(num_waves)) * (0.5 + unit(rng))});
    }
  }

  // A texture periodic with period_px in x and y: integer numbers of cycles per period in each axis.
  static WaveTexture periodic(std::uint32_t seed, int period_px, int num_waves = 24, double total_amplitude = 110.0) {
    WaveTexture texture(seed, 0);
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> cycles(-3, 3);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const double base = 2.0 * M_PI / period_px;
    while (static_cast<int>(texture.waves_.size()) < num_waves) {
      const int m = cycles(rng), n = cycles(rng);
      if (m == 0 && n == 0) continue;
      texture.waves_.push_back({base * m, base * n, 2.0 * M_PI * unit(rng),
                                total_amplitude / std::sqrt(static_cast<double>(num_waves)) * (0.5 + unit(rng))});
    }
    return texture;
  }

  double at(double x, double y) const {
    double value = 128.0;
    for (const Wave& w : waves_) value += w.amplitude * std::sin(w.u * x + w.v * y + w.phase);
    return value;
  }

  // Pixel (x, y) gets the texture at (x - shift_x, y - shift_y): content moves by +shift.
  void render(GrayImage& out, int width, int height, double shift_x, double shift_y) const {
    out.resize(width, height);
    std::vector<double> acc(static_cast<std::size_t>(width) * height, 128.0);
    std::vector<double> sx(width), cx(width), sy(height), cy(height);
    for (const Wave& w : waves_) {
      for (int x = 0; x < width; ++x) {
        const double a = w.u * (x - shift_x) + w.phase;
        sx[x] = std::sin(a);
        cx[x] = std::cos(a);
      }
      for (int y = 0; y < height; ++y) {
        const double b = w.v * (y - shift_y);
        sy[y] = std::sin(b);
        cy[y] = std::cos(b);
      }
      for (int y = 0; y < height; ++y) {
        double* row = acc.data() + static_cast<std::size_t>(y) * width;
        const double c = w.amplitude * cy[y], s = w.amplitude * sy[y];
        for (int x = 0; x < width; ++x) row[x] += sx[x] * c + cx[x] * s;
      }
    }
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        const double v = std::round(acc[static_cast<std::size_t>(y) * width + x]);
        out(x, y) = static_cast<std::uint8_t>(std::clamp(v, 0.0, 255.0));
      }
    }
  }

 private:
  struct Wave {
    double u, v, phase, amplitude;
  };
  std::vector<Wave> waves_;
};

// Two identical pinhole cameras, cam1 baseline_m to the right of cam0 (x axis), no rotation.
inline StereoRig pinholeRig(int width, int height, double focal_px, double baseline_m) {
  const std::vector<double> params = {focal_px, focal_px, 0.5 * (width - 1), 0.5 * (height - 1)};
  StereoRig rig;
  rig.source = "test rig";
  rig.body_frame = "cam0";
  for (int c = 0; c < 2; ++c) {
    CameraCalibration cam;
    cam.camera = GenericCamera<double>::fromParams("pinhole", params);
    cam.width = width;
    cam.height = height;
    cam.T_body_cam = SE3d(Eigen::Matrix3d::Identity(), Eigen::Vector3d(c * baseline_m, 0.0, 0.0));
    rig.cameras.push_back(cam);
  }
  return rig;
}

}  // namespace voca::test
