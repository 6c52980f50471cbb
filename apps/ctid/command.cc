#include "command.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <limits>
#include <map>
#include <new>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/io/file.h"
#include "ctid/io/json.h"
#include "field_flags.h"

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
  // A file name of any bytes (or a cut through a character) is shown, never printed as bytes
  // that are not UTF-8 (decision 0042).
  return io::escape_invalid_utf8(out);
}

// Whether `part` is `whole` with characters left out.
bool is_subsequence(const std::string& part, const std::string& whole) {
  std::size_t at = 0;
  for (const char c : whole) {
    if (at < part.size() && part[at] == c) ++at;
  }
  return at == part.size();
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

namespace {

// Fields whose flag has another name: the flag, and which part of its value the field is.
const std::map<std::string, std::pair<std::string, std::string>>& flag_aliases() {
  static const std::map<std::string, std::pair<std::string, std::string>> aliases{
      {"start_time", {"--time", "start"}},
      {"end_time", {"--time", "end"}},
      {"first_row", {"--rows", "first"}},
      {"end_row", {"--rows", "end"}}};
  return aliases;
}

// The flag of `app` that sets the field `components` ends in, or "" when none does.
std::string flag_for(const std::vector<std::string>& components, const CLI::App& app) {
  for (std::size_t j = components.size(); j-- > 0;) {
    std::string flag = "--" + components[j];
    std::replace(flag.begin(), flag.end(), '_', '-');
    std::string rest;
    for (std::size_t k = j + 1; k < components.size(); ++k) {
      rest += (rest.empty() ? "" : ".") + components[k];
    }
    const auto alias = flag_aliases().find(components[j]);
    if (app.get_option_no_throw(flag) == nullptr && alias != flag_aliases().end()) {
      flag = alias->second.first;
      rest = alias->second.second + (rest.empty() ? "" : "." + rest);
    }
    if (app.get_option_no_throw(flag) == nullptr) continue;
    return rest.empty() ? flag : flag + " (" + rest + ")";
  }
  return "";
}

}  // namespace

std::string with_flag_names(const std::string& message, const CLI::App& app) {
  // Scanned by hand: std::regex trips GCC 12's -Wmaybe-uninitialized under the sanitizers.
  const auto lower = [](char c) { return (c >= 'a' && c <= 'z') || c == '_'; };
  const auto letter = [](char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); };
  constexpr std::string_view kMark = "Options.";
  std::string out;
  std::size_t from = 0;
  for (std::size_t found = message.find(kMark); found != std::string::npos;
       found = message.find(kMark, found + 1)) {
    std::size_t start = found;  // the struct's name: letters back to a capital
    while (start > from && letter(message[start - 1])) --start;
    if (start == found || !(message[start] >= 'A' && message[start] <= 'Z')) continue;
    std::vector<std::string> components;
    std::size_t at = found + kMark.size() - 1;  // at the '.'
    while (at + 1 < message.size() && message[at] == '.' && lower(message[at + 1])) {
      std::size_t end = at + 1;
      while (end < message.size() &&
             (lower(message[end]) || std::isdigit(static_cast<unsigned char>(message[end])))) {
        ++end;
      }
      components.push_back(message.substr(at + 1, end - at - 1));
      at = end;
    }
    // A generated flag is found by its field's path; others by the field's name.
    std::string flag = recorded_field_flag(
        app, message.substr(start, found + kMark.size() - 1 - start), components);
    if (flag.empty()) flag = flag_for(components, app);
    if (flag.empty()) continue;
    out.append(message, from, start - from);
    out += flag;
    from = at;
    found = at - 1;
  }
  out.append(message, from, std::string::npos);
  return out;
}

std::vector<std::string>& diagnostics() {
  static std::vector<std::string> queued;
  return queued;
}

void queue_diagnostic(std::string line) { diagnostics().push_back(std::move(line)); }

void flush_diagnostics() {
  for (const std::string& line : diagnostics()) std::cerr << io::escape_invalid_utf8(line) << "\n";
  diagnostics().clear();
}

int run_command(const std::string& command_path, const std::function<ExitStatus()>& action,
                const CLI::App* app) {
  diagnostics().clear();
  // Whatever ends the action, a line queued before a refusal is not printed with it.
  struct Drop {
    ~Drop() { diagnostics().clear(); }
  } drop;
  try {
    const ExitStatus status = action();
    flush_diagnostics();
    return status;
  } catch (const InvalidArgument& e) {
    const std::string message = app != nullptr ? with_flag_names(e.what(), *app) : e.what();
    std::cerr << command_path << ": error: " << one_line(message) << "\n";
    return kExitUsage;
  } catch (const io::IoError& e) {
    std::cerr << command_path << ": error: " << one_line(e.what()) << "\n";
    return kExitFailure;
  } catch (const ComputationError& e) {
    std::cerr << command_path << ": error: " << one_line(e.what()) << "\n";
    return kExitFailure;
  } catch (const std::bad_alloc&) {
    // The bounds on flags and files (docs/reliability.md) keep requests below what a machine
    // has; what still fails is the input's size, which the user can change.
    std::cerr << command_path
              << ": error: not enough memory for this input (an allocation failed); use a "
                 "shorter record, fewer channels or lower orders\n";
    return kExitUsage;
  } catch (const std::exception& e) {
    std::cerr << command_path << ": error: internal error: " << one_line(e.what()) << "\n";
    return kExitFailure;
  }
}

int report_parse_error(const CLI::App& app, const CLI::ParseError& error,
                       const std::string& command_path, const std::string& hint) {
  if (dynamic_cast<const CLI::CallForHelp*>(&error) != nullptr ||
      dynamic_cast<const CLI::CallForAllHelp*>(&error) != nullptr ||
      dynamic_cast<const CLI::CallForVersion*>(&error) != nullptr) {
    return const_cast<CLI::App&>(app).exit(error);  // prints help or version on stdout
  }
  std::cerr << command_path << ": error: " << one_line(error.what())
            << (hint.empty() ? "" : "; " + hint) << " (see '" << command_path << " --help')\n";
  return kExitUsage;
}

int edit_distance(const std::string& a, const std::string& b) {
  // d[i][j]: distance of the first i characters of a and the first j of b.
  const std::size_t n = a.size();
  const std::size_t m = b.size();
  std::vector<std::vector<int>> d(n + 1, std::vector<int>(m + 1, 0));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = static_cast<int>(i);
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = static_cast<int>(j);
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      const int substitution = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + substitution});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[n][m];
}

namespace {

// Flags renamed when a count of samples came to say so in its name (decision 0055): the old
// spelling is refused with the new one, never read in another unit.
std::string renamed_flag(const CLI::App& app, const std::string& typed) {
  static const std::vector<std::pair<std::string, std::string>> renamed{
      {"delay", "input-delay-samples"},
      {"delay-scan", "delay-scan-samples"},
      {"record-delays", "record-delay-samples"},
      {"input-delays", "input-delays-samples"}};
  for (const auto& [old_name, new_name] : renamed) {
    if (typed == old_name && app.get_option_no_throw("--" + new_name) != nullptr) {
      return "--" + old_name + " is now --" + new_name +
             ", a count of samples (a delay in seconds is --delay-range, or the model's "
             "input_delay)";
    }
  }
  return {};
}

}  // namespace

std::string closest_name(const CLI::App& app, const std::vector<std::string>& unexpected) {
  for (const std::string& word : unexpected) {
    if (word.rfind("--", 0) == 0) {
      const std::string renamed = renamed_flag(app, word.substr(2, word.find('=') - 2));
      if (!renamed.empty()) return renamed;
    }
    const bool flag = word.rfind("--", 0) == 0;
    if (!flag && !word.empty() && word.front() == '-') continue;  // a short flag or a number
    // The flag's name, without "--" and without "=VALUE".
    const std::string typed = flag ? word.substr(2, word.find('=') - 2) : word;
    if (typed.empty()) continue;
    std::vector<std::string> names;
    if (flag) {
      for (const CLI::Option* option : app.get_options()) {
        for (const std::string& name : option->get_lnames()) names.push_back(name);
      }
    } else {
      for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
        names.push_back(sub->get_name());
      }
    }
    const int allowed = typed.size() <= 3 ? 1 : std::max(2, static_cast<int>(typed.size()) / 3);
    int best = allowed + 1;
    bool best_missed = false;
    std::string chosen;
    for (const std::string& name : names) {
      const int distance = edit_distance(typed, name);
      // Of names equally close, one the word is the name with characters left out of (a
      // missed key: --input-colums is --input-columns rather than --input-column).
      const bool missed = is_subsequence(typed, name);
      if (distance > 0 && (distance < best || (distance == best && missed && !best_missed))) {
        best = distance;
        best_missed = missed;
        chosen = name;
      }
    }
    if (!chosen.empty()) return "did you mean " + std::string(flag ? "--" : "") + chosen + "?";
  }
  return {};
}

void usage_error(const std::string& message) { throw InvalidArgument(message); }

void refuse_flags_not_taken(const CLI::App& app, const std::set<std::string>& groups,
                            const std::set<std::string>& taken, const std::string& why) {
  for (const CLI::Option* option : app.get_options()) {
    if (option->count() == 0 || groups.count(option->get_group()) == 0) continue;
    if (taken.count(option->get_name()) == 0) usage_error(option->get_name() + why);
  }
}

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

namespace {

// A CLI11 check that the whole text is a finite number `accept` takes; otherwise "'TEXT' is not
// WHAT".
CLI::Validator number_check(const char* name, bool (*accept)(double), const char* what) {
  return CLI::Validator(
      [accept, what](std::string& text) -> std::string {
        const std::optional<double> value = parse_number<double>(text);
        if (!value || !std::isfinite(*value) || !accept(*value)) {
          return "'" + text + "' is not " + what;
        }
        return "";
      },
      name);
}

}  // namespace

CLI::Validator positive_number() {
  return number_check(
      "POSITIVE", [](double v) { return v > 0.0; }, "a positive number");
}

CLI::Validator non_negative_number() {
  return number_check(
      "NONNEGATIVE", [](double v) { return v >= 0.0; }, "a number >= 0");
}

std::string plus_minus(double value, double error) {
  std::string text = format_brief(value);
  if (std::isfinite(error)) text += " ± " + format_brief(error);
  return text;
}

}  // namespace ctid::cli
