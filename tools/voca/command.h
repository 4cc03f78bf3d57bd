#pragma once
// Registry of `voca` subcommands. Each cmd_<name>.cpp registers one at static-initialisation time:
//
//   static const bool registered = voca::cli::registerCommand({
//       .name = "eval", .summary = "...", .order = 60,
//       .configure = [](CLI::App& app) -> voca::cli::Runner {
//         auto options = std::make_shared<EvalOptions>();
//         app.add_option("--ref", options->ref_path, "...")->required();
//         return [options] { return runEval(*options); };
//       }});
//
// configure() declares the options on the subcommand's CLI::App and returns the function that
// runs it after parsing. The runner returns the process exit code; voca::InputError and
// voca::RuntimeFailure thrown from it are printed as "voca <name>: error: ..." with exit 1.

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace voca::cli {

using Runner = std::function<int()>;

struct CommandSpec {
  std::string name;
  std::string summary;
  int order = 100;  // position in `voca --help`: pipeline order (synth, encode, mv, track, run, eval, bench)
  std::function<Runner(CLI::App&)> configure;
};

bool registerCommand(CommandSpec spec);
const std::vector<CommandSpec>& registeredCommands();

}  // namespace voca::cli
