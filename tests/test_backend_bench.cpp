// `voca bench backend`'s timing: the estimator run several times over the same observations, every
// run repeating the first one's estimates, and each frame's time the median of its runs.

#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include "pipeline/bench/backend_bench.h"
#include "pipeline/bench/per_frame_median.h"
#include "voca/backend/synthetic.h"
#include "voca/core/error.h"
#include "voca/synth/rigs.h"

namespace {

voca::SyntheticObservations shortSequence(const voca::StereoRig& rig) {
  voca::SyntheticObservationsConfig sc;
  sc.duration_s = 3.0;
  sc.noise_px = 0.5;
  return voca::makeSyntheticObservations(rig, sc);
}

}  // namespace

TEST_CASE("backend bench: each frame's time is the median of its runs") {
  using voca::pipeline::perFrameMedian;
  // Frame 0 is slow in one run, frame 1 in another: the median keeps neither disturbance.
  const std::vector<double> medians = perFrameMedian({{9.0, 2.0, 3.0}, {1.0, 8.0, 3.5}, {1.5, 2.5, 4.0}});
  REQUIRE(medians.size() == 3);
  CHECK(medians[0] == 1.5);
  CHECK(medians[1] == 2.5);
  CHECK(medians[2] == 3.5);
  // Two runs: the mean of the middle two, as for any even count.
  CHECK(perFrameMedian({{1.0}, {2.0}})[0] == 1.5);
  CHECK_THROWS_AS(perFrameMedian({}), voca::InputError);
  CHECK_THROWS_AS(perFrameMedian({{1.0, 2.0}, {1.0}}), voca::InputError);
}

TEST_CASE("backend bench: three runs time the same work as one and report each run's median") {
  const auto rig = voca::synth::builtinRig("euroc");
  REQUIRE(rig);
  const voca::SyntheticObservations seq = shortSequence(*rig);
  const voca::BackendConfig config;
  constexpr std::size_t kWarmup = 20;
  REQUIRE(seq.frames.size() > kWarmup + 20);
  const voca::pipeline::EstimatorTiming once = voca::pipeline::timeEstimator(seq.frames, *rig, config, kWarmup);
  const voca::pipeline::EstimatorTiming thrice = voca::pipeline::timeEstimator(seq.frames, *rig, config, kWarmup, 3);

  const std::size_t measured = seq.frames.size() - kWarmup;
  CHECK(once.run_median_ms.size() == 1);
  REQUIRE(thrice.run_median_ms.size() == 3);
  CHECK(thrice.measured == static_cast<int>(measured));
  REQUIRE(thrice.cpu_ms.size() == measured);
  for (const double ms : thrice.cpu_ms) CHECK((std::isfinite(ms) && ms > 0.0));
  for (const double ms : thrice.run_median_ms) CHECK((std::isfinite(ms) && ms > 0.0));
  // The estimator is deterministic: the same iterations, keyframes and inliers however often it runs.
  CHECK(thrice.keyframes == once.keyframes);
  CHECK(thrice.keyframes > 0);
  CHECK(thrice.resets == once.resets);
  CHECK(thrice.mean_lm_iterations == once.mean_lm_iterations);
  CHECK(thrice.mean_linearizations == once.mean_linearizations);
  CHECK(thrice.mean_cost_passes == once.mean_cost_passes);
  CHECK(thrice.mean_cost_passes > 0.0);  // every frame that converges judges its last step by one
  CHECK(thrice.mean_inliers == once.mean_inliers);

  CHECK_THROWS_AS(voca::pipeline::timeEstimator(seq.frames, *rig, config, kWarmup, 0), voca::InputError);
}
