// ctid: continuous-time system identification from sampled data, on the command line.
// The subcommands register themselves (command.h); this file parses the command line,
// runs the chosen command and returns its exit status (0 ran, 3 ran but no usable model,
// 2 bad usage or input, 1 other error).
#include <signal.h>

#include <csignal>
#include <iostream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "command.h"
#include "ctid/io/file.h"
#include "output_paths.h"

#ifndef CTID_VERSION
#define CTID_VERSION "unknown"
#endif

namespace {

// SIGINT, SIGTERM and SIGHUP remove the temporary files of writes in progress (the target is
// untouched until its temporary is complete) and then end the process by the signal, so the
// exit status is the conventional 128 + signal.
extern "C" void remove_temporaries_and_die(int signal_number) {
  ctid::io::remove_pending_temporaries();
  std::signal(signal_number, SIG_DFL);
  std::raise(signal_number);
}

void install_signal_handlers() {
  for (const int signal_number : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction action {};
    action.sa_handler = remove_temporaries_and_die;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESETHAND;
    sigaction(signal_number, &action, nullptr);
  }
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ctid::cli;
  install_signal_handlers();
  CLI::App app{
      "ctid: continuous-time system identification from sampled data.\n"
      "Models are JSON files with coefficients in ascending powers (docs/formats.md);\n"
      "data are CSV files with a header row of column names, or .npy arrays whose columns\n"
      "are named 0, 1, ... Run 'ctid <command> --help' for a command's flags.\n"
      "Exit status: 0 ran, 2 bad usage or input, 1 other error,\n"
      "3 ran but no usable model (fit).",
      "ctid"};
  app.set_version_flag("--version", std::string("ctid ") + CTID_VERSION,
                       "Print the version and exit");
  app.require_subcommand(1);
  app.fallthrough(false);

  std::vector<Command> commands;
  for (const CommandRegistration& registration : registered_commands()) {
    commands.push_back(registration.factory(app));
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    std::string path = "ctid";
    std::vector<std::string> unexpected = app.remaining();
    const CLI::App* chosen = &app;  // the command whose flags a misspelt one is compared with
    for (const Command& command : commands) {
      if (command.app->parsed()) {
        path += " " + command.app->get_name();
        chosen = command.app;
        const std::vector<std::string> extra = command.app->remaining();
        unexpected.insert(unexpected.end(), extra.begin(), extra.end());
      }
    }
    // CLI11 checks required flags before unknown ones; a misspelt flag is the likelier
    // cause of both, so it is the one reported, with the closest known name when one is close.
    if (!unexpected.empty() && dynamic_cast<const CLI::CallForHelp*>(&error) == nullptr &&
        dynamic_cast<const CLI::CallForVersion*>(&error) == nullptr) {
      return report_parse_error(app, CLI::ExtrasError(unexpected), path,
                                closest_name(*chosen, unexpected));
    }
    return report_parse_error(app, error, path);
  }

  for (const Command& command : commands) {
    if (command.app->parsed()) {
      // No output may be an input or another output (output_paths.h): checked before the
      // command reads or writes anything.
      return run_command(
          "ctid " + command.app->get_name(),
          [&command] {
            check_output_paths(*command.app);
            return command.run();
          },
          command.app);
    }
  }
  std::cerr << "ctid: error: no command given (see 'ctid --help')\n";
  return kExitUsage;
}
