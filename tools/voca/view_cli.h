#pragma once
// `--view [host:]port` and `--mcap FILE` on the commands that run the VO (`voca run`, `voca live`,
// `voca demo`): the live view server for Foxglove, Lichtblick and the built-in page, and a recording of
// the same channels to an MCAP file.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "drivers/view/foxglove_server.h"
#include "pipeline/vo/vo_run.h"
#include "voca_rt/odometry.h"

namespace voca::cli {

struct ViewCli {
  std::string address;  // empty: no view
  double image_rate_hz = 10.0;
  std::string mcap;  // empty: no recording
};

// Declares --view, --view-image-rate and --mcap on a command.
void addViewOptions(CLI::App& app, ViewCli& cli);

// --view, --view-image-rate and --mcap for the library's run (`voca run`, `voca live`).
void applyViewOptions(const ViewCli& cli, voca_rt::Options& options);

// The server for --view (nullptr without it), started and announced on stderr. Throws InputError when
// the address cannot be bound, before anything else of the command happens.
std::unique_ptr<view::FoxgloveServer> startView(const ViewCli& cli);

// The recording a run makes for --mcap (no file without it): to `file`, or for a command that makes
// several runs (`voca demo`) to `file` with "_<run>" before its extension. Throws InputError when the
// file cannot be written there, before anything else of the command happens.
pipeline::McapRunOptions mcapRunOptions(const ViewCli& cli, std::string_view run = {});

// What --view serves, what --mcap records and how to open them, for a command's footer.
std::string viewHelpFooter();

}  // namespace voca::cli
