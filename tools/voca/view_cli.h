#pragma once
// `--view [host:]port` on the commands that run the VO (`voca run`, `voca live`, `voca demo`): the live
// view server for Foxglove, Lichtblick and the built-in page.

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "drivers/view/foxglove_server.h"

namespace voca::cli {

struct ViewCli {
  std::string address;  // empty: no view
  double image_rate_hz = 10.0;
};

// Declares --view and --view-image-rate on a command.
void addViewOptions(CLI::App& app, ViewCli& cli);

// The server for --view (nullptr without it), started and announced on stderr. Throws InputError when
// the address cannot be bound, before anything else of the command happens.
std::unique_ptr<view::FoxgloveServer> startView(const ViewCli& cli);

// What --view serves and how to open it, for a command's footer.
std::string viewHelpFooter();

}  // namespace voca::cli
