// Proves the frontend's fixed-memory rule: after the first frames, track() never touches the heap.
// This executable replaces the global operator new/delete with the counting ones of test_alloc_counter.h.

#include <doctest/doctest.h>

#include <array>

#include "tests/test_alloc_counter.h"
#include "tests/test_frontend_support.h"
#include "voca/frontend/frontend.h"

using namespace voca;

TEST_CASE("frontend: no heap allocation in track() from the third frame on, in every prior mode and option") {
  const int w = 320, h = 240;
  const StereoRig rig = voca::test::pinholeRig(w, h, 300.0, 0.11);
  const voca::test::WaveTexture texture(21);
  // Frames rendered up front (rendering allocates); content moves 6 px right and 2 px down per
  // frame so that points leave the image and cells are refilled by detection every frame.
  const int num_frames = 10;
  std::vector<GrayImage> left(num_frames), right(num_frames);
  for (int k = 0; k < num_frames; ++k) {
    texture.render(left[static_cast<std::size_t>(k)], w, h, 6.0 * k, 2.0 * k);
    texture.render(right[static_cast<std::size_t>(k)], w, h, 6.0 * k - 16.5, 2.0 * k);
  }
  // And a camera speeding up by 6 px per frame each frame, beyond the plain track's reach after a few
  // (retry_previous_flow).
  std::vector<GrayImage> fast_left(num_frames), fast_right(num_frames);
  for (int k = 0; k < num_frames; ++k) {
    const double shift = 3.0 * k * (k + 1);
    texture.render(fast_left[static_cast<std::size_t>(k)], w, h, shift, shift / 3.0);
    texture.render(fast_right[static_cast<std::size_t>(k)], w, h, shift - 16.5, shift / 3.0);
  }
  MotionField field(w, h);
  // The five modes (none with stereo_rematch), then the paper's mode with the options of our own (presmooth) and of
  // TUM-VI (right-only detection, on a 0.4 m baseline rig so that the right image has cells of its own).
  const StereoRig wide_rig = voca::test::pinholeRig(w, h, 300.0, 0.4);
  // Then a still scene with a small capacity: every track survives, the tracker is full each frame
  // and crowded tracks give way to new points (thin_when_full_px). Last, the speeding-up camera with
  // the retry from the previous image flow.
  const std::array<PriorMode, 8> modes = {PriorMode::kNone,         PriorMode::kMv,           PriorMode::kOfThenMv,
                                          PriorMode::kMvThenOf,     PriorMode::kMvParallelOf, PriorMode::kMvParallelOf,
                                          PriorMode::kMvParallelOf, PriorMode::kNone};
  for (int run = 0; run < 8; ++run) {
    const PriorMode mode = modes[static_cast<std::size_t>(run)];
    FrontendConfig config;
    config.prior_mode = mode;
    config.presmooth = run == 5 ? InputScope::kAlways : InputScope::kOff;
    config.detection_nonoverlap = run == 5;
    config.thin_when_full_px = run == 6 ? 50.0 : 0.0;
    config.retry_previous_flow = run == 7 ? InputScope::kAlways : InputScope::kOff;
    config.stereo_rematch = run == 0;
    KltFrontend frontend(config, run == 5 ? wide_rig : rig, {.max_points = run == 6 ? 30 : 300});
    TrackedStereoFrame out;
    FrontendStats stats;
    DecodedStereoFrame in;
    in.reserve(w, h);
    long steady_allocations = 0, first_frame_allocations = 0;
    int detected_after_start = 0, tracked_after_start = 0, right_only_after_start = 0, thinned_after_start = 0,
        retried_after_start = 0, rematched_after_start = 0;
    for (int k = 0; k < num_frames; ++k) {
      const long before = voca::test::g_allocations.load();
      // Every third frame is an I-frame, so bridging copies run inside the window too.
      const PictureType type = k % 3 == 2 ? PictureType::kI : PictureType::kP;
      field.reset(w, h, type);
      if (type == PictureType::kP) {
        for (int y = 0; y < h; y += 16)
          for (int x = 0; x < w; x += 16) field.addBlock(x, y, 16, 16, 6.f, 2.f);
      }
      field.finalize();
      // Filling the message reuses its buffers (sized before the loop), as the pipeline's slots do.
      const auto image = static_cast<std::size_t>(run == 6 ? 0 : k);
      in.images[0] = run == 7 ? fast_left[image] : left[image];
      in.images[1] = run == 7 ? fast_right[image] : right[image];
      in.motion[0].copyFrom(field);
      in.motion[1].copyFrom(field);
      in.has_motion = true;
      in.t_ns = k;
      in.frame_index = k;
      frontend.track(in, out, stats);
      if (k == 0) first_frame_allocations = voca::test::g_allocations.load() - before;
      if (k >= 2) {
        steady_allocations += voca::test::g_allocations.load() - before;
        detected_after_start += stats.detected;
        right_only_after_start += stats.detected_right_only;
        thinned_after_start += stats.thinned;
        rematched_after_start += stats.stereo_rematched;
        retried_after_start += stats.temporal[0].flow_retried + stats.temporal[1].flow_retried;
        tracked_after_start += stats.temporal[0].kept + stats.temporal[1].kept;
      }
    }
    INFO("mode " << priorModeName(mode) << (run == 0 ? " with stereo_rematch" : "")
                 << (run == 5 ? " with presmooth and detection_nonoverlap" : "")
                 << (run == 6 ? " with thin_when_full_px on a still scene" : "")
                 << (run == 7 ? " with retry_previous_flow, speeding up" : ""));
    CHECK(steady_allocations == 0);
    // The counter sees the operator new calls: the first frame reserves the output buffers.
    CHECK(first_frame_allocations > 0);
    // The window exercised detection, stereo matching and tracking, not an idle tracker.
    CHECK(detected_after_start > 0);
    CHECK(tracked_after_start > 100);
    if (run == 5) CHECK(right_only_after_start > 0);
    if (run == 6) CHECK(thinned_after_start > 0);
    if (run == 0) CHECK(rematched_after_start > 0);
    if (run == 7) CHECK(retried_after_start > 100);
  }
}
