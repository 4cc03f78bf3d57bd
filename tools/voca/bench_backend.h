#pragma once
// `voca bench backend`: per-frame cost of the sliding-window estimator on synthetic observations.

#include <CLI/CLI.hpp>

#include "tools/voca/command.h"

namespace voca::cli {

// Declares the options of `voca bench backend` and returns its runner.
Runner configureBackendBench(CLI::App& app);

}  // namespace voca::cli
