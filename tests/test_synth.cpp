#include <algorithm>
#include <cmath>
#include <span>
#include <vector>

#include "tests/test_support.h"
#include "voca/synth/motion.h"
#include "voca/synth/renderer.h"
#include "voca/synth/rigs.h"
#include "voca/synth/scene.h"
#include "voca/synth/texture.h"

using namespace voca::synth;
using voca::SE3d;
using voca::SO3d;

namespace {

// A level camera at `position` looking along world +x (camera x = world -y, y = world -z).
SE3d levelCamera(const Eigen::Vector3d& position, double yaw = 0.0) {
  Eigen::Matrix3d level;
  level << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return SE3d(SO3d(Eigen::Matrix3d(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * level)), position);
}

// Uniform dark walls, no lights: the image is the albedo times 255, so a marker is all that varies.
Scene plainRoom(float wall_albedo) {
  Scene scene;
  TextureParams plain;
  plain.base = wall_albedo;
  plain.noise_amp = 0.0f;
  const int m = scene.addMaterial(plain);
  for (int wall = 0; wall < 6; ++wall) scene.setWallMaterial(wall, m);
  scene.setAmbient(1.0f);
  return scene;
}

voca::CameraCalibration smallPinhole(int width, int height) {
  const std::vector<double> params = {0.6 * width, 0.6 * width, 0.5 * width - 0.5, 0.5 * height - 0.5};
  return {voca::GenericCamera<double>::fromParams("pinhole", params), width, height, SE3d()};
}

}  // namespace

TEST_CASE("every ray-cast hit projects back onto its own pixel") {
  const voca::StereoRig rig = eurocRig();
  for (const voca::CameraCalibration& cam : {rig.cameras[0], tumviRig().cameras[0]}) {
    const RayTable rays = makeRayTable(cam);
    const std::vector<Eigen::Vector3d> no_keep_out;
    const Scene scene = Scene::generate(SceneConfig(), no_keep_out, 3);
    const SE3d T_world_cam = levelCamera(Eigen::Vector3d(-1.0, 0.3, 1.4), 0.4);
    double worst_px = 0.0;
    int checked = 0;
    for (int y = 0; y < cam.height; y += 7) {
      for (int x = 0; x < cam.width; x += 7) {
        if (!rays.valid(x, y)) continue;
        const float depth = rayDepth(scene, rays, T_world_cam, x, y);
        REQUIRE(depth > 0.0f);
        // Re-derive the hit in double from the float depth: the check covers the ray table
        // (unproject, storage as float) and the intersection distance.
        const Eigen::Vector3d p_cam = rays.bearing(x, y).cast<double>() * depth;
        Eigen::Vector2d uv;
        REQUIRE(cam.camera.project(p_cam, uv));
        worst_px = std::max(worst_px, (uv - Eigen::Vector2d(x, y)).norm());
        ++checked;
      }
    }
    CHECK(checked > 3000);
    // Float bearings (1e-7 relative) and float depths over a few metres give ~1e-4 px; 2e-3 px
    // leaves room for the fisheye's unproject tolerance while catching any half-pixel convention slip.
    CHECK(worst_px < 2e-3);
  }
}

TEST_CASE("ray-cast depth matches the analytic distance to the wall") {
  const voca::CameraCalibration cam = eurocRig().cameras[0];
  const RayTable rays = makeRayTable(cam);
  Scene scene = plainRoom(0.2f);  // no objects: every ray ends on a wall, floor or ceiling
  const SE3d T_world_cam = levelCamera(Eigen::Vector3d(0.5, -0.2, 1.3));
  const RoomBox room;
  double worst = 0.0;
  for (int y = 0; y < cam.height; y += 11) {
    for (int x = 0; x < cam.width; x += 11) {
      const Eigen::Vector3d dir = T_world_cam.so3() * rays.bearing(x, y).cast<double>().normalized();
      double expected = 1e9;
      for (int a = 0; a < 3; ++a) {
        if (dir[a] == 0.0) continue;
        const double bound = dir[a] > 0 ? room.max[a] : room.min[a];
        expected = std::min(expected, (bound - T_world_cam.translation()[a]) / dir[a]);
      }
      worst = std::max(worst, std::abs(rayDepth(scene, rays, T_world_cam, x, y) - expected) / expected);
    }
  }
  CHECK(worst < 1e-5);  // float arithmetic on metre-scale values: ~1e-7 relative, with margin
}

TEST_CASE("a rendered marker disc lands where the camera model projects its centre") {
  const voca::CameraCalibration cam = eurocRig().cameras[0];
  const RayTable rays = makeRayTable(cam);
  const SE3d T_world_cam = levelCamera(Eigen::Vector3d(0.0, 0.0, 1.5));
  const Eigen::Vector3d cam_z = T_world_cam.so3() * Eigen::Vector3d::UnitZ();
  // Centre, an off-axis point and a corner where radtan distortion is strong (~25 px).
  for (const Eigen::Vector3d& p_cam :
       {Eigen::Vector3d(0.013, -0.021, 2.0), Eigen::Vector3d(0.61, 0.27, 2.5), Eigen::Vector3d(-1.3, -0.85, 2.2)}) {
    Scene scene = plainRoom(0.1f);
    const Eigen::Vector3d center = T_world_cam * p_cam;
    // Facing the image plane: the projected disc is centred on the projected centre up to the
    // distortion's curvature over the disc, which is below 0.01 px for a 4 px radius.
    const float radius_m = static_cast<float>(4.0 / 458.0 * p_cam.z());
    scene.addDisc({center.cast<float>(), (-cam_z).cast<float>(), radius_m, 0.9f});
    Eigen::Vector2d expected;
    REQUIRE(cam.camera.project(p_cam, expected));

    RenderSettings settings;
    settings.noise_sigma = 0.0f;
    voca::GrayImage image(cam.width, cam.height, 0);
    const int cy = static_cast<int>(std::lround(expected.y()));
    const int y0 = std::max(cy - 12, 0);
    const int y1 = std::min(cy + 13, cam.height);
    renderRows(scene, rays, T_world_cam, settings, image.view(), y0, y1);
    const double background = 0.1 * 255.0;
    double sum = 0.0, sx = 0.0, sy = 0.0;
    const int cx = static_cast<int>(std::lround(expected.x()));
    for (int y = y0; y < y1; ++y) {
      for (int x = std::max(cx - 12, 0); x < std::min(cx + 13, cam.width); ++x) {
        const double w = std::max(static_cast<double>(image(x, y)) - background, 0.0);
        sum += w;
        sx += w * x;
        sy += w * y;
      }
    }
    REQUIRE(sum > 0.0);
    const Eigen::Vector2d centroid(sx / sum, sy / sum);
    INFO("expected " << expected.transpose() << " centroid " << centroid.transpose());
    // Edge pixels integrate 9 samples (coverage steps of 1/9) and values are rounded to 8 bits:
    // over the ~25 edge pixels of the disc this moves the centroid by about 0.01 px.
    CHECK((centroid - expected).norm() < 0.05);
  }
}

TEST_CASE("rendering is deterministic, independent of the row split, and seeded noise differs") {
  const voca::CameraCalibration cam = smallPinhole(96, 64);
  const RayTable rays = makeRayTable(cam);
  const std::vector<Eigen::Vector3d> no_keep_out;
  const Scene scene = Scene::generate(SceneConfig(), no_keep_out, 11);
  const SE3d T_world_cam = levelCamera(Eigen::Vector3d(-0.5, 0.5, 1.2), -0.3);
  RenderSettings settings;
  settings.noise_seed = 5;
  settings.frame_index = 3;

  voca::GrayImage whole(cam.width, cam.height, 0), split(cam.width, cam.height, 0), other(cam.width, cam.height, 0);
  renderRows(scene, rays, T_world_cam, settings, whole.view(), 0, cam.height);
  for (int y0 = 0; y0 < cam.height; y0 += 7) {
    renderRows(scene, rays, T_world_cam, settings, split.view(), y0, std::min(y0 + 7, cam.height));
  }
  CHECK(std::equal(whole.data(), whole.data() + whole.pixelCount(), split.data()));

  // The lens PSF reads neighbouring rows; a split must still not change a byte, and it must blur.
  RenderSettings blurred = settings;
  blurred.psf_sigma_px = 0.6f;
  voca::GrayImage blur_whole(cam.width, cam.height, 0), blur_split(cam.width, cam.height, 0);
  renderRows(scene, rays, T_world_cam, blurred, blur_whole.view(), 0, cam.height);
  for (int y0 = 0; y0 < cam.height; y0 += 5) {
    renderRows(scene, rays, T_world_cam, blurred, blur_split.view(), y0, std::min(y0 + 5, cam.height));
  }
  CHECK(std::equal(blur_whole.data(), blur_whole.data() + blur_whole.pixelCount(), blur_split.data()));
  CHECK(!std::equal(whole.data(), whole.data() + whole.pixelCount(), blur_whole.data()));

  settings.noise_seed = 6;
  renderRows(scene, rays, T_world_cam, settings, other.view(), 0, cam.height);
  double abs_diff = 0.0;
  int differing = 0;
  for (std::size_t i = 0; i < whole.pixelCount(); ++i) {
    const int d = static_cast<int>(whole.data()[i]) - static_cast<int>(other.data()[i]);
    abs_diff += std::abs(d);
    differing += d != 0;
  }
  abs_diff /= static_cast<double>(whole.pixelCount());
  // Two independent N(0, 2^2) fields differ by N(0, 8): E|d| = sqrt(8) sqrt(2/pi) = 2.26 gray levels
  // (slightly less where the signal clips); anything else means the seed is ignored or leaks into the scene.
  CHECK(abs_diff > 1.8);
  CHECK(abs_diff < 2.7);
  CHECK(differing > static_cast<int>(whole.pixelCount()) / 2);

  // Another frame index draws another noise field too.
  settings.noise_seed = 5;
  settings.frame_index = 4;
  renderRows(scene, rays, T_world_cam, settings, other.view(), 0, cam.height);
  CHECK(!std::equal(whole.data(), whole.data() + whole.pixelCount(), other.data()));
}

TEST_CASE("footprint-filtered texture matches a brute-force box filter") {
  TextureParams params;
  params.seed = 9;
  params.rect_cell_m = 0.8f;
  params.rect_small_cell_m = 0.15f;
  params.blob_cell_m = 0.3f;
  params.text_block_m = 0.006f;
  params.text_line_cell_m = 0.5f;
  params.text_density = 0.8f;
  const ProceduralTexture texture(params);
  // Compare the filtered sample with the mean of 32x32 fine samples over the footprint square, at
  // footprints from one text block to a fraction of the rectangle cells.
  for (const float footprint : {0.004f, 0.01f, 0.03f}) {
    double err2 = 0.0, var = 0.0;
    const int n = 150;
    for (int i = 0; i < n; ++i) {
      const float u = 0.37f * static_cast<float>(i) + 0.011f;
      const float v = 0.23f * static_cast<float>(i % 17) + 0.5f;
      double mean = 0.0;
      constexpr int kFine = 32;
      for (int a = 0; a < kFine; ++a) {
        for (int b = 0; b < kFine; ++b) {
          mean += texture.sample(u + footprint * ((a + 0.5f) / kFine - 0.5f),
                                 v + footprint * ((b + 0.5f) / kFine - 0.5f), footprint / kFine);
        }
      }
      mean /= kFine * kFine;
      const double filtered = texture.sample(u, v, footprint);
      err2 += (filtered - mean) * (filtered - mean);
      const double point = texture.sample(u, v, footprint / kFine);
      var += (point - mean) * (point - mean);
    }
    const double rms = std::sqrt(err2 / n);
    const double point_rms = std::sqrt(var / n);
    INFO("footprint " << footprint << " filtered rms " << rms << " unfiltered rms " << point_rms);
    // The filter is deliberately a stronger low-pass than a box (octaves fade out between 4 and 2
    // footprints per wavelength, where a box would still pass 64-90 % and alias), so it does not
    // equal the box mean; it must still be clearly closer to it than an unfiltered point sample,
    // whose error is the detail that would alias, and within a few percent of the albedo range.
    CHECK(rms < 0.7 * point_rms);
    CHECK(rms < 0.08);
  }
}

TEST_CASE("motion presets stay in the room and produce the advertised image motion") {
  const voca::StereoRig rig = eurocRig();
  const RoomBox room;
  const double clearance = 0.75;  // 0.5 m required + margin for the rig's lever arms (~0.11 m)
  const voca::CameraCalibration& cam0 = rig.cameras[0];
  const RayTable rays = makeRayTable(cam0);
  for (const MotionPreset preset : {MotionPreset::kGentle, MotionPreset::kFastRotation, MotionPreset::kAggressive}) {
    INFO("preset " << motionPresetName(preset));
    CHECK(parseMotionPreset(motionPresetName(preset)) == preset);
    std::vector<SE3d> poses;
    std::vector<Eigen::Vector3d> path;
    double max_speed = 0.0, max_accel = 0.0;
    const double dt = 0.05;
    for (int k = 0; k < 1200; ++k) {  // 60 s at 20 Hz
      const double t = k * dt;
      const SE3d T_world_cam0 = presetCameraPose(preset, t, room, clearance);
      poses.push_back(T_world_cam0);
      const SE3d T_world_body = T_world_cam0 * cam0.T_body_cam.inverse();
      for (const voca::CameraCalibration& c : rig.cameras) {
        CHECK(room.clearance((T_world_body * c.T_body_cam).translation()) >= 0.5);
      }
      CHECK(room.clearance(T_world_body.translation()) >= 0.5);
      path.push_back(T_world_cam0.translation());
      // Smoothness: central differences of the position at a fine step stay bounded.
      const double h = 1e-3;
      const Eigen::Vector3d p0 = presetCameraPose(preset, t - h, room, clearance).translation();
      const Eigen::Vector3d p1 = T_world_cam0.translation();
      const Eigen::Vector3d p2 = presetCameraPose(preset, t + h, room, clearance).translation();
      max_speed = std::max(max_speed, (p2 - p0).norm() / (2 * h));
      max_accel = std::max(max_accel, (p2 - 2 * p1 + p0).norm() / (h * h));
    }
    // Realistic speeds: walking pace for handheld, ~3 m/s for a drone; accelerations a few m/s^2
    // (a discontinuity would show as ~1/h^2 = 1e6 here).
    CHECK(max_speed < (preset == MotionPreset::kAggressive ? 4.0 : 1.0));
    CHECK(max_accel < 20.0);

    // Objects are placed clear of the path.
    const Scene scene = Scene::generate(SceneConfig(), path, 4);
    CHECK(scene.boxes().size() >= 8);
    for (const BoxObject& box : scene.boxes()) {
      for (const Eigen::Vector3d& p : path) {
        const Eigen::Vector3d local = p - box.center.cast<double>();
        CHECK_MESSAGE(local.cwiseAbs().maxCoeff() > 0.3, "camera inside a box");
      }
    }

    const Project into_image = [&cam0](const Eigen::Vector3d& p, Eigen::Vector2d& uv) {
      return cam0.camera.project(p, uv) && uv.x() >= 0 && uv.y() >= 0 && uv.x() < cam0.width && uv.y() < cam0.height;
    };
    const std::vector<SE3d> first(poses.begin(), poses.begin() + 100);
    const ImageMotionStats flow = measureImageMotion(scene, rays, into_image, first, 48);
    INFO("median " << flow.median_px << " p90 " << flow.p90_px << " max " << flow.max_px);
    switch (preset) {
      case MotionPreset::kGentle:
        CHECK(flow.median_px > 1.0);
        CHECK(flow.median_px < 10.0);
        break;
      case MotionPreset::kFastRotation:  // "tens of px per frame at 20 Hz"
        CHECK(flow.median_px > 15.0);
        CHECK(flow.p90_px < 80.0);
        break;
      case MotionPreset::kAggressive:
        CHECK(flow.median_px > 8.0);
        CHECK(flow.p90_px < 80.0);
        break;
    }
    CHECK(flow.samples > 0);
    // A jump far out of the room between two poses: no point stays in view, and the stats say so
    // instead of reading as a standstill.
    const SE3d far_away(poses[0].so3(), poses[0].translation() + Eigen::Vector3d(500.0, 0.0, 0.0));
    const std::vector<SE3d> jump = {poses[0], far_away};
    const ImageMotionStats lost = measureImageMotion(scene, rays, into_image, jump, 48);
    CHECK(lost.samples == 0);
  }
}

TEST_CASE("a recorded trajectory is placed inside a room that fits it") {
  std::vector<Eigen::Vector3d> positions;
  for (int k = 0; k < 100; ++k) positions.emplace_back(100.0 + 0.12 * k, -50.0 + 0.02 * k, 7.0 + 0.01 * k);
  const RoomPlacement placement = placeInRoom(positions, RoomBox(), 0.6);
  for (const Eigen::Vector3d& p : positions) CHECK(placement.room.clearance(p + placement.offset) >= 0.6 - 1e-9);
  // 11.9 m of travel along x does not fit the default 9 m room: it grows to 11.9 + 2 x 0.6.
  CHECK(placement.room.max.x() - placement.room.min.x() == doctest::Approx(11.88 + 1.2));
  CHECK(placement.room.min.z() == doctest::Approx(0.0));
}

TEST_CASE("motion blur averages the images along the shutter's poses; gain scales the signal") {
  const voca::CameraCalibration cam = smallPinhole(96, 64);
  const RayTable rays = makeRayTable(cam);
  const std::vector<Eigen::Vector3d> no_keep_out;
  const Scene scene = Scene::generate(SceneConfig(), no_keep_out, 11);
  RenderSettings settings;
  settings.noise_sigma = 0.0f;  // exact comparisons: no noise

  // A camera panning while the shutter is open: each pose alone, then all together.
  std::vector<SE3d> poses;
  for (int i = 0; i < 4; ++i) poses.push_back(levelCamera(Eigen::Vector3d(-0.5, 0.5, 1.2), -0.3 + 0.02 * i));
  std::vector<voca::GrayImage> single(poses.size(), voca::GrayImage(cam.width, cam.height, 0));
  for (std::size_t i = 0; i < poses.size(); ++i) {
    renderRows(scene, rays, poses[i], settings, single[i].view(), 0, cam.height);
  }
  voca::GrayImage blurred(cam.width, cam.height, 0);
  renderRows(scene, rays, poses, settings, blurred.view(), 0, cam.height);

  // The blurred image is the mean of the sharp ones, up to each one's 8-bit rounding.
  double max_error = 0.0;
  int differs_from_first = 0;
  for (std::size_t p = 0; p < blurred.pixelCount(); ++p) {
    double mean = 0.0;
    for (const voca::GrayImage& image : single) mean += image.data()[p];
    mean /= static_cast<double>(single.size());
    max_error = std::max(max_error, std::abs(mean - blurred.data()[p]));
    differs_from_first += std::abs(static_cast<int>(blurred.data()[p]) - single[0].data()[p]) > 2;
  }
  CHECK(max_error <= 1.0);
  CHECK(differs_from_first > static_cast<int>(blurred.pixelCount()) / 10);  // the pan really smears the image

  // One pose in the span is the sharp render, byte for byte.
  voca::GrayImage one(cam.width, cam.height, 0);
  renderRows(scene, rays, std::span<const SE3d>(poses.data(), 1), settings, one.view(), 0, cam.height);
  CHECK(std::equal(one.data(), one.data() + one.pixelCount(), single[0].data()));

  // Gain 0.25: a quarter of the signal, up to rounding.
  RenderSettings dark = settings;
  dark.gain = 0.25f;
  voca::GrayImage dim(cam.width, cam.height, 0);
  renderRows(scene, rays, poses[0], dark, dim.view(), 0, cam.height);
  double max_gain_error = 0.0;
  for (std::size_t p = 0; p < dim.pixelCount(); ++p) {
    max_gain_error = std::max(max_gain_error, std::abs(0.25 * single[0].data()[p] - dim.data()[p]));
  }
  CHECK(max_gain_error <= 0.75);
}
