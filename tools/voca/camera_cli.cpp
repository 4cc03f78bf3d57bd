#include "tools/voca/camera_cli.h"

#include <fmt/core.h>

#include "voca/core/error.h"

namespace voca::cli {

void addCameraOptions(CLI::App& app, CameraCli& cli) {
  app.add_option("--camera", cli.devices,
                 "Cameras: LEFT,RIGHT V4L2 devices (e.g. /dev/video0,/dev/video2) or libcamera cameras "
                 "(libcamera:0,libcamera:1), or one side-by-side stereo camera (split into left and right halves); "
                 "`voca devices` lists them")
      ->required();
  app.add_option("--size", cli.size, "Capture size WIDTHxHEIGHT per device (default: the device's current size)");
  app.add_option("--pixel-format", cli.pixel_format,
                 "GREY, Y10, Y16, YUYV or NV12 (default: the first of these the device offers)");
  app.add_option("--fps", cli.fps, "Frame rate to ask the devices for (default: their current rate)");
  app.add_option("--exposure", cli.exposure,
                 "Manual exposure in the device's units (UVC: 100 us steps; libcamera: microseconds); turns "
                 "automatic exposure off");
  app.add_option("--gain", cli.gain, "Manual gain in the device's units; turns automatic gain off");
  app.add_option("--pair-tolerance", cli.pair_tolerance_ms,
                 "Two devices: most milliseconds between a stereo pair's timestamps (default: just under half a "
                 "frame interval)");
  app.add_option("--buffers", cli.buffers, "Kernel capture buffers per device")->capture_default_str();
  app.add_option("--frames", cli.frames, "Stop after N stereo frames (0 = until Ctrl-C)")->capture_default_str();
}

capture::StereoCameraOptions applyCameraOptions(const CameraCli& cli) { return capture::stereoCameraOptions(cli); }

std::string cameraHelpFooter() {
  return "Cameras: any V4L2 capture device (UVC webcams, sensor drivers); formats are converted to 8-bit gray.\n"
         "Two devices are paired by their kernel timestamps (CLOCK_MONOTONIC): a frame without a partner within\n"
         "the tolerance is counted as unpaired and skipped; frames the driver dropped are counted as lost.\n"
         "On a Raspberry Pi 5 the camera modules are behind libcamera: `voca devices` lists them.";
}

}  // namespace voca::cli
