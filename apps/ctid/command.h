// The frame every `ctid` subcommand plugs into, and the exit-status policy of the tool:
// 0 the command ran; 3 it ran but produced no usable model (ctid fit: the quality verdict,
// estimation/verdict.h, failed; outputs are still written); 2 bad usage or bad input (one
// line on stderr, "ctid <command>: error: <what>"); 1 any other failure. A subcommand is one file,
// <name>_command.cc, that registers itself with CTID_REGISTER_COMMAND; main.cc never
// changes when a command is added. No numerics here: commands call the library.
#pragma once

#include <functional>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include <CLI/CLI.hpp>

namespace ctid::cli {

/// Exit statuses of the ctid tool.
enum ExitStatus : int { kExitOk = 0, kExitFailure = 1, kExitUsage = 2, kExitNoUsableModel = 3 };

/// What a command's registration gives back: the CLI11 subcommand it added (its flags bound
/// to storage the command owns) and the action main() runs when that subcommand was chosen,
/// which returns the exit status of a run that finished (kExitOk or kExitNoUsableModel).
struct Command {
  CLI::App* app = nullptr;
  std::function<ExitStatus()> run;
};

/// Adds one subcommand to the top-level app.
using CommandFactory = Command (*)(CLI::App& parent);

struct CommandRegistration {
  int order;  ///< position in `ctid --help` (ascending)
  CommandFactory factory;
};

/// Records a command; called once per command at static-initialisation time through
/// CTID_REGISTER_COMMAND. Returns true so it can initialise a namespace-scope constant.
bool register_command(int order, CommandFactory factory);
/// Every registered command, sorted by order.
std::vector<CommandRegistration> registered_commands();

/// Queues a warning or note line ("warning: FILE: ...") for stderr. Queued lines are printed
/// by flush_diagnostics(), which a command calls once its refusals are behind it, and by
/// run_command when the action returns; a refusal drops them, so it stays one line.
void queue_diagnostic(std::string line);
/// Prints the queued lines on stderr, in order, and empties the queue.
void flush_diagnostics();

/// One queued line written like a stream: `QueuedLine() << "note: " << path << ...;` queues
/// the text (a trailing newline dropped) when the statement ends.
class QueuedLine {
 public:
  QueuedLine() = default;
  QueuedLine(const QueuedLine&) = delete;
  QueuedLine& operator=(const QueuedLine&) = delete;
  ~QueuedLine() {
    std::string line = text_.str();
    if (!line.empty() && line.back() == '\n') line.pop_back();
    queue_diagnostic(std::move(line));
  }
  template <typename T>
  QueuedLine& operator<<(const T& part) {
    text_ << part;
    return *this;
  }

 private:
  std::ostringstream text_;
};

/// Runs a command's action and returns its status, or maps an exception to one:
/// ctid::InvalidArgument (bad input) gives 2, anything else 1, each with one line on stderr
/// naming the command. With the command's `app`, a message naming an options field
/// ("IdentificationOptions.refined_iv.max_iterations") names the flag the user typed instead
/// (with_flag_names).
int run_command(const std::string& command_path, const std::function<ExitStatus()>& action,
                const CLI::App* app = nullptr);

/// `message` with every options-field path ("<Name>Options.a.b") replaced by the flag of `app`
/// that sets it: the deepest component that is a flag's name ("--max-iterations"), followed by
/// what remains of the path ("--delay-range (max)"); a path no flag sets is left as it is.
std::string with_flag_names(const std::string& message, const CLI::App& app);

/// Prints a CLI11 parse error as one line naming the command and the help flag, and
/// returns 2; --help and --version print to stdout and return 0. A non-empty `hint` (such as
/// closest_name() gives) is added to the message after "; ".
int report_parse_error(const CLI::App& app, const CLI::ParseError& error,
                       const std::string& command_path, const std::string& hint = {});

/// Edit distance of `a` and `b`: insertions, deletions, substitutions and transpositions of
/// two adjacent characters each count 1 (optimal string alignment).
int edit_distance(const std::string& a, const std::string& b);

/// "did you mean --modes?" for the first word of `unexpected` that is close to a name `app`
/// knows: a word starting with "--" against the long flags of `app`, a bare word against its
/// subcommands. Close: at most 1 edit for words of up to 3 characters, otherwise at most 2 or
/// a third of the word, whichever is more; of names equally close, one the word is the name
/// with characters left out of. Empty when nothing is close.
std::string closest_name(const CLI::App& app, const std::vector<std::string>& unexpected);

/// Throws ctid::InvalidArgument with `message` (usage errors found after parsing, such as
/// two inputs given at once).
[[noreturn]] void usage_error(const std::string& message);

/// Refuses (usage_error: the flag's name, then `why`) the first flag given on `app` whose help
/// group is one of `groups` and whose name is not in `taken`: a path that reads only some of a
/// command's flags (several channels) ignores none of the others.
void refuse_flags_not_taken(const CLI::App& app, const std::set<std::string>& groups,
                            const std::set<std::string>& taken, const std::string& why);

/// The whole of a flag's `text` as an int or a double; none when it is empty, not a number
/// or has characters after the number. Each command words its own usage error around it.
template <class T>
std::optional<T> parse_number(const std::string& text) {
  static_assert(std::is_same_v<T, int> || std::is_same_v<T, double>);
  std::size_t used = 0;
  T value{};
  try {
    if constexpr (std::is_same_v<T, int>) {
      value = std::stoi(text, &used);
    } else {
      value = std::stod(text, &used);
    }
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (used != text.size()) return std::nullopt;
  return value;
}

/// A CLI11 check for seed flags: the text must be a whole number from 0 to 2^64 - 1 (CLI11
/// would otherwise wrap "-1" and clamp larger values silently).
CLI::Validator seed_validator();

/// "1.41629 ± 0.00295" (format_brief); the value alone when the error is not finite (no
/// covariance), so "± one standard error" never prints a "± nan".
std::string plus_minus(double value, double error);

/// A CLI11 check for flags that take a positive finite number: "'-1' is not a positive
/// number" (CLI::PositiveNumber printed its range, up to DBL_MAX written out in 309 digits).
CLI::Validator positive_number();
/// The same for flags that take a number >= 0: "'-1' is not a number >= 0"
/// (CLI::NonNegativeNumber printed the same range).
CLI::Validator non_negative_number();

}  // namespace ctid::cli

/// Registers `factory` (a CommandFactory) at position `order` in the help listing.
#define CTID_REGISTER_COMMAND(order, factory)                            \
  [[maybe_unused]] static const bool ctid_command_registered_##factory = \
      ::ctid::cli::register_command(order, &factory)
