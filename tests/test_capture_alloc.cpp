// Live capture allocates nothing per frame: kernel buffers are mapped at start and each frame is
// converted into the caller's images, which keep their size.

#include <doctest/doctest.h>

#include "drivers/capture/camera_source.h"
#include "tests/fake_v4l2.h"
#include "tests/test_alloc_counter.h"

using namespace voca;

TEST_CASE("capture from two paired cameras allocates nothing per frame in steady state") {
  for (const std::uint32_t fourcc : {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_Y10}) {
    test::FakeV4l2 io;
    test::FakeCameraSpec left, right;
    left.path = "/dev/video0";
    right.path = "/dev/video2";
    left.formats = right.formats = {fourcc};
    left.sizes = right.sizes = {{160, 120}};
    right.offset_ns = 1'000'000;
    right.dropped_sequences = {30};  // an unpaired frame on the way must not allocate either
    io.add(left);
    io.add(right);
    capture::StereoCameraOptions options;
    options.devices = {"/dev/video0", "/dev/video2"};
    capture::CameraStereoSource source(options, io);
    RawStereoFrame frame;
    for (int i = 0; i < 5; ++i) REQUIRE(source.next(frame));  // sizes the images, starts streaming
    const long before = test::g_allocations.load();
    for (int i = 0; i < 60; ++i) REQUIRE(source.next(frame));
    CHECK(test::g_allocations.load() - before == 0);
    CHECK(source.counters().unpaired == 1);
  }
}
