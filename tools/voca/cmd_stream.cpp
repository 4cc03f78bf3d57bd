// `voca stream`: replays a raw stereo dataset at its own rate, encodes both cameras live (hardware
// encoder when there is one) and sends them as MPEG-TS to a URL, where `voca run <url>` receives them.

#include <fmt/core.h>

#include <memory>
#include <string>

#include "pipeline/stream/stream_runner.h"
#include "platform/realtime/stop_signal.h"
#include "tools/voca/command.h"
#include "tools/voca/encoder_cli.h"
#include "voca/core/error.h"

namespace {

struct StreamCli {
  std::string input, url;
  double speed = 1.0;
  int frames = 0;
  voca::cli::EncoderCli encoder;
};

int runStreamCommand(const StreamCli& o) {
  voca::pipeline::StreamOptions options;
  options.input = o.input;
  options.url = o.url;
  options.encoder = voca::cli::liveEncoderSettings(o.encoder);
  options.speed = o.speed;
  if (o.frames < 0) throw voca::InputError("--frames: expected 0 (all) or a positive count");
  options.max_frames = o.frames;
  voca::platform::installStopHandlers();
  const voca::pipeline::StreamResult result = voca::pipeline::runStream(options);
  voca::pipeline::printStreamSummary(result, stdout);
  if (result.stop_signal != 0) {
    fmt::print(stderr, "voca stream: stopped by signal {} after {} frames\n", result.stop_signal, result.frames);
    return voca::platform::interruptedExitCode(result.stop_signal);
  }
  return 0;
}

const bool stream_command_registered = voca::cli::registerCommand({
    .name = "stream",
    .summary = "Send a stereo dataset, encoded live at its own rate, over the network (MPEG-TS)",
    .order = 45,
    .configure = [](CLI::App& app) -> voca::cli::Runner {
      auto o = std::make_shared<StreamCli>();
      app.add_option("input", o->input, "Raw stereo dataset (EuRoC/TUM-VI/KITTI folder, or `voca synth` output)")
          ->required();
      app.add_option("url", o->url,
                     "Where to send: udp://host:port (e.g. udp://127.0.0.1:5000); tcp://host:port, where one side "
                     "listens (tcp://0.0.0.0:5000?listen=1 on the receiver's or the sender's URL) and starts first; "
                     "or a file path (out.ts) to write the multiplex to, which `voca run out.ts` replays")
          ->required();
      voca::cli::addEncoderOptions(app, o->encoder);
      app.add_option("--speed", o->speed, "Playback speed factor (1 = the recording's rate)")->capture_default_str();
      app.add_option("--frames", o->frames, "Send only the first N frames (0 = all)")->capture_default_str();
      app.footer(
          "Both cameras go in one MPEG-TS multiplex (two H.264 streams, no B-frames, one reference, no\n"
          "look-ahead, constant bitrate), each access unit sent the moment it is encoded and stamped with the\n"
          "frame's sensor time (an SEI message), which the receiver pairs the cameras by. Receive with\n"
          "`voca run <url> --calib <calibration>` started first. The chosen encoder is printed in one line.\n"
          "A file is written as fast as --speed allows and replayed with `voca run out.ts --calib ...`, every\n"
          "frame (`--speed 50` records a dataset in a fraction of its duration).");
      return [o] { return runStreamCommand(*o); };
    },
});

}  // namespace
