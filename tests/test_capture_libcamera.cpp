// libcamera capture without a camera: the camera manager starts, lists what it finds (none on a
// build machine), and asking for a camera that is not there names those that are.

#include <doctest/doctest.h>

#include "drivers/capture/libcamera_source.h"
#include "tests/test_support.h"
#include "voca/core/error.h"

using namespace voca;
using namespace voca::capture;

TEST_CASE("the libcamera camera manager starts and lists its cameras") {
  std::vector<LibcameraCameraInfo> cameras;
  REQUIRE_NOTHROW(cameras = listLibcameraCameras());
  for (const LibcameraCameraInfo& camera : cameras) CHECK_FALSE(camera.id.empty());
  MESSAGE("libcamera cameras on this machine: " << cameras.size());
}

TEST_CASE("a libcamera camera that does not exist is named with those that do") {
  const std::size_t count = listLibcameraCameras().size();
  LibcameraStereoOptions options;
  options.cameras = {"99"};
  const std::string error = test::inputErrorOf([&] { LibcameraStereoSource source(options); });
  test::expectError(error, "libcamera camera 99: no such camera; available: ");
  if (count == 0) test::expectError(error, "available: none found");
  options.cameras = {"0", "1", "2"};
  test::expectError(test::inputErrorOf([&] { LibcameraStereoSource source(options); }),
                    "expected one side-by-side camera or two cameras");
}
