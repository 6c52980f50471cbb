// The ctid command line as a function, so that the binary (main.cc) and the Python package
// (`python3 -m ctid`, python/src/bind_command_line.cc) run the same commands (decision 0052).
#pragma once

#include <string>
#include <vector>

namespace ctid::cli {

/// How much of the process a run of the command line may take over.
enum class ProcessScope {
  /// The process is the command line: SIGINT, SIGTERM and SIGHUP remove the temporaries of
  /// writes in progress before the process ends, and std::cout escapes bytes that are not
  /// UTF-8 (decision 0042). The binary and `python3 -m ctid`.
  whole,
  /// A call inside a host that keeps its own signal handlers and streams (the Python
  /// package's batch plan and summary).
  borrowed,
};

/// Runs `ctid ARGS...` (`args` without the program name) and returns its exit status.
/// `self` is the argument vector that starts this command line in a new process, which
/// `ctid batch` runs its records with: empty for this process's own executable (the binary);
/// `python3 -m ctid` gives {interpreter, "-m", "ctid"}.
int run_command_line(const std::vector<std::string>& args, ProcessScope scope,
                     std::vector<std::string> self = {});

/// The argument vector that starts this command line in a new process (see run_command_line).
std::vector<std::string> self_command();

}  // namespace ctid::cli
