#pragma once
// Command-line options of the live encoder, shared by the commands that encode as frames arrive
// (`voca stream`, `voca record`): --encoder, --bitrate, --gop, --vaapi-device.

#include <CLI/CLI.hpp>
#include <string>

#include "drivers/encode/live_encoder.h"

namespace voca::cli {

struct EncoderCli {
  std::string encoder = "auto";
  std::string bitrate = "1M";
  int gop = 120;
  std::string vaapi_device = "/dev/dri/renderD128";
  std::string pix_fmt = "yuv420p";
};

// Declares the options on a command.
void addEncoderOptions(CLI::App& app, EncoderCli& cli);

// The settings for encode::openLiveEncoder (fps is the caller's: the camera's or dataset's rate).
// Throws InputError naming the option on bad values.
encode::LiveEncoderSettings liveEncoderSettings(const EncoderCli& cli);

}  // namespace voca::cli
