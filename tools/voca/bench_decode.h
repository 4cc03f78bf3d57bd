#pragma once
// `voca bench decode`: the decoder's CPU time per stereo frame (both cameras, with and without
// motion-vector export, and the MV-only parse) on one thread, beside the target.

#include <CLI/CLI.hpp>

#include "tools/voca/command.h"

namespace voca::cli {

// Declares the options and returns the runner.
Runner configureDecodeBench(CLI::App& app);

}  // namespace voca::cli
