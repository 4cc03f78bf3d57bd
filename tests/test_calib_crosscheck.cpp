// Cross-check of two calibrations of the same physical rig: EuRoC's own sensor.yaml (pinhole +
// radial-tangential, Kalibr) against Basalt's euroc_ds_calib.json (double sphere). Both must
// describe the same cameras: 3-D points project to nearly the same pixels, and stereo pairs
// triangulate to the same points.

#include <algorithm>
#include <cmath>
#include <vector>

#include "formats/calib/calibration_io.h"
#include "tests/test_support.h"

namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

struct Rigs {
  voca::StereoRig radtan, ds;
};

std::optional<Rigs> loadRigs() {
  const auto mav0 = voca::test::sharedData("euroc_v101_micro/mav0");
  const auto json = voca::test::sharedData("calib/euroc_ds_calib.json");
  if (!mav0 || !json) return std::nullopt;
  return Rigs{voca::loadCalibration(*mav0), voca::loadCalibration(*json)};
}

bool inImage(const Vector2d& uv, const voca::CameraCalibration& cam) {
  return uv.x() >= 0 && uv.y() >= 0 && uv.x() <= cam.width - 1 && uv.y() <= cam.height - 1;
}

// Points over cam0's field of view at 1-10 m: a pixel grid of the radtan cam0 unprojected and
// placed at each depth (z in cam0), in the cam0 frame.
std::vector<Vector3d> pointsInView(const voca::CameraCalibration& cam0) {
  std::vector<Vector3d> points;
  for (int v = 5; v < cam0.height; v += 15) {
    for (int u = 5; u < cam0.width; u += 15) {
      Vector3d bearing;
      if (!cam0.camera.unproject(Vector2d(u, v), bearing) || bearing.z() <= 0) continue;
      for (double depth : {1.0, 2.0, 3.5, 5.0, 7.5, 10.0}) points.push_back(bearing / bearing.z() * depth);
    }
  }
  return points;
}

double percentile(std::vector<double> values, double q) {
  std::sort(values.begin(), values.end());
  return values[static_cast<size_t>(q * static_cast<double>(values.size() - 1))];
}

// Midpoint of the closest points of two rays from the origin (direction f0) and from c1 (direction f1).
Vector3d triangulate(const Vector3d& f0, const Vector3d& c1, const Vector3d& f1) {
  Eigen::Matrix<double, 3, 2> m;
  m << f0, -f1;
  const Vector2d s = (m.transpose() * m).ldlt().solve(m.transpose() * c1);
  return 0.5 * (s[0] * f0 + c1 + s[1] * f1);
}

}  // namespace

TEST_CASE("EuRoC radtan and double-sphere calibrations agree on the stereo extrinsics") {
  const auto rigs = loadRigs();
  if (!rigs) return;
  const voca::SE3d T_a = rigs->radtan.T_cam0_cam1(), T_b = rigs->ds.T_cam0_cam1();
  const double dt_mm = (T_a.translation() - T_b.translation()).norm() * 1e3;
  const double dr_deg = (T_a.inverse() * T_b).so3().log().norm() * 180.0 / M_PI;
  MESSAGE("stereo extrinsics differ by " << dt_mm << " mm and " << dr_deg << " deg");
  // Measured 0.59 mm and 0.079 deg: two independent calibrations of one rig. A sign, axis or
  // inversion mistake in either reader would give centimetres (the baseline is 110 mm) or degrees.
  CHECK(dt_mm < 1.0);
  CHECK(dr_deg < 0.1);
}

TEST_CASE("EuRoC radtan and double-sphere calibrations project points to the same pixels") {
  const auto rigs = loadRigs();
  if (!rigs) return;
  const voca::StereoRig& a = rigs->radtan;
  const voca::StereoRig& b = rigs->ds;
  const voca::SE3d T_cam1_cam0[2] = {a.T_cam0_cam1().inverse(), b.T_cam0_cam1().inverse()};

  for (int c = 0; c < 2; ++c) {
    CAPTURE(c);
    std::vector<double> all, central;
    int ds_failures = 0;
    for (const Vector3d& p_cam0 : pointsInView(a.cameras[0])) {
      // The same point in the cam0 frame of each rig (the body frames are compared elsewhere:
      // the two files' IMU-camera extrinsics differ by 8 mm, which says nothing about the cameras).
      const Vector3d p_a = c == 0 ? p_cam0 : Vector3d(T_cam1_cam0[0] * p_cam0);
      const Vector3d p_b = c == 0 ? p_cam0 : Vector3d(T_cam1_cam0[1] * p_cam0);
      Vector2d uv_a, uv_b;
      if (!a.cameras[c].camera.project(p_a, uv_a) || !inImage(uv_a, a.cameras[c])) continue;
      if (!b.cameras[c].camera.project(p_b, uv_b)) {
        ++ds_failures;
        continue;
      }
      const double error = (uv_a - uv_b).norm();
      all.push_back(error);
      const Vector2d centre(0.5 * (a.cameras[c].width - 1), 0.5 * (a.cameras[c].height - 1));
      if ((uv_a - centre).norm() <= 300.0) central.push_back(error);
    }
    CHECK(ds_failures == 0);  // the double sphere's valid region covers the whole radtan image
    REQUIRE(all.size() > 5000);
    REQUIRE(central.size() > 0.7 * all.size());
    const double central_max = percentile(central, 1.0), median = percentile(all, 0.5), p90 = percentile(all, 0.9),
                 max = percentile(all, 1.0);
    MESSAGE("cam" << c << ": pixel disagreement median " << median << ", p90 " << p90 << ", max " << max
                  << ", max within 300 px of the centre " << central_max);
    // Measured (cam0 / cam1): median 1.6 / 1.5 px, p90 2.1 / 2.0 px, max within 300 px of the centre
    // 2.2 / 2.2 px. The near-constant 1.5 px is mostly the principal points of the two calibrations
    // (367.2, 248.4 vs 365.9, 249.3 for cam0): two calibration sessions, not a reader error (a
    // wrong parameter order or unit is tens to hundreds of pixels). In the corners (beyond ~300 px),
    // where the calibration targets rarely reach, radtan's polynomial and the double sphere
    // extrapolate differently: up to 18.8 / 17.3 px.
    CHECK(median < 2.0);
    CHECK(p90 < 2.5);
    CHECK(central_max < 3.0);
    CHECK(max < 25.0);
  }
}

TEST_CASE("a stereo pair from one calibration triangulates to the same point with the other") {
  const auto rigs = loadRigs();
  if (!rigs) return;
  const voca::StereoRig& a = rigs->radtan;
  const voca::StereoRig& b = rigs->ds;
  const voca::SE3d T_cam1_cam0_a = a.T_cam0_cam1().inverse();
  const voca::SE3d T_cam0_cam1_b = b.T_cam0_cam1();
  // Depth error expressed as the disparity error that would cause it: dZ * f * baseline / Z^2.
  const double f_times_baseline = a.cameras[0].camera.params()[0] * a.baselineM();
  double worst_disparity_px = 0.0;
  int count = 0, unprojection_failures = 0;
  for (const Vector3d& p_cam0 : pointsInView(a.cameras[0])) {
    Vector2d uv0, uv1;
    const Vector2d centre(375.5, 239.5);
    // Pixels within 300 px of the centre of both images, where the two models agree (see above).
    if (!a.cameras[0].camera.project(p_cam0, uv0) || (uv0 - centre).norm() > 300.0) continue;
    if (!a.cameras[1].camera.project(T_cam1_cam0_a * p_cam0, uv1) || (uv1 - centre).norm() > 300.0) continue;
    Vector3d f0, f1;
    if (!b.cameras[0].camera.unproject(uv0, f0) || !b.cameras[1].camera.unproject(uv1, f1)) {
      ++unprojection_failures;
      continue;
    }
    const Vector3d p_b = triangulate(f0, T_cam0_cam1_b.translation(), T_cam0_cam1_b.so3() * f1);
    const double depth = p_cam0.z();
    worst_disparity_px = std::max(worst_disparity_px, (p_b - p_cam0).norm() * f_times_baseline / (depth * depth));
    ++count;
  }
  CHECK(unprojection_failures == 0);
  REQUIRE(count > 2000);
  MESSAGE("worst triangulation error, as a disparity error: " << worst_disparity_px << " px over " << count
                                                              << " points");
  // Measured 0.6 px: about 1 % of depth at 1-2 m and up to 11 % at 10 m, where the disparity is
  // only 5 px. The pixel offsets of the previous test are common to both cameras and largely
  // cancel in the disparity. A baseline or rotation error (mm, 0.1 deg) would exceed 1 px.
  CHECK(worst_disparity_px < 1.0);
}
