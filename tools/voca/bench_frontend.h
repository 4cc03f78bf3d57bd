#pragma once
// `voca bench frontend`: the frontend's CPU time per stereo frame for each prior mode, measured
// through the pipeline runner (every stage in one thread, each stage timed on its own).

#include <CLI/CLI.hpp>

#include "tools/voca/command.h"

namespace voca::cli {

// Declares the options and returns the runner.
Runner configureFrontendBench(CLI::App& app);

}  // namespace voca::cli
