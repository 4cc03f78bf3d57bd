// Proves the backend's fixed-memory rule: after warm-up, process() never touches the heap, through
// keyframes, marginalisation, outlier removal and a reset. This executable replaces the global
// operator new/delete with the counting versions of test_alloc_counter.h.

#include <doctest/doctest.h>

#include "tests/test_alloc_counter.h"
#include "voca/backend/estimator.h"
#include "voca/backend/synthetic.h"
#include "voca/synth/rigs.h"

using namespace voca;

TEST_CASE("backend: no heap allocation in process() after warm-up, including marginalisation and a reset") {
  const StereoRig rig = synth::eurocRig();
  SyntheticObservationsConfig sc;
  sc.noise_px = 0.5;
  sc.duration_s = 8.0;    // short enough to run under qemu in the ARM cross stage too
  sc.motion_scale = 3.0;  // more keyframes and marginalisations per second
  SyntheticObservations seq = makeSyntheticObservations(rig, sc);
  seq.frames[90].observations[1].clear();  // a frame that cannot be tracked: forces a reset
  std::uint32_t state = 12345;             // scrambled left points (a decoder glitch)
  for (KeypointObservation& o : seq.frames[90].observations[0]) {
    state = state * 1664525u + 1013904223u;
    const float x = 20.f + static_cast<float>(state % 700u);
    state = state * 1664525u + 1013904223u;
    o.px = Eigen::Vector2f(x, 20.f + static_cast<float>(state % 440u));
  }

  VoEstimator estimator({}, rig);
  for (std::size_t k = 0; k < 20; ++k) estimator.process(seq.frames[k]);
  const long before = voca::test::g_allocations.load();
  int keyframes = 0, resets = 0, tracked = 0;
  for (std::size_t k = 20; k < seq.frames.size(); ++k) {
    const PoseEstimate& e = estimator.process(seq.frames[k]);
    keyframes += e.keyframe;
    resets += e.state != TrackingState::kTracking;
    tracked += e.state == TrackingState::kTracking;
  }
  const long allocations = voca::test::g_allocations.load() - before;
  MESSAGE((seq.frames.size() - 20) << " frames, " << keyframes << " keyframes, " << resets << " reset/lost frames");
  // The counter is live (building the sequence and the estimator allocated), so zero below is a measurement.
  CHECK(before > 0);
  CHECK(keyframes > 2 * estimator.config().max_keyframes);  // marginalisation ran many times
  CHECK(resets >= 1);
  CHECK(tracked > 100);
  CHECK(allocations == 0);
}
