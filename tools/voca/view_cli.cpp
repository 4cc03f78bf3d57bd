#include "tools/voca/view_cli.h"

#include <fmt/core.h>

#include "pipeline/sinks/view_sink.h"
#include "platform/filesystem/output_paths.h"

namespace voca::cli {

void addViewOptions(CLI::App& app, ViewCli& cli) {
  app.add_option("--view", cli.address,
                 "Serve the run live on [host:]port (a port alone listens on every interface; port 0 picks a free\n"
                 "one): a web page at http://host:port/ and the Foxglove WebSocket protocol at ws://host:port");
  app.add_option("--view-image-rate", cli.image_rate_hz,
                 fmt::format("With --view or --mcap: camera images per second at most (0 to {}; view clients may "
                             "change theirs)",
                             pipeline::kViewMaxImageRateHz))
      ->capture_default_str();
  app.add_option("--mcap", cli.mcap,
                 "Record the channels --view serves to this MCAP file as the run goes (open it in Foxglove or\n"
                 "Lichtblick); closed with its summary at the end, also after Ctrl-C");
}

void applyViewOptions(const ViewCli& cli, voca_rt::Options& options) {
  options.view_address = cli.address;
  options.view_image_rate_hz = cli.image_rate_hz;
  options.mcap_file = cli.mcap;
}

std::unique_ptr<view::FoxgloveServer> startView(const ViewCli& cli) {
  if (cli.address.empty()) return nullptr;
  return pipeline::startViewServer(cli.address, cli.image_rate_hz, stderr);
}

pipeline::McapRunOptions mcapRunOptions(const ViewCli& cli, std::string_view run) {
  pipeline::McapRunOptions options;
  if (cli.mcap.empty()) return options;
  std::filesystem::path file = cli.mcap;
  if (!run.empty()) {
    file.replace_filename(fmt::format("{}_{}{}", file.stem().string(), run, file.extension().string()));
  }
  requireWritableFile({"the MCAP recording (--mcap)", file});
  options.file = file;
  options.image_rate_hz = cli.image_rate_hz;
  return options;
}

std::string viewHelpFooter() {
  return "Live view (--view [host:]port): open http://host:port/ in a browser for the left camera with its tracks,\n"
         "a top view of the path (and the ground truth when the input has one) and a graph of the latency per\n"
         "stage; or, in Foxglove or Lichtblick, Open connection -> Foxglove WebSocket -> ws://host:port for the\n"
         "same channels: /voca/camera/left/compressed (image with tracks), /voca/camera/left/motion_vectors\n"
         "(image annotations), /voca/pose, /tf (odom -> base_link), /voca/path, /voca/ground_truth/path,\n"
         "/voca/landmarks (point cloud) and /voca/stats (latency, tracks, drops). Images are drawn and encoded\n"
         "only while a client subscribes to them, at most --view-image-rate per second (parameter\n"
         "image_rate_hz); a client that reads too slowly misses messages rather than slowing the run, which\n"
         "ends with its input as without --view.\n"
         "Recording (--mcap FILE): the same channels written to an MCAP file as the run goes, stamped with the\n"
         "frames' time (pose, /tf and stats every frame, images at --view-image-rate, the path once a second),\n"
         "by a thread of its own that never holds the run up. Open the file in Foxglove or Lichtblick to replay\n"
         "the run. A write error (a full disk) stops the recording with a warning; the run goes on.";
}

}  // namespace voca::cli
