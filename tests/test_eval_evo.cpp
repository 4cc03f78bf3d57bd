#include <doctest/doctest.h>

#include <cmath>
#include <iomanip>

#include "formats/calib/calibration_io.h"
#include "formats/trajectory/trajectory_io.h"
#include "tests/test_support.h"
#include "voca/eval/evaluate.h"

// Parity with evo on its own test data (../shared/data/evo_reference, values in its SOURCE.txt).

namespace {

struct Expected {
  double rmse, mean, median, std, min, max;
};

// evo's result files store full doubles and we compute the same formulas on the same numbers
// (KITTI rows as read, not re-orthonormalised), so only summation order and the SVD differ: far
// below 1e-6 relative. Re-orthonormalising the rounded KITTI rotations alone moves RPE by ~5e-6.
void checkRelative(const voca::ErrorStats& got, const Expected& want, double tolerance) {
  const auto close = [tolerance](double a, double b) { return std::abs(a - b) <= tolerance * std::abs(b); };
  MESSAGE("relative differences: rmse " << (got.rmse - want.rmse) / want.rmse << ", mean "
                                        << (got.mean - want.mean) / want.mean << ", median "
                                        << (got.median - want.median) / want.median << ", std "
                                        << (got.std - want.std) / want.std << ", min "
                                        << (got.min - want.min) / want.min << ", max "
                                        << (got.max - want.max) / want.max);
  CHECK_MESSAGE(close(got.rmse, want.rmse), "rmse " << got.rmse << " vs " << want.rmse);
  CHECK_MESSAGE(close(got.mean, want.mean), "mean " << got.mean << " vs " << want.mean);
  CHECK_MESSAGE(close(got.median, want.median), "median " << got.median << " vs " << want.median);
  CHECK_MESSAGE(close(got.std, want.std), "std " << got.std << " vs " << want.std);
  CHECK_MESSAGE(close(got.min, want.min), "min " << got.min << " vs " << want.min);
  CHECK_MESSAGE(close(got.max, want.max), "max " << got.max << " vs " << want.max);
}

void checkKitti(const std::string& estimate_name, const Expected& ape, const Expected& rpe) {
  const auto dir = voca::test::sharedData("evo_reference");
  if (!dir) return;
  // evo reads KITTI files without timestamps and pairs the poses by index.
  const voca::Trajectory gt = voca::loadTrajectory(*dir / "KITTI_00_gt.txt");
  const voca::Trajectory est = voca::loadTrajectory(*dir / estimate_name);
  REQUIRE(gt.poses.size() == 4541);

  voca::EvalOptions options;
  options.rte_delta = 10.0;
  options.rte_delta_unit = voca::DeltaUnit::kMeters;
  const voca::EvalReport report = voca::evaluateTrajectory(est, gt, options);
  CHECK(report.association.by_index);
  CHECK(report.ate.stats.count == 4541);
  checkRelative(report.ate.stats, ape, 1e-6);
  REQUIRE(report.rte.has_value());
  checkRelative(report.rte->stats, rpe, 1e-6);
}

}  // namespace

TEST_CASE("evo parity: KITTI 00 ORB-SLAM, APE (SE(3) Umeyama) and RPE (delta 10 m)") {
  checkKitti("KITTI_00_ORB.txt",
             {1.3034497145650266, 1.1569971285389768, 1.065624769555848, 0.6002822693968323, 0.06931322021483087,
              3.587949120678954},
             {0.22626134329310163, 0.16901737200653275, 0.13848432516645606, 0.1504238127053164, 0.025322719660754993,
              1.2722090778658726});
}

TEST_CASE("evo parity: KITTI 00 S-PTAM, APE (SE(3) Umeyama) and RPE (delta 10 m)") {
  checkKitti("KITTI_00_SPTAM.txt",
             {3.738487907582613, 3.4909766330848684, 3.6425846417432637, 1.3376748418045645, 0.694787347406252,
              7.7689774065713175},
             {0.27607109043606004, 0.22284797909537604, 0.1783338691210611, 0.16295405851853487, 0.01875232105572263,
              1.2065944255781629});
}

TEST_CASE("evo parity: KITTI 00 ORB sse") {
  const auto dir = voca::test::sharedData("evo_reference");
  if (!dir) return;
  const voca::EvalReport report = voca::evaluateTrajectory(voca::loadTrajectory(*dir / "KITTI_00_ORB.txt"),
                                                           voca::loadTrajectory(*dir / "KITTI_00_gt.txt"));
  CHECK(std::abs(report.ate.stats.sse - 7715.073440292808) <= 1e-6 * 7715.073440292808);
}

TEST_CASE("evo parity: EuRoC V1_02, TUM estimate vs EuRoC csv, time association") {
  const auto dir = voca::test::sharedData("evo_reference");
  if (!dir) return;
  const voca::Trajectory gt = voca::loadTrajectory(*dir / "V102_groundtruth.csv");
  const voca::Trajectory est = voca::loadTrajectory(*dir / "V102.txt");
  CHECK(gt.poses.size() == 16702);
  CHECK(est.poses.size() == 807);

  const voca::EvalReport report = voca::evaluateTrajectory(est, gt);  // the paper's defaults: se3, 6 frames
  CHECK_FALSE(report.association.by_index);
  MESSAGE("associated " << report.association.size() << " of " << est.poses.size() << " poses");
  // SOURCE.txt gives evo's values to 6 digits: agreement to half a unit of the last digit.
  const double tolerance = 5e-6;
  const voca::ErrorStats& ate = report.ate.stats;
  CHECK(std::abs(ate.rmse - 0.091727) <= tolerance);
  CHECK(std::abs(ate.mean - 0.081522) <= tolerance);
  CHECK(std::abs(ate.median - 0.077912) <= tolerance);
  CHECK(std::abs(ate.max - 0.255817) <= tolerance);
  REQUIRE(report.rte.has_value());
  const voca::ErrorStats& rte = report.rte->stats;
  CHECK(std::abs(rte.rmse - 0.041077) <= tolerance);
  CHECK(std::abs(rte.mean - 0.029747) <= tolerance);
  CHECK(std::abs(rte.median - 0.022696) <= tolerance);
  CHECK(std::abs(rte.max - 0.217894) <= tolerance);
  MESSAGE(std::setprecision(8) << "ATE rmse " << ate.rmse << " mean " << ate.mean << " median " << ate.median << " max "
                               << ate.max);
  MESSAGE(std::setprecision(8) << "RTE rmse " << rte.rmse << " mean " << rte.mean << " median " << rte.median << " max "
                               << rte.max);
}

TEST_CASE("frames: a cam0 trajectory matches body-frame ground truth only after conversion") {
  const auto calib = voca::test::sharedData("calib/euroc_ds_calib.json");
  const auto dir = voca::test::sharedData("evo_reference");
  if (!calib || !dir) return;
  const voca::SE3d T_body_cam0 = voca::loadCalibration(*calib).cameras.at(0).T_body_cam;
  REQUIRE(T_body_cam0.translation().norm() > 0.05);  // EuRoC's cam0 sits ~7 cm from the IMU

  const voca::Trajectory gt = voca::loadTrajectory(*dir / "V102_groundtruth.csv");
  const voca::Trajectory est_cam0 =
      voca::convertPoseFrame(gt, voca::PoseFrame::kBody, voca::PoseFrame::kCam0, T_body_cam0);
  // Compared as if it were a body trajectory, the lever arm and the camera's rotation show up:
  // the relative motions differ by centimetres.
  const voca::EvalReport wrong = voca::evaluateTrajectory(est_cam0, gt);
  CHECK(wrong.rte->stats.rmse > 0.01);
  const voca::EvalReport right = voca::evaluateTrajectory(
      voca::convertPoseFrame(est_cam0, voca::PoseFrame::kCam0, voca::PoseFrame::kBody, T_body_cam0), gt);
  // Only rounding remains (positions of a few metres).
  CHECK(right.ate.stats.max < 1e-12);
  CHECK(right.rte->stats.max < 1e-12);
}
