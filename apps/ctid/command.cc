#include "command.h"

#include <algorithm>
#include <iostream>

#include "ctid/core/error.h"
#include "ctid/io/file.h"

namespace ctid::cli {
namespace {

// A function-local static avoids the static-initialisation-order problem: commands register
// from other translation units before main() runs.
std::vector<CommandRegistration>& registry() {
  static std::vector<CommandRegistration> commands;
  return commands;
}

// Messages are printed on one line: embedded line breaks would split the one-line report.
std::string one_line(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text;
}

}  // namespace

bool register_command(int order, CommandFactory factory) {
  registry().push_back({order, factory});
  return true;
}

std::vector<CommandRegistration> registered_commands() {
  std::vector<CommandRegistration> sorted = registry();
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const auto& a, const auto& b) { return a.order < b.order; });
  return sorted;
}

int run_command(const std::string& command_path, const std::function<ExitStatus()>& action) {
  try {
    return action();
  } catch (const InvalidArgument& e) {
    std::cerr << command_path << ": error: " << one_line(e.what()) << "\n";
    return kExitUsage;
  } catch (const io::IoError& e) {
    std::cerr << command_path << ": error: " << one_line(e.what()) << "\n";
    return kExitFailure;
  } catch (const ComputationError& e) {
    std::cerr << command_path << ": error: " << one_line(e.what()) << "\n";
    return kExitFailure;
  } catch (const std::exception& e) {
    std::cerr << command_path << ": error: internal error: " << one_line(e.what()) << "\n";
    return kExitFailure;
  }
}

int report_parse_error(const CLI::App& app, const CLI::ParseError& error,
                       const std::string& command_path) {
  if (dynamic_cast<const CLI::CallForHelp*>(&error) != nullptr ||
      dynamic_cast<const CLI::CallForAllHelp*>(&error) != nullptr ||
      dynamic_cast<const CLI::CallForVersion*>(&error) != nullptr) {
    return const_cast<CLI::App&>(app).exit(error);  // prints help or version on stdout
  }
  std::cerr << command_path << ": error: " << one_line(error.what()) << " (see '" << command_path
            << " --help')\n";
  return kExitUsage;
}

void usage_error(const std::string& message) { throw InvalidArgument(message); }

}  // namespace ctid::cli
