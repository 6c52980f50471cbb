// `ctid batch`: runs `ctid fit` (or `ctid oma`, --output-only) on many records (a JSON or CSV
// manifest, or a glob with one shared spec) and writes one result document per record and a
// summary table. The spec is the command's own flags (a JSON object keyed by its long flag
// names); each record runs exactly `ctid fit DATA <flags> --output OUT/<name>.json --quiet` (or
// `ctid oma ...`) as a child process of this one
// (decision 0023: the fit prints on the process's std::cerr and a crash on one file must not
// end the batch), on --jobs worker threads. Finished records are skipped on a rerun (resume);
// a failed record leaves OUT/<name>.error.json. --scheduler hands the batch to the Python
// package's Dask runner (python3 -m ctid.batch). docs/batch.md.
#include <fcntl.h>
#include <glob.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <compare>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "command.h"
#include "command_line.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/io/batch_manifest.h"
#include "ctid/io/batch_summary.h"
#include "ctid/io/file.h"
#include "ctid/io/json.h"
#include "ctid/study/monte_carlo.h"
#include "plot_support.h"
#include "progress.h"

namespace ctid::cli {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

struct BatchFlags {
  std::string manifest;
  std::string glob_pattern;
  std::string spec;
  std::string out;
  int jobs = 0;
  bool retry_failed = false;
  bool force = false;
  bool strict = false;
  bool plan = false;
  bool summarize = false;
  std::string scheduler;
  bool quiet = false;
  bool output_only = false;
};

// The command each record runs: fit, or oma for output-only records (decision 0061).
std::string record_command(const BatchFlags& f) { return f.output_only ? "oma" : "fit"; }

// The record command's flags that the batch sets itself (or that write files the batch does not
// manage).
const std::map<std::string, std::string>& reserved_flags() {
  static const std::map<std::string, std::string> reserved{
      {"output", "the batch writes OUT/<name>.json (--out)"},
      {"force", "give --force to ctid batch"},
      {"quiet", "records always run quietly"},
      {"plot", "figures are not drawn in a batch"},
      {"model-output", "the model is the \"model\" field of OUT/<name>.json"},
      {"help", "not a fit setting"},
      {"help-all", "not a fit setting"}};
  return reserved;
}

// One record of the manifest with its settings merged over the shared spec.
struct Task {
  std::string name;
  std::vector<std::string> data;  // as passed to ctid fit (or oma)
  std::vector<std::string> args;  // after the executable: "fit" (or "oma"), DATA..., flags
  std::string output;             // OUT/<name>.json
  std::string error_output;       // OUT/<name>.error.json
  std::string context;            // where the record is in the manifest, for messages
};

// A record's flag value as written: JSON in a JSON manifest or spec, text in a CSV cell.
using FlagValue = io::ManifestValue;
using FlagSet = io::ManifestSettings;

// The subcommand the records run (`fit` or `oma`) on a scratch app, to check flag names against.
class FitFlagsReference {
 public:
  explicit FitFlagsReference(const std::string& command) : name_(command) {
    for (const CommandRegistration& registration : registered_commands()) {
      commands_.push_back(registration.factory(app_));
    }
    fit_ = app_.get_subcommand(command);
  }
  const std::string& name() const { return name_; }
  const CLI::App& fit() const { return *fit_; }
  const CLI::Option* option(const std::string& key) const {
    const CLI::Option* option = fit_->get_option_no_throw("--" + key);
    return option != nullptr && option->nonpositional() ? option : nullptr;
  }

 private:
  std::string name_;
  CLI::App app_;
  std::vector<Command> commands_;  // own the storage the flags are bound to
  CLI::App* fit_ = nullptr;
};

// The words a flag adds to fit's argument vector ("--modes=2"; "--submodel=2,0" "--submodel=2,1";
// "--history"; "--compute-covariance=false", which turns off a flag that is on by default;
// nothing for a value left empty).
std::vector<std::string> flag_words(const std::string& key, const FlagValue& given,
                                    const CLI::Option& option, const std::string& context) {
  const bool is_flag = option.get_expected_max() == 0 || option.get_type_size_max() == 0;
  const bool several = option.get_items_expected_max() > 1;
  const json& v = given.value;
  const std::string flag = "--" + key;
  const auto bad = [&](const std::string& rule) {
    usage_error(context + ": field '" + key + "' is " +
                (v.is_string() ? v.get<std::string>() : v.dump()) + "; " + rule);
  };
  if (v.is_null()) return {};
  if (is_flag) {
    if (v.is_boolean()) return {v.get<bool>() ? flag : flag + "=false"};
    if (given.from_csv && v.is_string()) {
      const std::string text = v.get<std::string>();
      if (text == "true" || text == "1" || text == "yes") return {flag};
      if (text == "false" || text == "0" || text == "no") return {flag + "=false"};
    }
    bad(flag + " is a flag without value: write true or false");
  }
  if (v.is_boolean()) bad(flag + " takes a value, not true or false");
  const auto text_of = [&](const json& item) -> std::string {
    if (item.is_string()) return item.get<std::string>();
    if (item.is_number()) return item.dump();
    bad("a value is a string or a number");
    return {};
  };
  std::vector<std::string> items;
  if (v.is_array()) {
    if (v.empty()) bad("an empty list gives no value");
    for (const json& item : v) items.push_back(text_of(item));
  } else if (given.from_csv && several) {
    // A CSV cell with several values separates them with spaces ("2,0 2,1").
    const std::string text = v.get<std::string>();
    std::size_t at = 0;
    while (at < text.size()) {
      const std::size_t start = text.find_first_not_of(' ', at);
      if (start == std::string::npos) break;
      const std::size_t stop = std::min(text.find(' ', start), text.size());
      items.push_back(text.substr(start, stop - start));
      at = stop;
    }
  } else {
    items.push_back(text_of(v));
  }
  if (several) {  // repeated: "--submodel=2,0" "--submodel=2,1"
    std::vector<std::string> words;
    for (const std::string& item : items) words.push_back(flag + "=" + item);
    return words;
  }
  std::string joined;
  for (const std::string& item : items) joined += (joined.empty() ? "" : ",") + item;
  return {flag + "=" + joined};
}

// Checks a flag name of the spec or a record against fit's flags.
void check_flag_name(const FitFlagsReference& fit, const std::string& key,
                     const std::string& context) {
  const auto reserved = reserved_flags().find(key);
  if (reserved != reserved_flags().end()) {
    usage_error(context + ": field '" + key + "' cannot be set in a batch (" + reserved->second +
                ")");
  }
  if (fit.option(key) == nullptr) {
    // closest_name words it for the command line ("did you mean --modes?"); a manifest
    // names the flag without dashes.
    std::string hint = closest_name(fit.fit(), {"--" + key});
    const std::string guess = "did you mean --";
    if (hint.rfind(guess, 0) == 0) {
      hint = "did you mean '" + hint.substr(guess.size(), hint.size() - guess.size() - 1) + "'?";
    } else {
      // A renamed flag ("--delay is now --input-delay-samples, ..."): the names without dashes.
      for (auto dashes = hint.find("--"); dashes != std::string::npos; dashes = hint.find("--"))
        hint.erase(dashes, 2);
    }
    const std::string command = "ctid " + fit.name();
    usage_error(context + ": field '" + key + "' is not a " + command + " flag" +
                (hint.empty() ? " (see '" + command + " --help')" : "; " + hint));
  }
}

json read_json_object(const std::string& file, const std::string& what) {
  const json document = io::read_json(file);
  if (!document.is_object()) usage_error(file + ": " + what + " is a JSON object");
  return document;
}

using RecordEntry = io::ManifestRecord;

std::vector<RecordEntry> records_from_glob(const std::string& pattern) {
  glob_t matches{};
  const int status = ::glob(pattern.c_str(), 0, nullptr, &matches);
  std::vector<RecordEntry> entries;
  if (status == 0) {
    for (std::size_t i = 0; i < matches.gl_pathc; ++i) {
      std::string path = matches.gl_pathv[i];
      if (!fs::is_regular_file(path)) continue;
      if (path.front() == '-') path = "./" + path;
      entries.push_back({"", {path}, {}, "--glob '" + pattern + "': " + path});
    }
  }
  ::globfree(&matches);
  if (entries.empty()) usage_error("--glob '" + pattern + "' matches no file");
  return entries;
}

std::string join_path(const std::string& dir, const std::string& file) {
  return (fs::path(dir) / file).string();
}

// ---- no output of the batch may be one of its inputs ----

struct FileId {
  std::uintmax_t device = 0;
  std::uintmax_t inode = 0;
  auto operator<=>(const FileId&) const = default;
};

std::optional<FileId> file_id(const std::string& path) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) return std::nullopt;
  return FileId{static_cast<std::uintmax_t>(info.st_dev), static_cast<std::uintmax_t>(info.st_ino)};
}

// Refuses, before any work and whatever --force says, an output file of the batch (a record's
// result or error document, the summary, the timings) that is the manifest, the spec, a data
// file or a file a record's flags read. Files are compared by device and inode, so links and
// "../" spellings are seen through; linear in the number of records.
void check_outputs_are_not_inputs(const BatchFlags& f, const std::vector<Task>& tasks) {
  std::map<FileId, std::string> inputs;  // what the file is, for the message
  const auto add_input = [&](const std::string& path, const std::string& what) {
    if (path.empty()) return;
    if (const auto id = file_id(path)) inputs.emplace(*id, what + " '" + path + "'");
  };
  add_input(f.manifest, "the manifest");
  add_input(f.spec, "the spec");
  for (const Task& task : tasks) {
    for (std::size_t k = 1; k < task.args.size(); ++k) {
      const std::string& word = task.args[k];
      if (word == "--output") {  // the record's own result, not an input
        ++k;
        continue;
      }
      const std::size_t equals = word.find('=');
      const std::string value =
          word.starts_with("--") && equals != std::string::npos ? word.substr(equals + 1) : word;
      if (!value.starts_with("--")) add_input(value, task.context + ": the file");
    }
  }
  const auto check = [&](const std::string& output, const std::string& what) {
    const auto id = file_id(output);
    if (!id) return;
    const auto input = inputs.find(*id);
    if (input == inputs.end()) return;
    usage_error(what + " '" + output + "' is " + input->second +
                "; writing it would destroy that file, so nothing was run (choose another --out "
                "folder or another name; --force does not change this)");
  };
  for (const char* own : {io::kBatchSummaryCsv, io::kBatchSummaryJson, io::kBatchTimings}) {
    check(join_path(f.out, own), "the batch's own file");
  }
  for (const Task& task : tasks) {
    check(task.output, task.context + ": the result");
    check(task.error_output, task.context + ": the error document");
  }
}

// The flags of every record parsed as `ctid fit` (or oma) parses them (a value that is not a
// number, not one of a flag's choices, a controller file that does not exist), so that a bad spec
// is one usage error before anything runs rather than the same failure for every record. Each
// distinct set of flags is parsed once; a record whose data file is missing is left to fail
// on its own.
void check_flag_values(const std::vector<Task>& tasks, const std::string& command) {
  std::set<std::vector<std::string>> checked;
  for (const Task& task : tasks) {
    std::error_code ignored;
    if (!fs::is_regular_file(task.data.front(), ignored)) continue;
    const auto first_flag = task.args.begin() + 1 + static_cast<std::ptrdiff_t>(task.data.size());
    std::vector<std::string> flags(first_flag, task.args.end());
    std::vector<std::string> key = flags;  // without the record's own output file
    const auto output = std::find(key.begin(), key.end(), "--output");
    if (output != key.end() && output + 1 != key.end()) key.erase(output + 1);
    if (!checked.insert(key).second) continue;
    CLI::App top;
    std::vector<Command> commands;  // own the storage the flags are parsed into
    for (const CommandRegistration& registration : registered_commands()) {
      commands.push_back(registration.factory(top));
    }
    std::vector<std::string> words{command, task.data.front()};
    words.insert(words.end(), flags.begin(), flags.end());
    std::reverse(words.begin(), words.end());  // CLI11 takes the arguments last first
    try {
      top.parse(words);
    } catch (const CLI::ParseError& e) {
      usage_error(task.context + ": the flags are not valid for ctid " + command + ": " + e.what());
    }
  }
}

// The manifest as tasks, in manifest order.
std::vector<Task> expand(const BatchFlags& f) {
  const FitFlagsReference fit(record_command(f));
  if (f.manifest.empty() == f.glob_pattern.empty()) {
    usage_error("give a manifest (MANIFEST.json or MANIFEST.csv) or --glob PATTERN, not both");
  }
  const io::ManifestKeyCheck check_key = [&fit](const std::string& key,
                                                const std::string& context) {
    check_flag_name(fit, key, context);
  };
  FlagSet spec;
  if (!f.spec.empty()) {
    spec = io::manifest_settings_from_json(read_json_object(f.spec, "a spec"), f.spec, check_key);
  }
  std::vector<RecordEntry> entries;
  if (!f.glob_pattern.empty()) {
    entries = records_from_glob(f.glob_pattern);
  } else {
    io::BatchManifest manifest = io::read_batch_manifest(f.manifest, check_key);
    for (auto& [key, value] : manifest.spec) spec[key] = std::move(value);
    entries = std::move(manifest.records);
  }
  if (entries.empty()) usage_error(f.manifest + ": the manifest has no records");
  std::vector<Task> tasks;
  const std::vector<std::string> names = io::record_names(entries);
  for (std::size_t e = 0; e < entries.size(); ++e) {
    const RecordEntry& entry = entries[e];
    Task task;
    task.name = names[e];
    task.data = entry.data;
    task.output = join_path(f.out, task.name + ".json");
    task.error_output = join_path(f.out, task.name + ".error.json");
    FlagSet merged = spec;
    for (const auto& [key, value] : entry.settings) merged[key] = value;
    // The records run side by side, so each fit filters on one thread unless the spec says
    // otherwise (decision 0068).
    if (fit.option("threads") != nullptr && merged.count("threads") == 0) {
      merged["threads"] = io::ManifestValue{1, false};
    }
    task.args.push_back(fit.name());
    task.args.insert(task.args.end(), task.data.begin(), task.data.end());
    for (const auto& [key, value] : merged) {
      const auto words = flag_words(key, value, *fit.option(key), entry.context);
      task.args.insert(task.args.end(), words.begin(), words.end());
    }
    task.args.insert(task.args.end(), {"--output", task.output, "--quiet"});
    if (f.force) task.args.push_back("--force");
    task.context = entry.context;
    tasks.push_back(std::move(task));
  }
  check_flag_values(tasks, fit.name());
  check_outputs_are_not_inputs(f, tasks);
  return tasks;
}

// ---- running one record ----

struct ChildResult {
  int exit_status = -1;  // 128 + signal when killed
  std::string err;       // the child's stderr (its last 64 KiB)
};

// Runs `command args...` with stdout on /dev/null and stderr captured. The child is sent
// SIGTERM if this thread ends first (a killed batch takes its fits with it, and their
// temporary files are removed by their signal handler).
ChildResult run_child(const std::vector<std::string>& command,
                      const std::vector<std::string>& args) {
  const std::string program = command.front();
  std::vector<std::string> words = command;
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& word : words) argv.push_back(word.data());
  argv.push_back(nullptr);
  int pipe_fds[2];
  if (::pipe2(pipe_fds, O_CLOEXEC) != 0) throw io::IoError("cannot create a pipe for a record");
  const int null_fd = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(pipe_fds[0]);
    ::close(pipe_fds[1]);
    if (null_fd >= 0) ::close(null_fd);
    throw io::IoError("cannot start a record (fork failed)");
  }
  if (pid == 0) {
    // Only async-signal-safe calls between fork and exec.
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) ::_exit(127);
    if (null_fd >= 0) ::dup2(null_fd, STDOUT_FILENO);
    ::dup2(pipe_fds[1], STDERR_FILENO);
    ::execv(program.c_str(), argv.data());
    ::_exit(127);
  }
  ::close(pipe_fds[1]);
  if (null_fd >= 0) ::close(null_fd);
  ChildResult result;
  char buffer[4096];
  while (true) {
    const ssize_t got = ::read(pipe_fds[0], buffer, sizeof buffer);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) break;
    result.err.append(buffer, static_cast<std::size_t>(got));
    constexpr std::size_t kKeep = 64 * 1024;
    if (result.err.size() > 2 * kKeep) result.err.erase(0, result.err.size() - kKeep);
  }
  ::close(pipe_fds[0]);
  int raw = 0;
  while (::waitpid(pid, &raw, 0) < 0 && errno == EINTR) {
  }
  result.exit_status = WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw);
  return result;
}

// The message of a failed record (`command`: "ctid fit" or "ctid oma"): its "ctid fit: error: ..."
// line, else its last line.
std::string failure_message(const ChildResult& child, const std::string& command) {
  std::string last;
  std::string error_line;
  std::size_t at = 0;
  while (at < child.err.size()) {
    const std::size_t stop = std::min(child.err.find('\n', at), child.err.size());
    std::string line = child.err.substr(at, stop - at);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (!line.empty()) last = line;
    if (line.rfind(command + ": error: ", 0) == 0) error_line = line;
    at = stop + 1;
  }
  if (!error_line.empty()) return error_line;
  if (child.exit_status > 128) {
    return command + " was ended by signal " + std::to_string(child.exit_status - 128) +
           (last.empty() ? "" : " (" + last + ")");
  }
  if (!last.empty()) return last;
  return command + " ended with exit status " + std::to_string(child.exit_status) +
         " and no message";
}

void remove_file(const std::string& path) {
  std::error_code ignored;
  fs::remove(path, ignored);
}

// Runs one record; returns its wall time in seconds.
double run_task(const std::vector<std::string>& command, const Task& task) {
  remove_file(task.error_output);  // a retried or forced record
  const auto start = std::chrono::steady_clock::now();
  const ChildResult child = run_child(command, task.args);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const bool wrote = fs::exists(task.output);
  if ((child.exit_status == kExitOk || child.exit_status == kExitNoUsableModel) && wrote) {
    return seconds;
  }
  const std::string record_command = "ctid " + task.args.front();
  const json error = {{"type", "ctid_batch_error"},
                      {"record", task.name},
                      {"message", wrote || child.exit_status != kExitOk
                                      ? failure_message(child, record_command)
                                      : record_command + " wrote no result document"},
                      {"exit_status", child.exit_status}};
  io::write_text_file(task.error_output, io::json_text(error) + "\n", io::Overwrite::yes);
  return seconds;
}

// The bytes of `text` as lowercase hex ("caf\xe9" -> "636166e9").
std::string hex_of(const std::string& text) {
  constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    out += kHex[byte >> 4];
    out += kHex[byte & 0xf];
  }
  return out;
}

// The files of the records, as the summary reads them.
std::vector<io::BatchRecordFiles> record_files(const std::vector<Task>& tasks) {
  std::vector<io::BatchRecordFiles> files;
  for (const Task& task : tasks) {
    files.push_back({task.name, task.data, task.output, task.error_output});
  }
  return files;
}

ExitStatus exit_status(const BatchFlags& f, const io::BatchCounts& counts) {
  if (!f.strict) return kExitOk;
  if (counts.failed > 0 || counts.not_run > 0) return kExitFailure;
  return counts.no_usable_model > 0 ? kExitNoUsableModel : kExitOk;
}

void prepare_out(const BatchFlags& f) {
  std::error_code error;
  if (fs::exists(f.out, error) && !fs::is_directory(f.out, error)) {
    usage_error("--out " + f.out + ": exists and is not a directory");
  }
  fs::create_directories(f.out, error);
  if (error) {
    usage_error("--out " + f.out + ": cannot create the directory (" + error.message() + ")");
  }
}

// --scheduler: the Python package runs the batch on a Dask cluster.
ExitStatus run_on_scheduler(const BatchFlags& f) {
  const fs::path package = require_python_package("--scheduler");
  std::vector<std::string> args{"-m", "ctid.batch"};
  if (!f.manifest.empty()) args.push_back(f.manifest);
  if (!f.glob_pattern.empty()) args.insert(args.end(), {"--glob", f.glob_pattern});
  if (!f.spec.empty()) args.insert(args.end(), {"--spec", f.spec});
  args.insert(args.end(), {"--out", f.out, "--scheduler", f.scheduler});
  if (f.jobs > 0) args.insert(args.end(), {"--jobs", std::to_string(f.jobs)});
  if (f.retry_failed) args.push_back("--retry-failed");
  if (f.force) args.push_back("--force");
  if (f.strict) args.push_back("--strict");
  if (f.quiet) args.push_back("--quiet");
  if (f.output_only) args.push_back("--output-only");
  ::setenv("PYTHONPATH", package.string().c_str(), 1);
  // The records run with this executable; from python3 -m ctid, the runner's own default.
  if (const std::vector<std::string> self = self_command(); self.size() == 1) {
    ::setenv("CTID_EXECUTABLE", self.front().c_str(), 1);
  }
  std::vector<std::string> words{python_executable()};
  words.insert(words.end(), args.begin(), args.end());
  return static_cast<ExitStatus>(run_python(std::move(words), "python3 -m ctid.batch"));
}

ExitStatus run_batch(const BatchFlags& f) {
  if (f.plan && f.summarize) usage_error("give --plan or --summarize, not both");
  if (!f.scheduler.empty()) {
    if (f.plan || f.summarize)
      usage_error("--scheduler runs the batch; it goes without --plan and --summarize");
    return run_on_scheduler(f);
  }
  const std::vector<Task> tasks = expand(f);
  if (f.plan) {
    // As a run would, before it runs.
    if (fs::is_directory(f.out) && !f.force) io::check_batch_summary_files(f.out);
    json plan = json::array();
    for (const Task& task : tasks) {
      const bool done = !f.force && (fs::exists(task.output) ||
                                     (!f.retry_failed && fs::exists(task.error_output)));
      json entry = {{"name", task.name},
                    {"data", task.data.size() == 1 ? json(task.data.front()) : json(task.data)},
                    {"args", task.args},
                    {"output", task.output},
                    {"error_output", task.error_output},
                    {"done", done}};
      // The document escapes bytes that are not UTF-8 (decision 0042); the runner that
      // executes the plan (python3 -m ctid.batch) needs the exact paths, given here in hex.
      std::vector<std::string> words = task.args;
      words.push_back(task.output);
      words.push_back(task.error_output);
      if (std::any_of(words.begin(), words.end(),
                      [](const std::string& w) { return io::escape_invalid_utf8(w) != w; })) {
        json args = json::array();
        for (const std::string& word : task.args) args.push_back(hex_of(word));
        entry["bytes"] = {{"args", args},
                          {"output", hex_of(task.output)},
                          {"error_output", hex_of(task.error_output)}};
      }
      plan.push_back(std::move(entry));
    }
    std::cout << io::json_text(plan) << "\n";
    return kExitOk;
  }
  prepare_out(f);
  if (!f.force) io::check_batch_summary_files(f.out);
  // Temporaries of records killed with -9 are swept once here; the records skip the sweep
  // (one scan of OUT per record would make a large batch quadratic).
  io::remove_dead_temporaries_in(f.out);
  if (!f.summarize) {
    ::setenv("CTID_NO_TEMPORARY_SWEEP", "1", 1);  // for the children: not in a host process
    std::vector<int> pending;
    for (int i = 0; i < static_cast<int>(tasks.size()); ++i) {
      const Task& task = tasks[static_cast<std::size_t>(i)];
      if (f.force ||
          (!fs::exists(task.output) && (f.retry_failed || !fs::exists(task.error_output)))) {
        pending.push_back(i);
      }
    }
    const std::vector<std::string> command = self_command();
    std::vector<double> seconds(pending.size(), 0.0);
    Progress progress("ctid batch", f.quiet);
    std::atomic<int> done{0};
    const int total = static_cast<int>(pending.size());
    parallel_for(total, resolve_thread_count(f.jobs), [&](int k) {
      const auto index = static_cast<std::size_t>(pending[static_cast<std::size_t>(k)]);
      seconds[static_cast<std::size_t>(k)] = run_task(command, tasks[index]);
      progress.update("records", ++done, total);
    });
    progress.clear();
    if (!pending.empty()) {
      std::map<std::string, double> times;
      for (std::size_t k = 0; k < pending.size(); ++k) {
        times[tasks[static_cast<std::size_t>(pending[k])].name] = seconds[k];
      }
      io::record_batch_timings(f.out, times);
    }
  }
  const io::BatchCounts counts = io::write_batch_summary(f.out, record_files(tasks));
  if (!f.quiet) {
    std::cout << "ctid batch: " << counts.ok << " ok, " << counts.no_usable_model
              << " no usable model, " << counts.failed << " failed";
    if (counts.not_run > 0) std::cout << ", " << counts.not_run << " not run";
    std::cout << "; summary in " << join_path(f.out, io::kBatchSummaryCsv) << "\n";
  }
  return exit_status(f, counts);
}

Command add_batch_command(CLI::App& parent) {
  auto flags = std::make_shared<BatchFlags>();
  BatchFlags& f = *flags;
  CLI::App* app = parent.add_subcommand(
      "batch",
      "Run ctid fit (or ctid oma: --output-only) on many records (a manifest or a glob) and "
      "write one result per record and a summary table; resumable, one bad file never stops the "
      "batch.");
  app->footer(
      "Manifest: JSON {\"spec\": {FLAGS}, \"records\": [{\"name\": N, \"data\": FILE, FLAGS}]} "
      "or CSV with a header name,data,<flag>...; FLAGS are ctid fit's (--output-only: ctid oma's) "
      "long flags without dashes ({\"modes\": 2, \"detrend\": \"linear\", \"history\": true}). "
      "Relative data paths are taken from the manifest's folder.\n"
      "Outputs in --out DIR: <name>.json (what 'ctid fit DATA FLAGS -o' writes), "
      "<name>.error.json for a record that failed, summary.csv and summary.json. A rerun skips "
      "finished records.\n"
      "Exit status: 0 every record ran (some may have failed: see the summary; --strict: 1 if "
      "any failed, 3 if any has no usable model), 2 bad manifest or usage, 1 other error. "
      "docs/batch.md.");
  app->add_option("manifest", f.manifest, "Manifest: records as JSON or CSV (.csv)")
      ->check(CLI::ExistingFile);
  app->add_option("--glob", f.glob_pattern,
                  "Fit every file matching this pattern (quote it) with the --spec flags");
  app->add_option("--spec", f.spec, "JSON object of ctid fit (or oma) flags shared by every record")
      ->check(CLI::ExistingFile);
  app->add_option("--out,-o", f.out, "Folder for the results (created if missing)")->required();
  app->add_option("--jobs,-j", f.jobs, "Records fitted at once (0: every core)")
      ->check(non_negative_number())
      ->capture_default_str();
  app->add_flag("--retry-failed", f.retry_failed, "Run again the records that failed before");
  app->add_flag("--force", f.force, "Run every record again and replace its result");
  app->add_flag("--strict", f.strict, "Exit 1 if any record failed, 3 if any has no usable model");
  app->add_flag("--plan", f.plan, "Print the records' ctid commands as JSON and run nothing");
  app->add_flag("--output-only", f.output_only,
                "Records without a measured input: each runs ctid oma (its flags in the spec) "
                "instead of ctid fit");
  app->add_flag("--summarize", f.summarize,
                "Only rebuild summary.csv and summary.json from the documents in --out");
  app->add_option("--scheduler", f.scheduler,
                  "Run the records on the Dask cluster at this scheduler address "
                  "(tcp://HOST:8786), through python3 -m ctid.batch");
  app->add_flag("--quiet,-q", f.quiet, "Print no count line and no progress");
  Command command;
  command.app = app;
  command.run = [flags] { return run_batch(*flags); };
  return command;
}

}  // namespace

CTID_REGISTER_COMMAND(27, add_batch_command);

}  // namespace ctid::cli
