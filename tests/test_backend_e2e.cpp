// End-to-end VO runs through the pipeline runner (the sequences rendered and encoded with the `voca`
// binary), checked against ground truth with the paper's metrics: rendered sequences (raw and
// 500 kbit/s), micro EuRoC (real images, 500 kbit/s) and the first 51 frames of KITTI 06 (real moving
// stereo).

#include <doctest/doctest.h>

#include <cstdlib>
#include <fstream>
#include <string>

#include "formats/trajectory/trajectory_io.h"
#include "pipeline/vo/vo_runner.h"
#include "tests/test_support.h"
#include "voca/eval/evaluate.h"

using namespace voca;

namespace {

std::string voca() { return std::string(VOCA_BINARY_DIR) + "/bin/voca"; }

// Runs a voca command line; its output goes to a log file in the scratch folder, shown on failure.
bool run(const std::string& args, const std::filesystem::path& log) {
  const std::string command = voca() + " " + args + " > " + log.string() + " 2>&1";
  const int code = std::system(command.c_str());
  if (code != 0) {
    std::ifstream in(log);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    MESSAGE("command failed: " << command << "\n" << text);
  }
  return code == 0;
}

// The VO on a dataset or video folder through the runner, the trajectory written to `trajectory`.
pipeline::VoRunResult runVo(const std::string& input, const std::filesystem::path& trajectory,
                            std::optional<PriorMode> mode = {}, std::int64_t encode_bps = 0,
                            std::optional<std::filesystem::path> config = {}) {
  pipeline::VoRunOptions options;
  options.input = input;
  options.trajectory_file = trajectory;
  options.mode = mode;
  options.encode_bitrate_bps = encode_bps;
  options.config = config;
  options.progress = false;
  pipeline::VoRunResult result = pipeline::runVisualOdometry(options);
  REQUIRE_FALSE(result.pipeline_report.error);
  return result;
}

EvalReport evaluate(const std::filesystem::path& est, const Trajectory& gt) {
  return evaluateTrajectory(loadTrajectory(est), gt);
}

}  // namespace

TEST_CASE("backend e2e: rendered fast-rotation sequence, raw and at 500 kbit/s, tracks without resets") {
  test::ScratchDir dir("backend-e2e-synth");
  const auto raw = dir / "synth";
  REQUIRE(
      run("synth --out " + raw.string() + " --motion fast-rotation --seconds 5 --supersample 1", dir / "synth.log"));
  REQUIRE(run("encode " + raw.string() + " --out " + (dir / "video").string() + " --bitrate 500k", dir / "encode.log"));
  const Trajectory gt = loadTrajectory(raw / "mav0" / "state_groundtruth_estimate0" / "data.csv");

  struct Case {
    std::string name, input;
    PriorMode mode;
    double max_ate_m, max_rte_m;
  };
  // Bounds: these runs measured ATE 3-4 mm and RTE 2-5 mm (100 frames, ~20 px/frame image motion,
  // exact ground truth); the bounds leave a factor 3-5 for platform and codec differences while a
  // broken estimator (wrong frame, drift, resets) gives centimetres to metres.
  const Case cases[] = {
      {"raw", raw.string(), PriorMode::kNone, 0.015, 0.010},
      {"500k-none", (dir / "video").string(), PriorMode::kNone, 0.03, 0.015},
      {"500k-mv_parallel_of", (dir / "video").string(), PriorMode::kMvParallelOf, 0.03, 0.015},
  };
  for (const Case& c : cases) {
    const auto traj = dir / (c.name + ".txt");
    const pipeline::VoRunResult result = runVo(c.input, traj, c.mode);
    CHECK(result.backend.resets == 0);
    CHECK(result.backend.lost == 0);
    const EvalReport report = evaluate(traj, gt);
    REQUIRE(report.rte);
    MESSAGE(c.name << ": ATE " << report.ate.stats.rmse << " m, RTE " << report.rte->stats.rmse << " m over "
                   << report.ate.stats.count << " poses");
    CHECK(report.ate.stats.count == 100);
    CHECK(report.ate.stats.rmse < c.max_ate_m);
    CHECK(report.rte->stats.rmse < c.max_rte_m);
  }
}

TEST_CASE("backend e2e: micro EuRoC at 500 kbit/s completes without reset, RTE below 2 cm") {
  const auto data = test::sharedData("euroc_v101_micro");
  if (!data) return;
  test::ScratchDir dir("backend-e2e-euroc");
  const auto traj = dir / "traj.txt";
  const auto gt_file = *data / "gt" / "V1_01_easy_openvins_vicon2gt.csv";
  const pipeline::VoRunResult result = runVo(data->string(), traj, {}, 500000);
  CHECK(result.backend.resets == 0);
  CHECK(result.backend.lost == 0);
  const EvalReport report = evaluate(traj, loadTrajectory(gt_file));
  REQUIRE(report.rte);
  MESSAGE("micro EuRoC 500k: ATE " << report.ate.stats.rmse << " m, RTE " << report.rte->stats.rmse << " m");
  // The issue's bound. The drone is still on the ground here, so the estimate must stay put (~1 mm measured).
  CHECK(report.rte->stats.rmse < 0.02);
}

TEST_CASE("backend e2e: KITTI 06, first 51 frames, ATE at Basalt's level (0.12 m) or better") {
  const auto data = test::sharedData("kitti06_first51/sequences/06");
  if (!data) return;
  test::ScratchDir dir("backend-e2e-kitti");
  // The shipped EuRoC config guesses right-image matches at 2 m depth, which on KITTI's 0.54 m
  // baseline is 190 px of disparity: no stereo point would be found. 15 m suits street scenes; and
  // the long forward tracks keep their landmarks when a keyframe is marginalised, as the kitti file does.
  const auto config = dir / "kitti.json";
  std::ofstream(config) << R"({"frontend": {"matching_default_depth_m": 15.0}, "backend": {"rehost_landmarks": true}})";
  const auto traj = dir / "traj.txt";
  const pipeline::VoRunResult result = runVo(data->string(), traj, {}, 0, config);
  CHECK(result.backend.resets == 0);
  CHECK(result.backend.lost == 0);
  // Ground truth is the left camera's pose; with a KITTI calibration the body frame is cam0.
  const Trajectory gt =
      loadTrajectory(*data / ".." / ".." / "poses" / "06.txt", TrajectoryFormat::kKitti, *data / "times.txt");
  const EvalReport report = evaluate(traj, gt);
  REQUIRE(report.rte);
  MESSAGE("KITTI 06 first 51 frames: ATE " << report.ate.stats.rmse << " m, RTE " << report.rte->stats.rmse << " m");
  CHECK(report.ate.stats.count == 51);
  // Basalt's VO reaches ~0.12 m here (DESIGN.md); measured 0.113 m. The bound allows 0.125 m so that
  // frontend changes of a few tracks do not flip it, while anything clearly worse than Basalt fails.
  CHECK(report.ate.stats.rmse < 0.125);
}

TEST_CASE("backend e2e: --encode keeps the recording's ground truth; a KITTI --gt file takes the sequence's times") {
  const auto data = test::sharedData("kitti06_first51/sequences/06");
  if (!data) return;
  test::ScratchDir dir("backend-e2e-kitti-gt");
  for (const bool explicit_gt : {false, true}) {
    pipeline::VoRunOptions options;
    options.input = *data;
    options.trajectory_file = dir / "traj.txt";
    options.encode_bitrate_bps = 500000;
    options.max_frames = 12;
    options.progress = false;
    if (explicit_gt) options.ground_truth = *data / ".." / ".." / "poses" / "06.txt";
    const pipeline::VoRunResult result = pipeline::runVisualOdometry(options);
    REQUIRE_FALSE(result.pipeline_report.error);
    INFO("explicit --gt: " << explicit_gt);
    // Before, the temporary encoding had no ground truth and a KITTI poses file given with --gt had
    // no timestamps to associate: either way no ATE.
    REQUIRE(result.eval);
    CHECK(result.eval->ate.stats.count == 12);
    CHECK(result.eval->ate.stats.rmse < 0.2);
  }
}
