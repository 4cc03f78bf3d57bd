// The library API (voca_rt::Odometry) as a program uses it: pushed H.264 and gray frames, bad input
// through it (another image size, time going back, a stream with B-frames, a calibration that does not
// fit), the on-device encode path, one thread pushing while another polls, and stopping from the
// destructor, and that pushing and polling allocate nothing after the start (this executable counts
// operator new: tests/test_alloc_counter.h). (The CLI's rows against the API's: test_example_odometry and test_python.)

#include <doctest/doctest.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <new>
#include <string>
#include <thread>
#include <vector>

#include "drivers/encode/video_encoder.h"
// GCC sees the replaced operator delete free() what its inlined allocator got from operator new and
// warns of a mismatch; the replacement operator new mallocs, so they match.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#include "tests/test_alloc_counter.h"
#pragma GCC diagnostic pop
#include "tests/test_support.h"
#include "voca/core/image.h"
#include "voca_rt/odometry.h"

namespace {

constexpr int kWidth = 320, kHeight = 240;
constexpr std::int64_t kFrameNs = 50'000'000;  // 20 Hz

// A pinhole stereo rig of kWidth x kHeight with a 10 cm baseline.
voca_rt::Calibration rig(int width = kWidth, int height = kHeight) {
  voca_rt::Calibration calibration;
  for (int c = 0; c < 2; ++c) {
    voca_rt::CameraModel camera;
    camera.type = "pinhole";
    camera.intrinsics = {250.0, 250.0, width / 2.0, height / 2.0};
    camera.width = width;
    camera.height = height;
    camera.T_body_cam[3] = 0.1 * c;
    calibration.cameras.push_back(camera);
  }
  return calibration;
}

// A textured picture drifting sideways with the frame index, and its right view shifted by a disparity.
voca::GrayImage picture(int frame, int disparity, int width = kWidth, int height = kHeight) {
  voca::GrayImage image(width, height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double u = x + disparity + 0.7 * frame;
      image(x, y) = static_cast<std::uint8_t>(128 + 60 * std::sin(0.21 * u) * std::cos(0.17 * y) +
                                              40 * std::sin(0.05 * u * y / 40.0));
    }
  }
  return image;
}

// One camera's Annex B access units (SPS/PPS in band), as a camera's encoder hands them out.
std::vector<std::vector<std::uint8_t>> encodeCamera(int frames, int disparity, const std::string& x264_params,
                                                    int width = kWidth, int height = kHeight) {
  voca::encode::silenceCodecLogs();
  voca::encode::EncoderSettings settings;
  settings.x264_params = x264_params;
  settings.x264_preset = "ultrafast";
  settings.two_pass = false;
  settings.global_header = false;
  settings.bitrate_bps = 1'000'000;
  voca::encode::VideoEncoder encoder;
  encoder.open(settings, width, height);
  std::vector<std::vector<std::uint8_t>> units;
  const auto keep = [&](std::span<const voca::encode::EncodedPacket> out) {
    for (const voca::encode::EncodedPacket& p : out) units.push_back(p.bytes);
  };
  for (int i = 0; i < frames; ++i) keep(encoder.encode(picture(i, disparity, width, height).view(), i));
  keep(encoder.flush());
  return units;
}

const std::string kCausal = "keyint=20:min-keyint=20:scenecut=0:bframes=0:ref=1";

voca_rt::Options grayOptions() {
  voca_rt::Options options;
  options.calibration = rig();
  options.input = voca_rt::InputKind::kGray;
  options.max_points = 200;
  return options;
}

bool pushGray(voca_rt::Odometry& odometry, int frame) {
  const voca::GrayImage left = picture(frame, 0), right = picture(frame, 8);
  return odometry.pushGray(frame * kFrameNs, left.data(), right.data(), kWidth, kHeight);
}

std::string errorOf(const auto& call) {
  try {
    call();
  } catch (const voca_rt::Error& e) {
    return e.what();
  }
  return {};
}

// Pushes the access units until one is refused, then finishes; the refusal's message, else the one
// the run stopped with (a stage may fail after the last push was taken).
std::string pushUntilRefused(voca_rt::Odometry& odometry, const std::vector<std::vector<std::uint8_t>>& left,
                             const std::vector<std::vector<std::uint8_t>>& right, voca_rt::Summary& summary) {
  std::string error;
  for (std::size_t i = 0; i < left.size() && error.empty(); ++i) {
    error = errorOf([&] {
      odometry.pushH264(static_cast<std::int64_t>(i) * kFrameNs, left[i].data(), left[i].size(), right[i].data(),
                        right[i].size());
    });
  }
  summary = odometry.finish();
  return error.empty() ? summary.error : error;
}

}  // namespace

TEST_CASE("pushH264: every access unit gives one pose, in order, with the decode stage's latency") {
  const auto left = encodeCamera(30, 0, kCausal), right = encodeCamera(30, 8, kCausal);
  REQUIRE(left.size() == 30);
  voca_rt::Options options;
  options.calibration = rig();
  options.max_points = 200;
  voca_rt::Odometry odometry(options);
  for (std::size_t i = 0; i < left.size(); ++i) {
    CHECK(odometry.pushH264(static_cast<std::int64_t>(i) * kFrameNs, left[i].data(), left[i].size(), right[i].data(),
                            right[i].size()));
  }
  const voca_rt::Summary summary = odometry.finish();
  CHECK(summary.error.empty());
  CHECK(summary.frames == 30);
  std::vector<voca_rt::Pose> poses;
  voca_rt::Pose pose;
  while (odometry.poll(pose)) poses.push_back(pose);
  REQUIRE(poses.size() == 30);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    CHECK(poses[i].frame_index == static_cast<std::int64_t>(i));
    CHECK(poses[i].t_ns == static_cast<std::int64_t>(i) * kFrameNs);
    CHECK(poses[i].latency.decode_ms > 0.0);
    CHECK(poses[i].latency.end_to_end_ms >= poses[i].latency.frontend_ms);
  }
  CHECK(odometry.description().find("decoder: software") != std::string::npos);
}

TEST_CASE("pushH264: a stream with B-frames stops the run with the decoder's message, also for later pushes") {
  const std::string with_b_frames = "keyint=20:min-keyint=20:scenecut=0:bframes=2:b-adapt=0:ref=1";
  const auto left = encodeCamera(12, 0, with_b_frames), right = encodeCamera(12, 8, with_b_frames);
  voca_rt::Options options;
  options.calibration = rig();
  voca_rt::Odometry odometry(options);
  voca_rt::Summary summary;
  const std::string error = pushUntilRefused(odometry, left, right, summary);
  INFO(error);
  CHECK(error.find("decode stage failed at frame") != std::string::npos);
  CHECK((error.find("B-frame") != std::string::npos || error.find("reorders frames") != std::string::npos));
  CHECK_FALSE(odometry.running());
  CHECK(odometry.error() == summary.error);
  // Once stopped, a push says why instead of queueing into a dead pipeline.
  const std::string later = errorOf(
      [&] { odometry.pushH264(100 * kFrameNs, left[0].data(), left[0].size(), right[0].data(), right[0].size()); });
  CHECK_FALSE(later.empty());
}

TEST_CASE("pushH264: pictures of another size than the calibration's are named with both sizes") {
  const auto left = encodeCamera(3, 0, kCausal, 160, 120), right = encodeCamera(3, 8, kCausal, 160, 120);
  voca_rt::Options options;
  options.calibration = rig();
  voca_rt::Odometry odometry(options);
  voca_rt::Summary summary;
  const std::string error = pushUntilRefused(odometry, left, right, summary);
  INFO(error);
  CHECK(error.find("160x120") != std::string::npos);
  CHECK(error.find("320x240") != std::string::npos);
}

TEST_CASE("pushGray: bad frames are refused with the reason and the odometry goes on; nothing estimated is lost") {
  voca_rt::Odometry odometry(grayOptions());
  for (int i = 0; i < 5; ++i) CHECK(pushGray(odometry, i));
  // Another size than the calibration's: both named.
  const voca::GrayImage small(160, 120);
  const std::string size_error =
      errorOf([&] { odometry.pushGray(5 * kFrameNs, small.data(), small.data(), small.width(), small.height()); });
  CHECK(size_error.find("160x120") != std::string::npos);
  CHECK(size_error.find("320x240") != std::string::npos);
  // Time that does not go forward.
  const voca::GrayImage image = picture(5, 0);
  const std::string time_error =
      errorOf([&] { odometry.pushGray(4 * kFrameNs, image.data(), image.data(), kWidth, kHeight); });
  CHECK_FALSE(time_error.empty());
  CHECK(errorOf([&] { odometry.pushGray(4 * kFrameNs, image.data(), image.data(), kWidth, kHeight); }) == time_error);
  // A stride below the width.
  CHECK_FALSE(
      errorOf([&] { odometry.pushGray(6 * kFrameNs, image.data(), image.data(), kWidth, kHeight, 10); }).empty());
  CHECK(odometry.running());
  for (int i = 5; i < 10; ++i) CHECK(pushGray(odometry, i));
  const voca_rt::Summary summary = odometry.finish();
  CHECK(summary.error.empty());
  CHECK(summary.frames == 10);
  int polled = 0;
  voca_rt::Pose pose;
  while (odometry.poll(pose)) CHECK(pose.frame_index == polled++);
  CHECK(polled == 10);
}

TEST_CASE("a calibration that cannot be used is refused when the odometry is made") {
  voca_rt::Options one_camera = grayOptions();
  one_camera.calibration.cameras.pop_back();
  CHECK_THROWS_AS(voca_rt::Odometry{one_camera}, voca_rt::Error);
  voca_rt::Options no_baseline = grayOptions();
  no_baseline.calibration.cameras[1].T_body_cam[3] = 0.0;
  CHECK_THROWS_AS(voca_rt::Odometry{no_baseline}, voca_rt::Error);
  voca_rt::Options no_file;
  no_file.calibration_file = "/nonexistent/calib.json";
  const std::string error = errorOf([&] { voca_rt::Odometry odometry(no_file); });
  CHECK(error.find("/nonexistent/calib.json") != std::string::npos);
}

TEST_CASE("one thread pushes while another polls: every frame's pose once, in order") {
  constexpr int kFrames = 60;
  voca_rt::Options options = grayOptions();
  options.poll_capacity = 8;  // smaller than the run: the poller must keep up (offline pushes wait)
  std::atomic<int> from_callback{0};
  voca_rt::Odometry odometry(options, [&](const voca_rt::Pose&) { from_callback.fetch_add(1); });
  std::atomic<bool> done{false};
  std::vector<std::int64_t> seen;
  std::thread poller([&] {
    voca_rt::Pose pose;
    for (;;) {
      const bool finished = done.load();
      while (odometry.poll(pose)) seen.push_back(pose.frame_index);
      if (finished) break;
      std::this_thread::yield();
    }
  });
  for (int i = 0; i < kFrames; ++i) pushGray(odometry, i);
  const voca_rt::Summary summary = odometry.finish();
  done.store(true);
  poller.join();
  CHECK(summary.frames == kFrames);
  CHECK(from_callback.load() == kFrames);
  // The ring keeps the newest poses when the poller falls behind; what it delivers is in order, once.
  REQUIRE_FALSE(seen.empty());
  for (std::size_t i = 1; i < seen.size(); ++i) CHECK(seen[i] > seen[i - 1]);
  CHECK(seen.back() == kFrames - 1);
}

TEST_CASE("gray frames encoded on the device first: poses carry the encode and decode stages' latency") {
  voca_rt::Options options = grayOptions();
  options.encode_bitrate = "1M";
  options.encoder = "x264";
  voca_rt::Odometry odometry(options);
  for (int i = 0; i < 20; ++i) CHECK(pushGray(odometry, i));
  const voca_rt::Summary summary = odometry.finish();
  CHECK(summary.error.empty());
  CHECK(summary.frames == 20);
  int polled = 0;
  voca_rt::Pose pose;
  while (odometry.poll(pose)) {
    ++polled;
    CHECK(pose.latency.encode_ms > 0.0);
    CHECK(pose.latency.decode_ms > 0.0);
  }
  CHECK(polled == 20);
}

TEST_CASE("the destructor stops: flushing writes every pushed frame, discarding returns at once") {
  voca::test::ScratchDir dir("api-destructor");
  const std::string trajectory = (dir / "flush.tum").string();
  {
    voca_rt::Options options = grayOptions();
    options.trajectory_file = trajectory;
    voca_rt::Odometry odometry(options, {}, voca_rt::Odometry::Stop::kFlush);
    for (int i = 0; i < 15; ++i) pushGray(odometry, i);
  }
  std::ifstream file(trajectory);
  int rows = 0;
  for (std::string line; std::getline(file, line);) rows += !line.empty() && line[0] != '#';
  CHECK(rows == 15);
  {
    voca_rt::Odometry odometry(grayOptions(), {}, voca_rt::Odometry::Stop::kDiscard);
    for (int i = 0; i < 15; ++i) pushGray(odometry, i);
  }  // returning from here at all is the check: no frame left waiting holds the threads up
}

TEST_CASE("after start, pushing gray frames and polling their poses allocates nothing") {
  constexpr int kWarmup = 15, kFrames = 45;
  std::vector<voca::GrayImage> left, right;
  for (int i = 0; i < kFrames; ++i) {
    left.push_back(picture(i, 0));
    right.push_back(picture(i, 8));
  }
  voca_rt::Odometry odometry(grayOptions());
  voca_rt::Pose pose;
  int polled = 0;
  const auto pollUntil = [&](int count) {
    while (polled < count) {
      if (odometry.poll(pose)) {
        ++polled;
      } else {
        std::this_thread::yield();
      }
    }
  };
  for (int i = 0; i < kWarmup; ++i) {
    odometry.pushGray(i * kFrameNs, left[static_cast<std::size_t>(i)].data(), right[static_cast<std::size_t>(i)].data(),
                      kWidth, kHeight);
  }
  pollUntil(kWarmup);
  const long before = voca::test::g_allocations.load();
  CHECK(before > 0);  // the counter is live: building the odometry allocated
  for (int i = kWarmup; i < kFrames; ++i) {
    odometry.pushGray(i * kFrameNs, left[static_cast<std::size_t>(i)].data(), right[static_cast<std::size_t>(i)].data(),
                      kWidth, kHeight);
  }
  pollUntil(kFrames);
  CHECK(voca::test::g_allocations.load() - before == 0);
  CHECK(odometry.finish().frames == kFrames);
}
