// ctid: continuous-time system identification from sampled data, on the command line. The
// commands and their frame are the object library ctid_cli (command_line.h).
#include <string>
#include <vector>

#include "command_line.h"

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + (argc > 0 ? 1 : 0), argv + argc);
  return ctid::cli::run_command_line(args, ctid::cli::ProcessScope::whole);
}
