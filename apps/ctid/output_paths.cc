#include "output_paths.h"

#include <algorithm>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "command.h"
#include "ctid/io/file.h"

namespace ctid::cli {
namespace {
namespace fs = std::filesystem;

struct NamedPath {
  std::string option;  // "--output", "data"
  std::string value;   // as the user wrote it
};

bool is_output_option(const CLI::Option& option) {
  for (const std::string& name : option.get_lnames()) {
    if (std::find(std::begin(kOutputFileOptions), std::end(kOutputFileOptions), name) !=
        std::end(kOutputFileOptions)) {
      return true;
    }
  }
  return false;
}

// Whether `a` and `b` name one file: the same inode when both exist, else the same path
// once symbolic links and "." / ".." are resolved.
bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec_a;
  std::error_code ec_b;
  if (fs::exists(a, ec_a) && fs::exists(b, ec_b)) {
    std::error_code ec;
    const bool equivalent = fs::equivalent(a, b, ec);
    return !ec && equivalent;
  }
  const fs::path canonical_a = fs::weakly_canonical(fs::absolute(a, ec_a), ec_a);
  const fs::path canonical_b = fs::weakly_canonical(fs::absolute(b, ec_b), ec_b);
  return !ec_a && !ec_b && canonical_a == canonical_b;
}

// Whether the chain of symbolic links from `path` leads through /proc: /dev/stdout and
// /dev/fd/N name an open descriptor, which io::write_text_file appends to as a stream
// whatever file is behind it (decision 0021).
bool links_through_proc(const fs::path& path) {
  fs::path current = path;
  for (int hop = 0; hop < 40; ++hop) {
    std::error_code ec;
    if (!fs::is_symlink(fs::symlink_status(current, ec))) return false;
    const fs::path target = fs::read_symlink(current, ec);
    if (ec) return false;
    current = target.is_absolute() ? target : current.parent_path() / target;
    if (current.lexically_normal().string().rfind("/proc/", 0) == 0) return true;
  }
  return false;
}

// An output that may be written to a file: missing, or a regular file (possibly through a
// link). Streams and folders are left out of the comparison.
bool is_file_output(const std::string& value) {
  std::error_code ec;
  const fs::file_status status = fs::status(value, ec);
  if (!fs::exists(status)) return true;
  return fs::is_regular_file(status) && !links_through_proc(value);
}

std::string in_quotes(const std::string& text) { return "'" + text + "'"; }

}  // namespace

void check_output_paths(const CLI::App& command) {
  std::vector<NamedPath> inputs;
  std::vector<NamedPath> outputs;
  for (const CLI::Option* option : command.get_options()) {
    if (option->count() == 0) continue;
    const bool output = is_output_option(*option);
    for (const std::string& value : option->results()) {
      if (value.empty()) continue;
      std::error_code ec;
      if (output) {
        if (is_file_output(value)) outputs.push_back({option->get_name(), value});
      } else if (fs::is_regular_file(value, ec)) {
        inputs.push_back({option->get_name(), value});
      }
    }
  }
  for (size_t i = 0; i < outputs.size(); ++i) {
    for (const NamedPath& input : inputs) {
      if (same_file(outputs[i].value, input.value)) {
        usage_error(outputs[i].option + " " + in_quotes(outputs[i].value) + " is the input file " +
                    in_quotes(input.value) + " (" + input.option +
                    "); writing it would destroy the input, so nothing was run (choose "
                    "another output file; --force does not change this)");
      }
    }
    for (size_t j = 0; j < i; ++j) {
      if (same_file(outputs[i].value, outputs[j].value)) {
        usage_error(outputs[j].option + " " + in_quotes(outputs[j].value) + " and " +
                    outputs[i].option + " " + in_quotes(outputs[i].value) +
                    " are the same file; give each output its own file");
      }
    }
  }
  // An output this user may not write is refused before anything runs (issue 33).
  for (const NamedPath& output : outputs) io::check_permission_to_write(output.value);
  // Without --force an existing output file is refused before anything runs (streams such
  // as /dev/null are written into and need no --force; io/file.h).
  const CLI::Option* force = command.get_option_no_throw("--force");
  if (force == nullptr || force->count() > 0) return;
  for (const NamedPath& output : outputs) {
    std::error_code ec;
    if (fs::exists(output.value, ec)) {
      usage_error(output.value + ": file exists; pass --force to replace it (" + output.option +
                  ")");
    }
  }
}

}  // namespace ctid::cli
