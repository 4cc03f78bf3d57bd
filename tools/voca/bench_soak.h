#pragma once
// `voca bench soak`: the live pipeline for many frames on a looping, lossy source; memory,
// allocations, queues and frame accounting against their targets.

#include <CLI/CLI.hpp>

#include "tools/voca/command.h"

namespace voca::cli {

Runner configureSoakBench(CLI::App& app);

}  // namespace voca::cli
