// `voca`: the VOCA-RT command line. Subcommands register themselves (command.h).

#include <algorithm>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>
#include <string_view>

#include <fmt/core.h>

#include "tools/voca/command.h"
#include "voca/core/error.h"
#include "voca_rt/error.h"

namespace voca::cli {

namespace {
std::vector<CommandSpec>& registry() {
  static std::vector<CommandSpec> commands;
  return commands;
}
}  // namespace

bool registerCommand(CommandSpec spec) {
  registry().push_back(std::move(spec));
  return true;
}

const std::vector<CommandSpec>& registeredCommands() { return registry(); }

}  // namespace voca::cli

namespace {
// A command line that does not parse: an unknown option, a missing or malformed value.
constexpr int kUsageExitCode = 2;
}  // namespace

int main(int argc, char** argv) {
  using namespace voca::cli;
  CLI::App app{
      "VOCA-RT: causal stereo visual odometry on H.264 video, with the codec's motion vectors as\n"
      "priors for KLT tracking. Run `voca <command> --help` for a command's options."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "voca 0.1.0");

  std::vector<CommandSpec> commands = registeredCommands();
  std::stable_sort(commands.begin(), commands.end(),
                   [](const CommandSpec& a, const CommandSpec& b) { return a.order < b.order; });
  std::vector<std::pair<CLI::App*, Runner>> runners;
  for (const CommandSpec& spec : commands) {
    CLI::App* sub = app.add_subcommand(spec.name, spec.summary);
    runners.emplace_back(sub, spec.configure(*sub));
    // `voca --help` lists one line per command; a longer description a command sets for itself
    // belongs in its own --help, after the options.
    if (sub->get_description() != spec.summary) {
      const std::string details = sub->get_description();
      const std::string footer = sub->get_footer();
      sub->description(spec.summary);
      sub->footer(footer.empty() ? details : details + "\n\n" + footer);
    }
  }

  // CLI11 answers a misspelt command with "A subcommand is required", which names neither.
  if (argc > 1 && argv[1][0] != '-') {
    const std::string_view given = argv[1];
    const bool known =
        std::any_of(commands.begin(), commands.end(), [&](const CommandSpec& spec) { return spec.name == given; });
    if (!known) {
      std::string names;
      for (const CommandSpec& spec : commands) names += (names.empty() ? "" : ", ") + spec.name;
      fmt::print(stderr, "voca: unknown command '{}' (the commands: {}); `voca --help` describes them\n", given, names);
      return kUsageExitCode;
    }
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version end here too (CLI11 code 0); every other parse error is a usage error,
    // exit code 2 (CLI11's own codes, 101-127, would read as a crash's or a signal's).
    return app.exit(e) == 0 ? 0 : kUsageExitCode;
  }

  for (auto& [sub, run] : runners) {
    if (!sub->parsed()) continue;
    try {
      return run();
    } catch (const voca::InputError& e) {
      fmt::print(stderr, "voca {}: error: {}\n", sub->get_name(), e.what());
      return 1;
    } catch (const voca_rt::Error& e) {
      fmt::print(stderr, "voca {}: error: {}\n", sub->get_name(), e.what());
      return 1;
    } catch (const voca::RuntimeFailure& e) {
      fmt::print(stderr, "voca {}: error: {}\n", sub->get_name(), e.what());
      return 1;
    } catch (const std::filesystem::filesystem_error& e) {
      // A path the system refused (a file where a folder belongs, no permission, a full disk): the
      // user's to fix, and the message names the path.
      fmt::print(stderr, "voca {}: error: {}\n", sub->get_name(), e.what());
      return 1;
    } catch (const std::exception& e) {
      fmt::print(stderr, "voca {}: internal error: {}\n", sub->get_name(), e.what());
      return 3;
    }
  }
  return 0;
}
