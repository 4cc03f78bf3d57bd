#pragma once
// `voca bench pipeline`: whole-pipeline throughput offline (one thread vs the staged threads), latency
// at the recording's real rate, and peak memory.

#include <CLI/CLI.hpp>

#include "tools/voca/command.h"

namespace voca::cli {

Runner configurePipelineBench(CLI::App& app);

}  // namespace voca::cli
