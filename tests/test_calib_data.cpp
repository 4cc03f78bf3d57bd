// Every calibration file in ../shared/data loads with the right model, size and a plausible
// baseline (skipped when the shared data is absent).

#include <string>

#include "formats/calib/calibration_io.h"
#include "tests/test_support.h"
#include "voca/core/error.h"

namespace {

struct Expected {
  std::string path;  // under ../shared/data
  std::string model;
  int width, height;
  double baseline_m;
  std::string body_frame;
};

}  // namespace

TEST_CASE("every calibration in the shared data loads with a sane rig") {
  // Baselines: EuRoC's VI-sensor 0.110 m, TUM-VI 0.101 m, KITTI 379.8145 / 707.0912 = 0.537 m,
  // RealSense T265 64 mm. Files of one rig come from different calibrations (Basalt vs Kalibr),
  // which agree to ~0.2 mm; 1 mm tolerance says "this rig", 0.1 mm for the exact KITTI value.
  const Expected cases[] = {
      {"calib/euroc_ds_calib.json", "ds", 752, 480, 0.110, "imu"},
      {"calib/euroc_eucm_calib.json", "eucm", 752, 480, 0.110, "imu"},
      {"calib/tumvi_512_ds_calib.json", "ds", 512, 512, 0.101, "imu"},
      {"calib/tumvi_512_eucm_calib.json", "eucm", 512, 512, 0.101, "imu"},
      {"calib/t265_kb4_calib.json", "kb4", 848, 800, 0.0632, "imu"},
      {"calib/kalibr_euroc/kalibr_imucam_chain.yaml", "pinhole-radtan8", 752, 480, 0.110, "imu"},
      {"calib/kalibr_tumvi/kalibr_imucam_chain.yaml", "kb4", 512, 512, 0.101, "imu"},
      {"euroc_v101_micro", "pinhole-radtan8", 752, 480, 0.110, "euroc-body"},
      {"euroc_v101_micro/mav0", "pinhole-radtan8", 752, 480, 0.110, "euroc-body"},
      {"euroc_v101_micro/mav0/cam0/sensor.yaml", "pinhole-radtan8", 752, 480, 0.110, "euroc-body"},
      {"kitti06_first51/sequences/06", "pinhole", 1226, 370, 0.5372, "cam0"},
      {"kitti06_first51/sequences/06/calib.txt", "pinhole", 1226, 370, 0.5372, "cam0"},
  };
  for (const Expected& expected : cases) {
    CAPTURE(expected.path);
    const auto path = voca::test::sharedData(expected.path);
    if (!path) continue;
    const voca::StereoRig rig = voca::loadCalibration(*path);
    REQUIRE(rig.cameras.size() == 2);
    CHECK(rig.body_frame == expected.body_frame);
    for (const voca::CameraCalibration& cam : rig.cameras) {
      CHECK(cam.camera.modelName() == expected.model);
      CHECK(cam.width == expected.width);
      CHECK(cam.height == expected.height);
    }
    CHECK(std::abs(rig.baselineM() - expected.baseline_m) < (expected.model == "pinhole" ? 1e-4 : 1e-3));
    // In every rig here cam1 is to the right of cam0 along its x axis, with nearly parallel axes.
    CHECK(rig.T_cam0_cam1().translation().x() > 0.95 * rig.baselineM());
    CHECK(rig.T_cam0_cam1().so3().log().norm() < 0.05);  // < 3 degrees
  }
}

TEST_CASE("Basalt configuration files are not calibrations and say so") {
  const auto path = voca::test::sharedData("calib/euroc_config_vo.json");
  if (!path) return;
  try {
    voca::loadCalibration(*path);
    FAIL("expected an error");
  } catch (const voca::InputError& e) {
    CHECK(std::string(e.what()).find("euroc_config_vo.json: value0.T_imu_cam: missing") != std::string::npos);
  }
}
