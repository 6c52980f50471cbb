// The command line inside the extension (decision 0052): `python3 -m ctid ARGS` runs the
// commands the `ctid` binary runs, and the batch runner asks for its plan and summary here
// instead of starting the binary.
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "command_line.h"
#include "common.h"

namespace ctid::python {
namespace {

// std::cout and std::cerr sent to strings for the life of the object.
class CapturedStreams {
 public:
  CapturedStreams()
      : out_rdbuf_(std::cout.rdbuf(out_.rdbuf())), err_rdbuf_(std::cerr.rdbuf(err_.rdbuf())) {}
  CapturedStreams(const CapturedStreams&) = delete;
  CapturedStreams& operator=(const CapturedStreams&) = delete;
  ~CapturedStreams() {
    std::cout.rdbuf(out_rdbuf_);
    std::cerr.rdbuf(err_rdbuf_);
  }
  std::string out() const { return out_.str(); }
  std::string err() const { return err_.str(); }

 private:
  std::ostringstream out_;
  std::ostringstream err_;
  std::streambuf* out_rdbuf_;
  std::streambuf* err_rdbuf_;
};

}  // namespace

void bind_command_line(py::module_& m) {
  m.def(
      "_command_line",
      [](const std::vector<std::string>& args, const std::vector<std::string>& self) {
        py::gil_scoped_release release;
        return cli::run_command_line(args, cli::ProcessScope::whole, self);
      },
      py::arg("args"), py::arg("self"),
      "Runs `ctid ARGS...` as this process's command line (python3 -m ctid): signal handlers "
      "and std::cout are taken over; `self` starts it again in a new process (the records of "
      "ctid batch). Returns the exit status.");
  m.def(
      "_command_line_captured",
      [](const std::vector<std::string>& args) {
        int status = 0;
        std::string out;
        std::string err;
        {
          py::gil_scoped_release release;
          const CapturedStreams captured;
          status = cli::run_command_line(args, cli::ProcessScope::borrowed);
          out = captured.out();
          err = captured.err();
        }
        return py::make_tuple(status, py::bytes(out), py::bytes(err));
      },
      py::arg("args"),
      "Runs `ctid ARGS...` in this process without touching its signal handlers; returns "
      "(exit status, stdout bytes, stderr bytes). Not for commands that run for long or start "
      "other processes: the batch runner uses it for --plan and --summarize.");
}

}  // namespace ctid::python
