// V4L2 capture against the fake device (tests/fake_v4l2.h), which speaks the kernel protocol with
// the real videodev2 structs: every conversion is checked against the known pattern exactly.

#include <doctest/doctest.h>
#include <linux/videodev2.h>

#include <cerrno>
#include <cstring>
#include <optional>
#include <string>

#include "drivers/capture/camera_source.h"
#include "drivers/capture/pixel_format.h"
#include "drivers/capture/stereo_pairing.h"
#include "drivers/capture/v4l2_camera.h"
#include "drivers/capture/v4l2_devices.h"
#include "platform/realtime/clock.h"
#include "platform/v4l2/m2m_devices.h"
#include "platform/v4l2/v4l2_nodes.h"
#include "tests/fake_v4l2.h"
#include "tests/test_support.h"
#include "voca/core/error.h"

using namespace voca;
using namespace voca::capture;
using voca::test::FakeCameraSpec;
using voca::test::fakePixel;
using voca::test::FakeV4l2;

namespace {

// Columns [x0, x0 + width) of frame `sequence` match the fake's pattern exactly; returns the
// number of mismatching pixels.
int mismatches(const GrayImage& image, std::uint32_t sequence, int x0 = 0) {
  int bad = 0;
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) bad += image(x, y) != fakePixel(x0 + x, y, sequence) ? 1 : 0;
  }
  return bad;
}

// The fake's timestamp of frame `sequence` at 30 Hz, as a struct timeval carries it (microseconds).
std::int64_t stampOf(std::uint32_t sequence) {
  return (1'000'000'000 + static_cast<std::int64_t>(sequence) * 33'333'333) / 1000 * 1000;
}

CameraRequest sized(int width, int height) {
  CameraRequest request;
  request.width = width;
  request.height = height;
  return request;
}

CameraRequest withControls(std::optional<int> exposure, std::optional<int> gain) {
  CameraRequest request;
  request.controls.exposure = exposure;
  request.controls.gain = gain;
  return request;
}

StereoCameraOptions twoCameras() {
  StereoCameraOptions options;
  options.devices = {"/dev/video0", "/dev/video2"};
  options.frame_timeout_ms = 300;
  return options;
}

}  // namespace

TEST_CASE("every supported pixel format converts to the exact gray values, with padded lines") {
  for (const std::uint32_t fourcc :
       {V4L2_PIX_FMT_GREY, V4L2_PIX_FMT_Y10, V4L2_PIX_FMT_Y16, V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_NV12}) {
    CAPTURE(platform::fourccName(fourcc));
    FakeV4l2 io;
    FakeCameraSpec spec;
    spec.formats = {V4L2_PIX_FMT_MJPEG, fourcc};  // a compressed format first: it must be skipped
    spec.sizes = {{64, 48}, {32, 24}};
    spec.line_padding = 12;
    io.add(spec);
    V4l2Camera camera(io, "/dev/video0", sized(32, 24));
    CHECK(camera.format().fourcc == fourcc);
    CHECK(camera.format().width == 32);
    CHECK(camera.format().bytes_per_line > 32u);
    camera.start();
    GrayImage gray;
    for (std::uint32_t expected = 0; expected < 3; ++expected) {
      CapturedBuffer buffer;
      REQUIRE(camera.dequeue(buffer));
      CHECK(buffer.sequence == expected);
      CHECK(buffer.t_ns == stampOf(expected));
      convertToGray(buffer.data, buffer.bytes_used, fourcc, camera.format().bytes_per_line, 0, 32, 24, gray);
      CHECK(mismatches(gray, expected) == 0);
      camera.requeue(buffer);
    }
    CHECK(camera.monotonicTimestamps());
  }
}

TEST_CASE("a truncated buffer and an unsupported format are clear errors") {
  GrayImage gray;
  const std::vector<std::uint8_t> bytes(100);
  test::expectError(
      test::inputErrorOf([&] { convertToGray(bytes.data(), 100, V4L2_PIX_FMT_GREY, 16, 0, 16, 8, gray); }),
      "holds 100 bytes, 128 needed");
  test::expectError(
      test::inputErrorOf([&] { convertToGray(bytes.data(), 100, V4L2_PIX_FMT_MJPEG, 16, 0, 16, 4, gray); }),
      "MJPG is not supported");
  FakeV4l2 io;
  FakeCameraSpec spec;
  spec.formats = {V4L2_PIX_FMT_MJPEG};
  io.add(spec);
  test::expectError(test::inputErrorOf([&] { V4l2Camera(io, "/dev/video0", {}); }),
                    "/dev/video0: offers MJPG but voca reads only GREY, Y10, Y16, YUYV, NV12");
  CHECK(io.openHandles() == 0);
}

TEST_CASE("a size the device does not capture names the nearest") {
  FakeV4l2 io;
  io.add(FakeCameraSpec{});
  test::expectError(test::inputErrorOf([&] { V4l2Camera(io, "/dev/video0", sized(640, 480)); }),
                    "/dev/video0: does not capture 640x480 in GREY (nearest: 64x48");
}

TEST_CASE("discovery lists only capture nodes with their formats, sizes and rates") {
  FakeV4l2 io;
  FakeCameraSpec webcam;
  webcam.path = "/dev/video0";
  webcam.driver = "uvcvideo";
  webcam.card = "HD Webcam";
  webcam.formats = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_MJPEG};
  webcam.sizes = {{640, 480}, {320, 240}};
  webcam.rates_hz = {30, 15};
  io.add(webcam);
  FakeCameraSpec codec;
  codec.path = "/dev/video11";
  codec.driver = "bcm2835-codec";
  codec.capabilities = V4L2_CAP_VIDEO_M2M | V4L2_CAP_STREAMING | V4L2_CAP_VIDEO_CAPTURE;
  io.add(codec);
  FakeCameraSpec metadata;
  metadata.path = "/dev/video1";
  metadata.capabilities = V4L2_CAP_META_CAPTURE | V4L2_CAP_STREAMING;
  io.add(metadata);

  const std::vector<V4l2DeviceInfo> cameras = listCameras(io);
  REQUIRE(cameras.size() == 1);
  const V4l2DeviceInfo& camera = cameras[0];
  CHECK(camera.path == "/dev/video0");
  CHECK(camera.driver == "uvcvideo");
  REQUIRE(camera.formats.size() == 2);
  CHECK(camera.formats[0].gray_convertible);
  CHECK_FALSE(camera.formats[1].gray_convertible);
  REQUIRE(camera.formats[0].sizes.size() == 2);
  CHECK(camera.formats[0].sizes[1].width == 320);
  CHECK(camera.formats[0].sizes[0].rates_hz == std::vector<double>{30, 15});
  const std::string listing = formatCameraList(cameras);
  CHECK(listing.find("/dev/video0: HD Webcam (uvcvideo, platform:fake)") != std::string::npos);
  CHECK(listing.find("640x480: 30 15 fps") != std::string::npos);
  CHECK(listing.find("MJPG \"MJPG (fake)\" (not usable") != std::string::npos);
  CHECK(io.openHandles() == 0);

  // The codec node is no camera even though it has a capture queue.
  test::expectError(test::inputErrorOf([&] { V4l2Camera(io, "/dev/video11", {}); }),
                    "/dev/video11: not a camera (bcm2835-codec is a memory-to-memory codec); available: /dev/video0 "
                    "(uvcvideo, HD Webcam)");
}

TEST_CASE("one discovery walks the nodes for cameras and memory-to-memory codecs alike") {
  FakeV4l2 io;
  FakeCameraSpec webcam;  // a UVC camera that also streams H.264: compressed on CAPTURE, but no codec
  webcam.path = "/dev/video0";
  webcam.driver = "uvcvideo";
  webcam.compressed_capture = {V4L2_PIX_FMT_H264};
  io.add(webcam);
  FakeCameraSpec decoder;  // a stateful multi-planar decoder: H.264 and MPEG-2 in on OUTPUT
  decoder.path = "/dev/video10";
  decoder.driver = "rpivid";
  decoder.capabilities = V4L2_CAP_VIDEO_M2M_MPLANE | V4L2_CAP_STREAMING;
  decoder.formats = {V4L2_PIX_FMT_NV12};
  decoder.compressed_output = {V4L2_PIX_FMT_H264, V4L2_PIX_FMT_MPEG2};
  io.add(decoder);
  FakeCameraSpec encoder;  // a single-planar encoder: H.264 out on CAPTURE
  encoder.path = "/dev/video2";
  encoder.driver = "bcm2835-codec";
  encoder.capabilities = V4L2_CAP_VIDEO_M2M | V4L2_CAP_STREAMING;
  encoder.formats = {};
  encoder.compressed_capture = {V4L2_PIX_FMT_H264};
  io.add(encoder);
  FakeCameraSpec busy;  // listed but cannot be opened
  busy.path = "/dev/video3";
  busy.busy = true;
  io.add(busy);

  // The shared walk: every node that opens, in number order, with its QUERYCAP answer.
  std::vector<std::string> visited, skipped;
  platform::forEachV4l2Node(
      io,
      [&](int fd, const platform::V4l2NodeInfo& node) {
        visited.push_back(node.path + " " + node.driver);
        if (node.path == "/dev/video10") {
          const auto output = platform::enumerateFormats(io, fd, V4L2_BUF_TYPE_VIDEO_OUTPUT_MPLANE);
          REQUIRE(output.size() == 2);
          CHECK(output[1].fourcc == V4L2_PIX_FMT_MPEG2);
          CHECK(output[1].compressed);
          CHECK(output[1].description == "MPG2 (fake)");
          const auto capture = platform::enumerateFormats(io, fd, V4L2_BUF_TYPE_VIDEO_CAPTURE_MPLANE);
          REQUIRE(capture.size() == 1);
          CHECK_FALSE(capture[0].compressed);
          CHECK(platform::enumerateFormats(io, fd, V4L2_BUF_TYPE_VIDEO_CAPTURE).empty());  // no single-planar queue
        }
      },
      &skipped);
  CHECK(visited ==
        std::vector<std::string>{"/dev/video0 uvcvideo", "/dev/video2 bcm2835-codec", "/dev/video10 rpivid"});
  REQUIRE(skipped.size() == 1);
  CHECK(skipped[0] == std::string("/dev/video3: ") + std::strerror(EBUSY));
  CHECK(io.openHandles() == 0);

  // Cameras and codecs are chosen from that one walk by their capabilities.
  const std::vector<V4l2DeviceInfo> cameras = listCameras(io);
  REQUIRE(cameras.size() == 1);
  CHECK(cameras[0].path == "/dev/video0");
  CHECK(cameras[0].formats.size() == 2);  // GREY and the compressed H.264
  using platform::M2mRole;
  CHECK(platform::findM2mCodecNodes(M2mRole::kDecoder, V4L2_PIX_FMT_H264, io) ==
        std::vector<std::string>{"/dev/video10"});
  CHECK(platform::findM2mCodecNodes(M2mRole::kDecoder, V4L2_PIX_FMT_MPEG2, io) ==
        std::vector<std::string>{"/dev/video10"});
  CHECK(platform::findM2mCodecNodes(M2mRole::kEncoder, V4L2_PIX_FMT_H264, io) ==
        std::vector<std::string>{"/dev/video2"});
  CHECK(platform::findM2mCodecNodes(M2mRole::kDecoder, V4L2_PIX_FMT_MPEG4, io).empty());
  platform::V4l2NodeCaps caps;
  REQUIRE(platform::queryV4l2Node("/dev/video10", caps, io));
  CHECK(caps.driver == "rpivid");
  CHECK(caps.output_formats == std::vector<std::uint32_t>{V4L2_PIX_FMT_H264, V4L2_PIX_FMT_MPEG2});
  CHECK(caps.capture_formats.empty());
  CHECK_FALSE(platform::queryV4l2Node("/dev/video3", caps, io));
  CHECK(io.openHandles() == 0);
}

TEST_CASE("a missing device names the cameras that exist, or says none were found") {
  FakeV4l2 io;
  test::expectError(test::inputErrorOf([&] { CameraStereoSource source(twoCameras(), io); }),
                    "/dev/video0: no such device; available: none found");
  FakeCameraSpec spec;
  spec.driver = "uvcvideo";
  io.add(spec);
  test::expectError(test::inputErrorOf([&] { CameraStereoSource source(twoCameras(), io); }),
                    "/dev/video2: no such device; available: /dev/video0 (uvcvideo, Fake Camera)");
  CHECK(io.openHandles() == 0);
  CHECK(io.mappedBuffers() == 0);
}

TEST_CASE("a side-by-side stereo device is split into its left and right halves") {
  FakeV4l2 io;
  FakeCameraSpec spec;
  spec.formats = {V4L2_PIX_FMT_YUYV};
  spec.sizes = {{128, 40}};
  io.add(spec);
  StereoCameraOptions options;
  options.devices = {"/dev/video0"};
  CameraStereoSource source(options, io);
  CHECK(source.info().width == 64);
  CHECK(source.info().height == 40);
  CHECK(source.info().live);
  CHECK(source.info().kind == SourceKind::kRaw);
  CHECK(source.info().nominal_rate_hz == doctest::Approx(30.0));
  RawStereoFrame frame;
  for (std::int64_t i = 0; i < 3; ++i) {
    REQUIRE(source.next(frame));
    CHECK(frame.frame_index == i);
    CHECK(mismatches(frame.images[0], static_cast<std::uint32_t>(i), 0) == 0);
    CHECK(mismatches(frame.images[1], static_cast<std::uint32_t>(i), 64) == 0);
  }
  test::expectError(test::inputErrorOf([&] {
                      FakeV4l2 odd;
                      FakeCameraSpec s;
                      s.sizes = {{63, 40}};
                      odd.add(s);
                      CameraStereoSource bad(options, odd);
                    }),
                    "must have an even width, got 63");
}

TEST_CASE("pairing by timestamp: skewed cameras pair within the tolerance, a skipped frame is counted unpaired") {
  FakeV4l2 io;
  FakeCameraSpec left, right;
  left.path = "/dev/video0";
  right.path = "/dev/video2";
  right.offset_ns = 3'000'000;       // 3 ms later than the left camera
  right.dropped_sequences = {5, 6};  // the right driver loses two frames
  left.dropped_sequences = {10};
  io.add(left);
  io.add(right);
  StereoCameraOptions options = twoCameras();
  options.pair_tolerance_ns = 5'000'000;
  CameraStereoSource source(options, io);
  RawStereoFrame frame;
  std::vector<std::int64_t> indices;
  for (int i = 0; i < 12; ++i) {
    REQUIRE(source.next(frame));
    indices.push_back(frame.frame_index);
    const auto sequence = static_cast<std::uint32_t>(frame.frame_index);
    // Left at 1 s + seq * 33.3 ms; the right image is the right camera's frame of the same time.
    CHECK(frame.t_ns == stampOf(sequence));
    CHECK(mismatches(frame.images[0], sequence) == 0);
    CHECK(mismatches(frame.images[1], sequence) == 0);
  }
  // Left frames 5 and 6 have no partner; right frame 10 has none (the left camera lost 10).
  CHECK(indices == std::vector<std::int64_t>{0, 1, 2, 3, 4, 7, 8, 9, 11, 12, 13, 14});
  CHECK(source.counters().unpaired == 3);
  CHECK(source.counters().frames_lost == 3);  // sequence gaps: two on the right, one on the left
}

TEST_CASE("pairing tolerance: cameras further apart than the tolerance never pair, which is an error") {
  FakeV4l2 io;
  FakeCameraSpec left, right;
  left.path = "/dev/video0";
  right.path = "/dev/video2";
  right.offset_ns = 3'000'000;
  io.add(left);
  io.add(right);
  StereoCameraOptions options = twoCameras();
  options.pair_tolerance_ns = 2'000'000;
  CameraStereoSource source(options, io);
  RawStereoFrame frame;
  try {
    source.next(frame);
    FAIL("expected a pairing failure");
  } catch (const RuntimeFailure& e) {
    test::expectError(e.what(), "no two frames within 2.0 ms of each other");
  }
  CHECK(source.counters().unpaired > 10);
}

TEST_CASE("decidePair keeps the newer frame and the default tolerance is under half a frame") {
  CHECK(decidePair(100, 104, 5) == PairDecision::kPair);
  CHECK(decidePair(100, 106, 5) == PairDecision::kDropLeft);
  CHECK(decidePair(106, 100, 5) == PairDecision::kDropRight);
  CHECK(defaultPairTolerance(30.0) < 16'666'667);
  CHECK(defaultPairTolerance(30.0) > 16'000'000);
  CHECK(defaultPairTolerance(0.0) == 10'000'000);
}

TEST_CASE("a device that disappears mid-stream stops the source with a clear error and releases everything") {
  FakeV4l2 io;
  FakeCameraSpec spec;
  spec.sizes = {{128, 40}};
  spec.vanish_after_frames = 4;
  io.add(spec);
  StereoCameraOptions options;
  options.devices = {"/dev/video0"};
  {
    CameraStereoSource source(options, io);
    RawStereoFrame frame;
    for (int i = 0; i < 4; ++i) REQUIRE(source.next(frame));
    try {
      source.next(frame);
      FAIL("expected the device to be gone");
    } catch (const RuntimeFailure& e) {
      test::expectError(e.what(), "/dev/video0: the device disappeared after 4 frames");
    }
  }
  CHECK(io.openHandles() == 0);
  CHECK(io.mappedBuffers() == 0);
}

TEST_CASE("an unplugged camera is noticed through poll") {
  FakeV4l2 io;
  FakeCameraSpec left, right;
  left.path = "/dev/video0";
  right.path = "/dev/video2";
  right.paced = true;  // the right camera is waiting for its next frame when the left one goes
  left.paced = true;
  io.add(left);
  io.add(right);
  CameraStereoSource source(twoCameras(), io);
  RawStereoFrame frame;
  REQUIRE(source.next(frame));
  io.unplug("/dev/video2");
  CHECK_THROWS_AS(source.next(frame), RuntimeFailure);
}

TEST_CASE("interrupt makes a waiting next() return false") {
  FakeV4l2 io;
  FakeCameraSpec spec;
  spec.sizes = {{64, 40}};
  io.add(spec);
  StereoCameraOptions options;
  options.devices = {"/dev/video0"};
  CameraStereoSource source(options, io);
  RawStereoFrame frame;
  REQUIRE(source.next(frame));
  source.interrupt();
  CHECK_FALSE(source.next(frame));
}

TEST_CASE("timestamps not on CLOCK_MONOTONIC are replaced by the dequeue time, with a warning") {
  FakeV4l2 io;
  FakeCameraSpec spec;
  spec.sizes = {{64, 40}};
  spec.monotonic = false;
  io.add(spec);
  StereoCameraOptions options;
  options.devices = {"/dev/video0"};
  CameraStereoSource source(options, io);
  RawStereoFrame frame;
  const std::int64_t before = platform::monotonicNs();
  REQUIRE(source.next(frame));
  CHECK(frame.t_ns >= before);
  CHECK(frame.t_ns <= platform::monotonicNs());
  REQUIRE(source.warnings().size() == 1);
  test::expectError(source.warnings()[0], "not CLOCK_MONOTONIC");
}

TEST_CASE("exposure and gain pass through to the device's controls, checked against its ranges") {
  FakeV4l2 io;
  FakeCameraSpec spec;
  spec.has_exposure = true;
  spec.has_gain = true;
  io.add(spec);
  {
    V4l2Camera camera(io, "/dev/video0", withControls(120, 40));
    CHECK(io.control("/dev/video0", V4L2_CID_EXPOSURE_ABSOLUTE) == 120);
    CHECK(io.control("/dev/video0", V4L2_CID_EXPOSURE_AUTO) == V4L2_EXPOSURE_MANUAL);
    CHECK(io.control("/dev/video0", V4L2_CID_GAIN) == 40);
  }
  test::expectError(test::inputErrorOf([&] { V4l2Camera(io, "/dev/video0", withControls(std::nullopt, 999)); }),
                    "/dev/video0: gain 999 is outside the device's range 0 to 255");
  FakeV4l2 bare;
  bare.add(FakeCameraSpec{});
  test::expectError(test::inputErrorOf([&] { V4l2Camera(bare, "/dev/video0", withControls(10, std::nullopt)); }),
                    "/dev/video0: has no exposure control");
  CHECK(bare.openHandles() == 0);
}

TEST_CASE("the frame rate is set through S_PARM") {
  FakeV4l2 io;
  FakeCameraSpec spec;
  spec.rates_hz = {30, 15};
  io.add(spec);
  CameraRequest request;
  request.rate_hz = 15;
  V4l2Camera camera(io, "/dev/video0", request);
  CHECK(camera.format().rate_hz == doctest::Approx(15.0));
  CHECK(camera.warnings().empty());
  CHECK(camera.description() == "/dev/video0 (fakecam, Fake Camera) 64x48 GREY 15 fps");
}

TEST_CASE("device lists parse") {
  CHECK(parseDeviceList("/dev/video0,/dev/video2") == std::vector<std::string>{"/dev/video0", "/dev/video2"});
  CHECK(parseDeviceList("/dev/video0") == std::vector<std::string>{"/dev/video0"});
  CHECK_THROWS_AS(parseDeviceList("/dev/video0,"), InputError);
  CHECK_THROWS_AS(parseDeviceList("a,b,c"), InputError);
  CHECK_THROWS_AS(parseDeviceList("a,a"), InputError);
}
