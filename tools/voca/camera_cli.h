#pragma once
// Command-line options every command that captures from cameras shares (`voca live`, `voca record`):
// the devices, format, size, rate, exposure/gain and stereo pairing tolerance.

#include <CLI/CLI.hpp>
#include <string>

#include "drivers/capture/camera_source.h"

namespace voca::cli {

using CameraCli = capture::CameraSettings;

void addCameraOptions(CLI::App& app, CameraCli& cli);

// Validates the parsed options into the capture's (InputError naming the option).
capture::StereoCameraOptions applyCameraOptions(const CameraCli& cli);

// The help footer on devices, pairing and board set-up.
std::string cameraHelpFooter();

}  // namespace voca::cli
