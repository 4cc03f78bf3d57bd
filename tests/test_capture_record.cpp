// `voca record`'s library path: fake cameras -> live x264 -> a VOCA video folder, read back the way
// `voca run` reads it (same frame count, the capture timestamps, the calibration, decodable video),
// including a stop request and a camera vanishing mid-recording.

#include <doctest/doctest.h>

#include "drivers/decode/demuxer.h"
#include "drivers/source/dataset_source.h"
#include "formats/calib/calibration_io.h"
#include "formats/dataset/dataset.h"
#include "pipeline/vo/camera_runner.h"
#include "platform/filesystem/temp_dir.h"
#include "tests/fake_v4l2.h"
#include "tests/test_frontend_support.h"
#include "tests/test_support.h"
#include "voca/core/error.h"

using namespace voca;
using namespace voca::pipeline;
namespace fs = std::filesystem;

namespace {

constexpr int kWidth = 160, kHeight = 120;

std::int64_t stampOf(std::uint32_t sequence, std::int64_t offset_ns = 0) {
  return (1'000'000'000 + static_cast<std::int64_t>(sequence) * 33'333'333 + offset_ns) / 1000 * 1000;
}

void addCameras(test::FakeV4l2& io, int vanish_after = -1) {
  test::FakeCameraSpec left, right;
  left.path = "/dev/video0";
  right.path = "/dev/video2";
  left.sizes = right.sizes = {{kWidth, kHeight}};
  left.formats = right.formats = {V4L2_PIX_FMT_YUYV};
  right.offset_ns = 2'000'000;
  right.dropped_sequences = {7};
  right.vanish_after_frames = vanish_after;
  io.add(left);
  io.add(right);
}

CameraRecordOptions recordOptions(const fs::path& out, const fs::path& calibration) {
  CameraRecordOptions options;
  options.cameras.devices = {"/dev/video0", "/dev/video2"};
  options.out = out;
  options.calibration = calibration;
  options.encoder.bitrate_bps = 400'000;
  options.encoder.kind = encode::EncoderKind::kX264;
  return options;
}

// Reads every packet of a recorded camera: the container must be complete (finished mp4).
std::int64_t countPackets(const fs::path& video, bool& in_order) {
  decode::Demuxer demuxer(video);
  decode::Packet packet;
  std::int64_t count = 0;
  in_order = true;
  while (demuxer.read(packet)) {
    in_order = in_order && packet.pts == packet.dts;  // no reordering: a causal stream without B-frames
    ++count;
  }
  return count;
}

}  // namespace

TEST_CASE("voca record's path: cameras -> x264 -> a video folder that voca run's path reads back") {
  test::FakeV4l2 io;
  addCameras(io);
  TempDir dir("voca-record-test");
  const fs::path calibration = dir.path() / "rig.json";
  saveBasaltCalibration(test::pinholeRig(kWidth, kHeight, 150.0, 0.1), calibration);
  CameraRecordOptions options = recordOptions(dir.path() / "rec", calibration);
  options.cameras.max_frames = 24;
  int progress_calls = 0;
  options.progress = [&](const encode::RecordReport&) { ++progress_calls; };
  const CameraRecordResult result = recordFromCameras(options, io);
  const encode::RecordReport& r = result.report;
  CHECK(r.error.empty());
  CHECK(r.frames == 24);
  CHECK(progress_calls == 24);
  CHECK(r.source.unpaired == 1);  // left frame 7 had no partner
  CHECK(r.video_bytes > 0);
  CHECK(r.video_bytes < r.raw_bytes);
  CHECK(io.openHandles() == 0);

  const Dataset dataset = openDataset(dir.path() / "rec");
  CHECK(dataset.layout == DatasetLayout::kVocaVideo);
  REQUIRE(dataset.frames.size() == 24);
  // Capture timestamps (the left camera's) survive into data.csv; frame 7 is the skipped one.
  CHECK(dataset.frames[0].t_ns == stampOf(0));
  CHECK(dataset.frames[6].t_ns == stampOf(6));
  CHECK(dataset.frames[7].t_ns == stampOf(8));
  CHECK(dataset.frames[23].t_ns == stampOf(24));
  REQUIRE(dataset.calibration.has_value());
  const StereoRig rig = loadCalibration(*dataset.calibration);
  CHECK(rig.cameras[1].width == kWidth);
  for (const char* camera : {"cam0", "cam1"}) {
    bool in_order = false;
    CHECK(countPackets(dir.path() / "rec" / "mav0" / camera / "data.mp4", in_order) == 24);
    CHECK(in_order);
  }

  // `voca run`'s runner on the folder: every frame decoded and tracked.
  VoRunOptions run;
  run.input = dir.path() / "rec";
  run.estimate = false;
  run.progress = false;
  run.pipeline_options.stop_requested = [] { return false; };
  const VoRunResult replay = runVisualOdometry(run);
  CHECK_FALSE(replay.pipeline_report.error.has_value());
  CHECK(replay.frames == 24);
  CHECK(replay.has_motion);
}

TEST_CASE("a stop request and a vanishing camera both leave a finished, playable folder") {
  TempDir dir("voca-record-test");
  const fs::path calibration = dir.path() / "rig.json";
  saveBasaltCalibration(test::pinholeRig(kWidth, kHeight, 150.0, 0.1), calibration);
  {
    test::FakeV4l2 io;
    addCameras(io);
    CameraRecordOptions options = recordOptions(dir.path() / "stopped", calibration);
    int frames = 0;
    options.progress = [&](const encode::RecordReport& r) { frames = static_cast<int>(r.frames); };
    options.stop_requested = [&] { return frames >= 10; };  // as Ctrl-C sets the flag
    const CameraRecordResult result = recordFromCameras(options, io);
    CHECK(result.report.stopped);
    CHECK(result.report.frames == 10);
    VideoFolderSource source(openDataset(dir.path() / "stopped"));
    CHECK(source.info().expected_frames == 10);
  }
  {
    test::FakeV4l2 io;
    addCameras(io, /*vanish_after=*/12);
    const CameraRecordResult result = recordFromCameras(recordOptions(dir.path() / "vanished", calibration), io);
    test::expectError(result.report.error, "/dev/video2: the device disappeared after 12 frames");
    CHECK(result.report.frames == 12);  // the right camera delivered 12 frames, each paired
    VideoFolderSource source(openDataset(dir.path() / "vanished"));
    CHECK(source.info().expected_frames == 12);
    EncodedStereoPacket packet;
    int packets = 0;
    while (source.next(packet)) ++packets;
    CHECK(packets == 12);
    CHECK(io.openHandles() == 0);
  }
}

TEST_CASE("recording refuses an existing recording and a calibration of another size") {
  TempDir dir("voca-record-test");
  const fs::path calibration = dir.path() / "rig.json";
  saveBasaltCalibration(test::pinholeRig(320, 240, 150.0, 0.1), calibration);
  test::FakeV4l2 io;
  addCameras(io);
  test::expectError(test::inputErrorOf([&] { recordFromCameras(recordOptions(dir.path() / "a", calibration), io); }),
                    "camera 0 is calibrated for 320x240 but the frames are 160x120");
  fs::create_directories(dir.path() / "b" / "mav0");
  test::expectError(test::inputErrorOf([&] { recordFromCameras(recordOptions(dir.path() / "b", {}), io); }),
                    "already holds a recording");
  CHECK(io.openHandles() == 0);
}

TEST_CASE("recording encoder settings: the cameras' rate, headers out of band for the .mp4, causal x264") {
  encode::LiveEncoderSettings live;
  live.kind = encode::EncoderKind::kX264;
  encode::setFrameRate(live, 30.0);
  CHECK(live.fps_num == 30);
  CHECK(live.fps_den == 1);
  encode::setFrameRate(live, 29.97);
  CHECK(live.fps_num == 29970);
  CHECK(live.fps_den == 1000);
  CHECK_THROWS_AS(encode::setFrameRate(live, 0.0), InputError);
  CHECK_THROWS_AS(encode::setFrameRate(live, 5000.0), InputError);
  live.global_header = true;
  const encode::EncoderSettings s = encode::lowLatencySettings(encode::EncoderKind::kX264, live);
  CHECK(s.codec == "libx264");
  CHECK(s.global_header);
  CHECK_FALSE(s.two_pass);
  CHECK(s.x264_params.find("bframes=0") != std::string::npos);
  CHECK(s.x264_params.find("ref=1") != std::string::npos);
  CHECK(s.x264_params.find("rc-lookahead=0") != std::string::npos);
  CHECK_THROWS_AS(encode::parseEncoderKind("vp9"), InputError);
}
