// Counts operator new (its own test executable): encoding the live view's messages into buffers reserved
// once, and capturing a finished frame's telemetry, allocate nothing.

#include <doctest/doctest.h>

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include "formats/foxglove/foxglove_json.h"
#include "pipeline/sinks/telemetry.h"
#include "test_alloc_counter.h"

namespace {

using voca::SE3d;
namespace fg = voca::foxglove;

SE3d poseOf(double x, double y, double z, double angle) {
  return SE3d(Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d(0.3, -0.5, 0.8).normalized())),
              Eigen::Vector3d(x, y, z));
}

}  // namespace

TEST_CASE("encoding into a buffer reserved for the largest message allocates nothing") {
  const std::vector<SE3d> path(500, poseOf(-1.0 / 7.0, 2.0 / 3.0, 1e-9, 2.0));
  const std::vector<Eigen::Vector3f> points(2000, Eigen::Vector3f(-1.0f / 3.0f, 12345.6789f, 1e-7f));
  const std::vector<std::uint8_t> jpeg(50'000, 0xab);
  voca::MotionField field(752, 480);
  field.reset(752, 480, voca::PictureType::kP);
  for (int y = 0; y < 480; y += 4)
    for (int x = 0; x < 752; x += 4) field.addBlock(x, y, 4, 4, -1.0f / 3.0f, 1.0f / 7.0f);
  field.finalize();
  std::string out;
  out.reserve(std::max({fg::posesInFrameMaxBytes(path.size()), fg::pointCloudMaxBytes(points.size()),
                        fg::compressedImageMaxBytes(jpeg.size()),
                        fg::motionVectorAnnotationsMaxBytes(field.blocks().size()), fg::kSmallMessageMaxBytes}));
  const std::size_t capacity = out.capacity();
  const long before = voca::test::g_allocations.load();
  fg::writePosesInFrame(-1, "odom", path, out);
  fg::writePointCloud(std::numeric_limits<std::int64_t>::max(), "odom", points, out);
  fg::writeCompressedImage(1, "cam0", "jpeg", jpeg, out);
  fg::writeMotionVectorAnnotations(1, field.blocks(), out);
  fg::writePoseInFrame(1, "odom", path[0], out);
  fg::writeFrameTransform(1, "odom", "base_link", path[0], out);
  fg::writeFrameStats({.state = "tracking"}, out);
  CHECK(voca::test::g_allocations.load() - before == 0);
  CHECK(out.capacity() == capacity);
}

TEST_CASE("capturing a finished frame's telemetry into a reserved snapshot allocates nothing") {
  constexpr int kWidth = 752, kHeight = 480, kPoints = 300, kLandmarks = 2000;
  voca::pipeline::FrameSlot slot;
  slot.reserve(kWidth, kHeight, kPoints, kLandmarks);
  for (voca::GrayImage& image : slot.frame.images) image.resize(kWidth, kHeight);
  slot.frame.has_motion = true;
  slot.frame.motion[0].reset(kWidth, kHeight, voca::PictureType::kP);
  for (int y = 0; y < kHeight; y += 8)
    for (int x = 0; x < kWidth; x += 8) slot.frame.motion[0].addBlock(x, y, 8, 8, 1.f, 0.f);
  slot.frame.motion[0].finalize();
  slot.tracked.observations[0].assign(kPoints, {});
  slot.left_traces.assign(kPoints, {});
  slot.landmarks_world.assign(kLandmarks, Eigen::Vector3f::Ones());

  voca::pipeline::TelemetrySnapshot snapshot;
  snapshot.reserve(kWidth, kHeight, kPoints, kLandmarks);
  voca::pipeline::TelemetryChannels all;
  all.set();
  const long before = voca::test::g_allocations.load();
  for (int frame = 0; frame < 3; ++frame) {
    voca::pipeline::captureTelemetry(slot, {.decode = 1, .frontend = 2, .backend = 3, .write = 4}, all, snapshot);
  }
  CHECK(voca::test::g_allocations.load() - before == 0);
  CHECK(snapshot.left.width() == kWidth);
  CHECK(snapshot.traces.size() == static_cast<std::size_t>(kPoints));
  CHECK(snapshot.motion_blocks.size() == slot.frame.motion[0].blocks().size());
  CHECK(snapshot.landmarks.size() == static_cast<std::size_t>(kLandmarks));
}
