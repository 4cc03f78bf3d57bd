#pragma once
// `voca bench suite` (run an evaluation suite: the paper's tables over sequences, bitrates and modes)
// and `voca bench collect` (tables from a suite folder whose runs ran elsewhere, e.g. on a cluster).

#include <CLI/CLI.hpp>

#include "tools/voca/command.h"

namespace voca::cli {

Runner configureSuiteBench(CLI::App& app);
Runner configureCollectBench(CLI::App& app);

}  // namespace voca::cli
