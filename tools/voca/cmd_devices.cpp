// `voca devices`: the cameras this machine has, with the formats, sizes and frame rates they offer.

#include <fmt/core.h>

#include "drivers/capture/v4l2_devices.h"
#ifdef VOCA_HAVE_LIBCAMERA
#include "drivers/capture/libcamera_source.h"
#endif
#include "tools/voca/command.h"

namespace {

int runDevices() {
  std::vector<std::string> skipped;
  const std::vector<voca::capture::V4l2DeviceInfo> cameras =
      voca::capture::listCameras(voca::platform::systemV4l2Io(), &skipped);
  fmt::print("V4L2 cameras:\n");
  if (cameras.empty()) fmt::print("  none found\n");
  fmt::print("{}", voca::capture::formatCameraList(cameras));
  for (const std::string& line : skipped) fmt::print("  could not open {}\n", line);
#ifdef VOCA_HAVE_LIBCAMERA
  fmt::print("libcamera cameras (use as --camera libcamera:N):\n");
  const std::vector<voca::capture::LibcameraCameraInfo> lc = voca::capture::listLibcameraCameras();
  if (lc.empty()) fmt::print("  none found\n");
  for (std::size_t i = 0; i < lc.size(); ++i) fmt::print("  {}: {} ({})\n", i, lc[i].model, lc[i].id);
#else
  fmt::print("libcamera cameras: not listed (built without libcamera)\n");
#endif
  return 0;
}

const bool devices_command_registered = voca::cli::registerCommand({
    .name = "devices",
    .summary = "List the cameras (V4L2, libcamera) with their formats, sizes and frame rates",
    .order = 5,
    .configure = [](CLI::App& app) -> voca::cli::Runner {
      app.footer(
          "Only video capture nodes count as cameras (codec and metadata nodes are left out). Formats marked\n"
          "\"not usable\" are compressed or colour formats voca does not read; pick a size and rate listed\n"
          "under a usable format for `voca live --size --fps` and `voca record`.");
      return [] { return runDevices(); };
    },
});

}  // namespace
