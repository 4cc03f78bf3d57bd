#include "tools/voca/encoder_cli.h"

#include <fmt/core.h>

#include "voca/core/error.h"

namespace voca::cli {

void addEncoderOptions(CLI::App& app, EncoderCli& cli) {
  app.add_option("--encoder", cli.encoder,
                 "H.264 encoder: auto (the first that opens of v4l2m2m, vaapi, x264), x264, v4l2m2m (V4L2 "
                 "memory-to-memory: Jetson, RK3588, Raspberry Pi) or vaapi (Intel/AMD GPU)")
      ->capture_default_str();
  app.add_option("--bitrate", cli.bitrate, "Constant bitrate per camera (e.g. 500k, 1M)")->capture_default_str();
  app.add_option("--gop", cli.gop, "Frames between keyframes (a receiver recovers from loss at the next one)")
      ->capture_default_str();
  app.add_option("--vaapi-device", cli.vaapi_device, "VAAPI render node for --encoder vaapi")->capture_default_str();
  app.add_option("--pix-fmt", cli.pix_fmt,
                 "yuv420p (luma plus neutral chroma, what every decoder takes) or gray (x264 only: luma alone, "
                 "4:0:0; a software decoder then skips the chroma planes, but hardware decoders commonly take "
                 "4:2:0 only)")
      ->capture_default_str()
      ->check(CLI::IsMember({"yuv420p", "gray"}));
}

encode::LiveEncoderSettings liveEncoderSettings(const EncoderCli& cli) {
  encode::LiveEncoderSettings live;
  live.kind = encode::parseEncoderKind(cli.encoder);
  live.bitrate_bps = encode::parseBitrate(cli.bitrate);
  if (cli.gop < 1) throw InputError(fmt::format("--gop: expected at least 1 frame, got {}", cli.gop));
  live.gop = cli.gop;
  live.vaapi_device = cli.vaapi_device;
  live.monochrome = cli.pix_fmt == "gray";
  return live;
}

}  // namespace voca::cli
