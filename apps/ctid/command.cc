#include "command.h"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <iostream>
#include <limits>
#include <system_error>

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

// Messages are printed on one line: embedded line breaks would split the one-line report,
// other control bytes (from a binary file echoed in a message) are escaped as \xNN, and a
// message is cut after kMaxMessage bytes with its full length stated.
std::string one_line(const std::string& text) {
  constexpr size_t kMaxMessage = 2000;
  std::string out;
  for (size_t i = 0; i < text.size() && i < kMaxMessage; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\n') {
      out += ' ';
    } else if (c < 0x20 || c == 0x7f) {
      constexpr char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 0xf];
    } else {
      out += static_cast<char>(c);
    }
  }
  if (text.size() > kMaxMessage) {
    out += "... (message cut; " + std::to_string(text.size()) + " bytes)";
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  return out;
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

CLI::Validator seed_validator() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        std::uint64_t value = 0;
        const char* end = text.data() + text.size();
        const auto [stop, ec] = std::from_chars(text.data(), end, value);
        if (text.empty() || ec != std::errc() || stop != end) {
          return "'" + text + "' is not a seed: expected a whole number from 0 to " +
                 std::to_string(std::numeric_limits<std::uint64_t>::max());
        }
        return "";
      },
      "SEED");
}

}  // namespace ctid::cli
