// The ctid command line as one function (command_line.h): the subcommands register themselves
// (command.h); this file parses the arguments, runs the chosen command and returns its exit
// status (0 ran, 3 ran but no usable model, 2 bad usage or input, 1 other error).
#include <signal.h>

#include <csignal>
#include <filesystem>
#include <iostream>
#include <streambuf>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "command.h"
#include "command_line.h"
#include "ctid/core/error.h"
#include "ctid/io/file.h"
#include "ctid/io/json.h"
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

// std::cout line by line with the bytes that are not UTF-8 written \xHH (decision 0042): the
// summaries echo the names of the files read and written, which may be any bytes. A complete
// line goes out at once, so its order with what else reaches stdout is as before.
class Utf8Lines : public std::streambuf {
 public:
  explicit Utf8Lines(std::streambuf* target) : target_(target) {}

 protected:
  int_type overflow(int_type c) override {
    if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
    const char byte = traits_type::to_char_type(c);
    return xsputn(&byte, 1) == 1 ? c : traits_type::eof();
  }
  std::streamsize xsputn(const char* text, std::streamsize count) override {
    pending_.append(text, static_cast<std::size_t>(count));
    const std::size_t end = pending_.rfind('\n');
    if (end != std::string::npos && !emit(end + 1)) return 0;
    return count;
  }
  int sync() override { return emit(pending_.size()) && target_->pubsync() == 0 ? 0 : -1; }

 private:
  // Writes the first `count` bytes of pending_, escaped.
  bool emit(std::size_t count) {
    const std::string out =
        ctid::io::escape_invalid_utf8(std::string_view(pending_).substr(0, count));
    pending_.erase(0, count);
    const auto size = static_cast<std::streamsize>(out.size());
    return target_->sputn(out.data(), size) == size;
  }
  std::streambuf* target_;
  std::string pending_;
};

// Puts Utf8Lines in front of std::cout for the life of the process: a static, so that what is
// pending is written and std::cout restored also when the process ends by std::exit.
void escape_stdout() {
  struct Guard {
    Utf8Lines lines{std::cout.rdbuf()};
    std::streambuf* original = std::cout.rdbuf(&lines);
    ~Guard() {
      std::cout.flush();
      std::cout.rdbuf(original);
    }
  };
  static Guard guard;
}

}  // namespace

namespace ctid::cli {
namespace {
std::vector<std::string>& self_command_storage() {
  static std::vector<std::string> self;
  return self;
}
}  // namespace

std::vector<std::string> self_command() {
  if (!self_command_storage().empty()) return self_command_storage();
  std::error_code error;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) throw ComputationError("cannot find the ctid executable (/proc/self/exe)");
  return {exe.string()};
}

int run_command_line(const std::vector<std::string>& args, ProcessScope scope,
                     std::vector<std::string> self) {
  self_command_storage() = std::move(self);
  if (scope == ProcessScope::whole) {
    install_signal_handlers();
    escape_stdout();
  }
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
    std::vector<std::string> words(args.rbegin(), args.rend());  // CLI11 takes them last first
    app.parse(words);
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

}  // namespace ctid::cli
