#include <doctest/doctest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <random>

#include "formats/eval/eval_report_json.h"
#include "voca/core/error.h"
#include "voca/eval/evaluate.h"

using voca::AlignMode;
using voca::DeltaUnit;
using voca::SE3d;
using voca::SO3d;
using voca::Trajectory;

namespace {

constexpr int64_t kFrameNs = 50'000'000;  // 20 Hz

SE3d randomPose(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Matrix<double, 6, 1> xi;
  for (int k = 0; k < 6; ++k) xi[k] = scale * u(rng);
  return SE3d::exp(xi);
}

// A wandering trajectory with rotation, so alignment has something to recover.
Trajectory randomWalk(int n, uint32_t seed) {
  std::mt19937 rng(seed);
  Trajectory trajectory;
  SE3d T_world_body;
  for (int i = 0; i < n; ++i) {
    trajectory.poses.push_back({i * kFrameNs, T_world_body});
    T_world_body = T_world_body * randomPose(rng, 0.3);
  }
  return trajectory;
}

Trajectory transformed(const Trajectory& trajectory, const SE3d& T_new_old) {
  Trajectory out = trajectory;
  for (voca::TimedPose& pose : out.poses) pose.T_world_body = T_new_old * pose.T_world_body;
  return out;
}

// Moves along the body x axis by step_m per frame and turns by yaw_rad about z after each step.
Trajectory drivingStraight(int n, double step_m, double yaw_rad) {
  Trajectory trajectory;
  SE3d T_world_body;
  const SE3d step(SO3d::exp(Eigen::Vector3d(0, 0, yaw_rad)), Eigen::Vector3d(step_m, 0, 0));
  for (int i = 0; i < n; ++i) {
    trajectory.poses.push_back({i * kFrameNs, T_world_body});
    T_world_body = T_world_body * step;
  }
  return trajectory;
}

}  // namespace

TEST_CASE("error statistics match numpy's definitions") {
  const std::vector<double> errors = {4.0, 1.0, 3.0, 2.0};
  const voca::ErrorStats s = voca::errorStatistics(errors);
  CHECK(s.count == 4);
  CHECK(s.sse == 30.0);
  CHECK(s.rmse == doctest::Approx(std::sqrt(7.5)).epsilon(1e-15));
  CHECK(s.mean == 2.5);
  CHECK(s.median == 2.5);                                           // even count: mean of the middle two
  CHECK(s.std == doctest::Approx(std::sqrt(1.25)).epsilon(1e-15));  // population deviation (ddof 0)
  CHECK(s.min == 1.0);
  CHECK(s.max == 4.0);
  CHECK(voca::errorStatistics(std::vector<double>{3.0, 1.0, 2.0}).median == 2.0);
  CHECK(voca::errorStatistics(std::vector<double>{}).count == 0);
}

TEST_CASE("Umeyama recovers a random rigid and similarity transform exactly") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Eigen::Vector3d> p_est, p_gt, p_gt_scaled;
    const SE3d T_gt_est = randomPose(rng, 3.0);
    const double scale = 0.2 + 0.1 * trial;
    for (int i = 0; i < 30; ++i) {
      p_est.emplace_back(u(rng), u(rng), u(rng));
      p_gt.push_back(T_gt_est * p_est.back());
      p_gt_scaled.push_back(scale * (T_gt_est.so3() * p_est.back()) + T_gt_est.translation());
    }
    // Exact data: the closed form is exact up to rounding of sums over 30 points of size ~10.
    const voca::Alignment rigid = voca::umeyamaAlignment(p_est, p_gt, false);
    CHECK((rigid.T_gt_est.matrix() - T_gt_est.matrix()).norm() < 1e-12);
    CHECK(rigid.scale == 1.0);
    const voca::Alignment similarity = voca::umeyamaAlignment(p_est, p_gt_scaled, true);
    CHECK((similarity.T_gt_est.matrix() - T_gt_est.matrix()).norm() < 1e-12);
    CHECK(std::abs(similarity.scale - scale) < 1e-12);
  }
  CHECK_THROWS_AS(voca::umeyamaAlignment(std::vector<Eigen::Vector3d>(2), std::vector<Eigen::Vector3d>(2), false),
                  voca::InputError);
}

TEST_CASE("ATE: a rigidly moved copy is 0 after alignment, a constant offset is its length without") {
  const Trajectory gt = randomWalk(200, 5);
  std::mt19937 rng(9);
  const SE3d T_other_world = randomPose(rng, 2.0);
  const voca::EvalReport aligned = voca::evaluateTrajectory(transformed(gt, T_other_world), gt);
  CHECK(aligned.association.size() == 200);
  // Rounding only: positions are O(10) m.
  CHECK(aligned.ate.stats.rmse < 1e-12);
  CHECK(aligned.ate.stats.max < 1e-12);
  // RTE does not see a change of world frame at all.
  REQUIRE(aligned.rte.has_value());
  CHECK(aligned.rte->stats.max < 1e-12);
  CHECK((aligned.ate.alignment.T_gt_est.matrix() - T_other_world.inverse().matrix()).norm() < 1e-12);

  const Eigen::Vector3d offset(0.3, -0.4, 1.2);  // length 1.3
  const Trajectory shifted = transformed(gt, SE3d(SO3d::identity(), offset));
  voca::EvalOptions options;
  options.align = AlignMode::kNone;
  const voca::EvalReport unaligned = voca::evaluateTrajectory(shifted, gt, options);
  CHECK(unaligned.ate.stats.rmse == doctest::Approx(1.3).epsilon(1e-12));
  CHECK(unaligned.ate.stats.min == doctest::Approx(1.3).epsilon(1e-12));
  CHECK(unaligned.ate.stats.std < 1e-12);
  CHECK(voca::evaluateTrajectory(shifted, gt).ate.stats.rmse < 1e-12);

  // Sim(3) alignment also undoes a scale; SE(3) cannot.
  Trajectory scaled = gt;
  for (voca::TimedPose& pose : scaled.poses) pose.T_world_body.translation() *= 0.5;
  options.align = AlignMode::kSim3;
  const voca::EvalReport sim3 = voca::evaluateTrajectory(scaled, gt, options);
  CHECK(sim3.ate.stats.rmse < 1e-12);
  CHECK(sim3.ate.alignment.scale == doctest::Approx(2.0).epsilon(1e-12));
  CHECK(voca::evaluateTrajectory(scaled, gt).ate.stats.rmse > 0.1);
}

TEST_CASE("RTE of a known per-step drift, computed by hand") {
  // Ground truth drives straight, 1 m per frame. The estimate also moves 1 m per frame but turns
  // by eps after each step. Over 6 frames the estimate's relative motion is
  // (sum_k cos(k eps), sum_k sin(k eps)), k = 0..5, with a yaw of 6 eps; the ground truth's is
  // (6, 0) without rotation, so the error translation is their difference for every pair.
  const double eps = 0.01;
  const Trajectory gt = drivingStraight(61, 1.0, 0.0);
  const Trajectory est = drivingStraight(61, 1.0, eps);
  // Closed-form sums: sum_{k=0}^{5} cos(k e) = sin(3e) cos(2.5e) / sin(e/2), sin likewise.
  const double sum_cos = std::sin(3 * eps) * std::cos(2.5 * eps) / std::sin(eps / 2);
  const double sum_sin = std::sin(3 * eps) * std::sin(2.5 * eps) / std::sin(eps / 2);
  const double expected = std::hypot(sum_cos - 6.0, sum_sin);

  const voca::EvalReport report = voca::evaluateTrajectory(est, gt);
  REQUIRE(report.rte.has_value());
  // 61 poses: pairs (0,6), (6,12), ..., (54,60).
  CHECK(report.rte->stats.count == 10);
  CHECK(report.rte->pairs.front() == std::pair<std::size_t, std::size_t>(0, 6));
  CHECK(report.rte->pairs.back() == std::pair<std::size_t, std::size_t>(54, 60));
  // Composition of 60 poses accumulates rounding ~1e-14.
  CHECK(report.rte->stats.min == doctest::Approx(expected).epsilon(1e-10));
  CHECK(report.rte->stats.max == doctest::Approx(expected).epsilon(1e-10));
  CHECK(report.rte->stats.rmse == doctest::Approx(expected).epsilon(1e-10));

  // A pure scale drift: 1.01 m per 1 m step gives 0.06 m over 6 frames.
  const voca::EvalReport scale_drift = voca::evaluateTrajectory(drivingStraight(61, 1.01, 0.0), gt);
  CHECK(scale_drift.rte->stats.rmse == doctest::Approx(0.06).epsilon(1e-12));
}

TEST_CASE("RTE pairs by travelled distance follow evo's consecutive path filter") {
  std::vector<Eigen::Vector3d> positions;
  for (int i = 0; i < 11; ++i) positions.emplace_back(i, 0, 0);
  // The path restarts at each selected pose, which is reached when >= delta: poses 3, 6, 9.
  const auto pairs = voca::relativePosePairs(positions, 2.5, DeltaUnit::kMeters);
  REQUIRE(pairs.size() == 2);
  CHECK(pairs[0] == std::pair<std::size_t, std::size_t>(3, 6));
  CHECK(pairs[1] == std::pair<std::size_t, std::size_t>(6, 9));
  CHECK(voca::relativePosePairs(positions, 4, DeltaUnit::kFrames).size() == 2);  // (0,4), (4,8)
  CHECK_THROWS_AS(voca::relativePosePairs(positions, 1.5, DeltaUnit::kFrames), voca::InputError);
}

TEST_CASE("association follows evo: nearest within max_diff, from the shorter trajectory") {
  const auto at = [](std::initializer_list<double> seconds) {
    Trajectory t;
    for (const double s : seconds) t.poses.push_back({static_cast<int64_t>(std::llround(s * 1e9)), SE3d()});
    return t;
  };
  // Estimate shorter: each of its poses looks for the nearest ground truth.
  const voca::PoseAssociation a = voca::associateTrajectories(at({0.0, 0.1, 0.2}), at({0.005, 0.095, 0.3, 0.4}));
  CHECK(a.est_index == std::vector<std::size_t>{0, 1});
  CHECK(a.gt_index == std::vector<std::size_t>{0, 1});
  CHECK(a.max_abs_dt_s == doctest::Approx(0.005).epsilon(1e-9));

  // Ground truth shorter: pairs come in ground-truth order; an exact tie takes the earlier pose.
  const voca::PoseAssociation b = voca::associateTrajectories(at({0.0, 0.01, 0.02, 0.03}), at({0.005, 0.03}));
  CHECK(b.gt_index == std::vector<std::size_t>{0, 1});
  CHECK(b.est_index == std::vector<std::size_t>{0, 3});

  // Not one-to-one on the longer side, as in evo: two estimates may share a ground-truth pose.
  const voca::PoseAssociation c = voca::associateTrajectories(at({1.0, 1.002}), at({1.001, 5.0, 6.0}));
  CHECK(c.gt_index == std::vector<std::size_t>{0, 0});
  CHECK(c.reused_poses == 1);

  CHECK_THROWS_AS(voca::associateTrajectories(at({0.0, 1.0}), at({0.5})), voca::InputError);

  // KITTI without timestamps pairs by index, only with equal counts and only with each other.
  Trajectory k1 = at({0, 1, 2}), k2 = at({0, 1, 2}), k3 = at({0, 1});
  k1.has_timestamps = k2.has_timestamps = k3.has_timestamps = false;
  CHECK(voca::associateTrajectories(k1, k2).by_index);
  CHECK_THROWS_AS(voca::associateTrajectories(k1, k3), voca::InputError);
  CHECK_THROWS_AS(voca::associateTrajectories(k1, at({0, 1, 2})), voca::InputError);
}

TEST_CASE("divergence and reset verdicts follow the paper's thresholds") {
  const Trajectory gt = drivingStraight(61, 1.0, 0.0);
  const Trajectory est = drivingStraight(61, 1.02, 0.0);  // RTE 0.12 m per 6 frames: above 0.10
  voca::EvalOptions options;
  const voca::EvalReport report = voca::evaluateTrajectory(est, gt, options);
  CHECK(report.rte_divergent);
  CHECK(report.rte_verdict == voca::EvalVerdict::kDivergent);
  CHECK_FALSE(report.ate_divergent);  // the 1.2 m scale error leaves an ATE well below 10 m
  CHECK(report.ate_verdict == voca::EvalVerdict::kOk);

  options.ate_divergence_m = 0.1;
  CHECK(voca::evaluateTrajectory(est, gt, options).ate_divergent);

  options.expected_frames = 123;  // 61 of 123 frames estimated: less than half
  const voca::EvalReport reset = voca::evaluateTrajectory(est, gt, options);
  CHECK(reset.ate_verdict == voca::EvalVerdict::kReset);
  CHECK(reset.rte_verdict == voca::EvalVerdict::kReset);
  CHECK(*reset.coverage == 61.0 / 123.0);  // the same one division: exact
  options.expected_frames = 122;  // exactly half is not "more than half missing"
  CHECK(voca::evaluateTrajectory(est, gt, options).ate_verdict == voca::EvalVerdict::kDivergent);

  const nlohmann::json j = voca::evalReportToJson(reset, options);
  CHECK(j["rte"]["verdict"] == "R");
  CHECK(j["rte"]["count"] == 10);
  CHECK(j["ate"]["alignment"] == "se3");
  CHECK(j["association"]["pairs"] == 61);
  CHECK(j["association"]["method"] == "timestamp");
}
