#include "plot_support.h"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <numbers>
#include <random>
#include <sstream>
#include <system_error>
#include <utility>
#include <vector>

#include "ctid/core/error.h"
#include "ctid/frequency/mimo_frf.h"
#include "ctid/io/csv.h"
#include "ctid/io/json.h"
#include "ctid/io/model_json.h"
#include "ctid/io/report_json.h"

namespace ctid::cli {
namespace {

constexpr const char* kPython = "/usr/bin/python3";

std::string quote(const std::string& word) {
  std::string quoted = "'";
  for (char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

bool holds_package(const std::filesystem::path& dir) {
  std::error_code ignored;
  if (!std::filesystem::is_regular_file(dir / "ctid" / "plot.py", ignored)) return false;
  for (const auto& entry : std::filesystem::directory_iterator(dir / "ctid", ignored)) {
    if (entry.path().filename().string().rfind("_ctid", 0) == 0) return true;
  }
  return false;
}

std::filesystem::path executable_directory() {
  std::error_code error;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
  return error ? std::filesystem::path() : exe.parent_path();
}

// Where the package may be, in the order searched.
std::vector<std::filesystem::path> candidates() {
  std::vector<std::filesystem::path> dirs;
  if (const char* env = std::getenv("CTID_PYTHONPATH"); env != nullptr && *env != '\0') {
    dirs.emplace_back(env);
  }
  const std::filesystem::path exe_dir = executable_directory();
  if (!exe_dir.empty()) {
    dirs.push_back(exe_dir / ".." / ".." / "python");  // build tree: <build>/apps/ctid/ctid
    dirs.push_back(exe_dir / ".." / "python");
    dirs.push_back(exe_dir / ".." / "lib" / "ctid" / "python");  // install: <prefix>/bin/ctid
  }
  return dirs;
}

std::string last_line(const std::string& text) {
  std::string trimmed = text;
  while (!trimmed.empty() && (trimmed.back() == '\n' || trimmed.back() == ' ')) {
    trimmed.pop_back();
  }
  const auto pos = trimmed.rfind('\n');
  return pos == std::string::npos ? trimmed : trimmed.substr(pos + 1);
}

}  // namespace

std::optional<std::filesystem::path> find_python_package() {
  for (const std::filesystem::path& dir : candidates()) {
    if (holds_package(dir)) return std::filesystem::weakly_canonical(dir);
  }
  return std::nullopt;
}

std::filesystem::path require_plotting() { return require_python_package("--plot"); }

std::string python_executable() { return kPython; }

int run_python(std::vector<std::string> words, const std::string& what) {
  std::vector<char*> argv;
  for (std::string& word : words) argv.push_back(word.data());
  argv.push_back(nullptr);
  std::cout.flush();
  const pid_t pid = ::fork();
  if (pid < 0) throw ComputationError("cannot start " + words.front());
  if (pid == 0) {
    ::execv(words.front().c_str(), argv.data());
    ::_exit(127);
  }
  int raw = 0;
  while (::waitpid(pid, &raw, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(raw)) throw ComputationError(what + " was ended by a signal");
  if (WEXITSTATUS(raw) == 127) throw ComputationError("could not run " + words.front());
  return WEXITSTATUS(raw);
}

std::filesystem::path require_python_package(const std::string& flag) {
  if (::access(kPython, X_OK) != 0) {
    throw ComputationError(flag + " needs " + kPython +
                           (flag == "--plot" ? " with matplotlib" : "") +
                           ", which is not installed");
  }
  if (auto dir = find_python_package()) return *dir;
  std::string looked;
  for (const std::filesystem::path& dir : candidates()) {
    looked += (looked.empty() ? "" : ", ") + dir.lexically_normal().string();
  }
  throw ComputationError(
      flag +
      " needs the ctid Python package (build with -DCTID_BUILD_PYTHON=ON, or set "
      "CTID_PYTHONPATH to the folder holding ctid/); looked in " +
      looked);
}

void plot(const std::filesystem::path& package_dir, const std::vector<PlotJob>& jobs) {
  if (jobs.empty()) return;
  for (const PlotJob& job : jobs) {
    if (job.output.has_parent_path()) create_output_directory(job.output.parent_path(), "--plot");
  }
  const TemporaryDirectory status_dir;
  std::string command;
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    const PlotJob& job = jobs[i];
    const std::string stem = (status_dir.path() / std::to_string(i)).string();
    std::string one = "PYTHONPATH=" + quote(package_dir.string()) + " MPLBACKEND=Agg " + kPython +
                      " -m ctid.plot " + quote(job.kind) + " " + quote(job.input.string()) + " " +
                      quote(job.output.string());
    if (!job.title.empty()) one += " --title " + quote(job.title);
    for (const std::string& argument : job.arguments) one += " " + quote(argument);
    command += "( " + one + " > /dev/null 2> " + quote(stem + ".err") + "; echo $? > " +
               quote(stem + ".status") + " ) & ";
  }
  command += "wait";
  const int raw = std::system(command.c_str());
  if (!WIFEXITED(raw) || WEXITSTATUS(raw) != 0) {
    throw ComputationError("could not run " + std::string(kPython) + " for the figures");
  }
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    const std::string stem = (status_dir.path() / std::to_string(i)).string();
    int status = -1;
    std::ifstream(stem + ".status") >> status;
    if (status == 0) continue;
    std::ifstream in(stem + ".err");
    std::ostringstream text;
    text << in.rdbuf();
    const std::string message =
        "plotting " + jobs[i].output.filename().string() + " failed: " + last_line(text.str());
    if (status == 2) throw InvalidArgument(message);
    throw ComputationError(message);
  }
}

void run_python_module(const std::filesystem::path& package_dir, const std::string& module,
                       const std::vector<std::string>& arguments, const std::string& what) {
  const TemporaryDirectory status_dir;
  const std::string errors = (status_dir.path() / "stderr").string();
  std::string command =
      "PYTHONPATH=" + quote(package_dir.string()) + " " + kPython + " -m " + quote(module);
  for (const std::string& argument : arguments) command += " " + quote(argument);
  command += " > /dev/null 2> " + quote(errors);
  const int raw = std::system(command.c_str());
  if (raw != -1 && WIFEXITED(raw) && WEXITSTATUS(raw) == 0) return;
  std::ifstream in(errors);
  std::ostringstream text;
  text << in.rdbuf();
  std::string message = what + " failed";
  if (const std::string line = last_line(text.str()); !line.empty()) message += ": " + line;
  if (raw != -1 && WIFEXITED(raw) && WEXITSTATUS(raw) == 2) throw InvalidArgument(message);
  throw ComputationError(message);
}

TemporaryDirectory::TemporaryDirectory() {
  std::random_device device;
  for (int attempt = 0; attempt < 100; ++attempt) {
    const std::filesystem::path candidate =
        std::filesystem::temp_directory_path() /
        ("ctid-" + std::to_string(::getpid()) + "-" + std::to_string(device()));
    std::error_code error;
    if (std::filesystem::create_directory(candidate, error)) {
      path_ = candidate;
      return;
    }
  }
  throw ComputationError("could not create a temporary directory under " +
                         std::filesystem::temp_directory_path().string());
}

TemporaryDirectory::~TemporaryDirectory() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

void prepare_plot_directory(const std::filesystem::path& dir,
                            const std::vector<std::string>& figures, bool force,
                            const std::string& flag) {
  std::error_code error;
  if (std::filesystem::exists(dir, error) && !std::filesystem::is_directory(dir, error)) {
    throw InvalidArgument(flag + " " + dir.string() + ": exists and is not a directory");
  }
  if (!force) {
    for (const std::string& name : figures) {
      if (std::filesystem::exists(dir / name, error)) {
        throw InvalidArgument((dir / name).string() + ": file exists; pass --force to replace it");
      }
    }
  }
  // Nothing is created yet (a refused input must leave no folder behind); the nearest folder
  // that exists must be one the folder can be made in.
  std::filesystem::path existing = std::filesystem::absolute(dir, error);
  while (!existing.empty() && !std::filesystem::exists(existing, error)) {
    if (existing == existing.parent_path()) break;
    existing = existing.parent_path();
  }
  if (!std::filesystem::is_directory(existing, error) || ::access(existing.c_str(), W_OK) != 0) {
    throw InvalidArgument(flag + " " + dir.string() + ": cannot create the directory (" +
                          existing.string() + " is not a writable folder)");
  }
}

void create_output_directory(const std::filesystem::path& dir, const std::string& flag) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) {
    throw InvalidArgument(flag + " " + dir.string() + ": cannot create the directory (" +
                          error.message() + ")");
  }
}

std::vector<std::string> model_figure_names(bool modes) {
  std::vector<std::string> names{"bode.png", "validation.png", "residuals.png"};
  if (modes) names.emplace_back("modes.png");
  return names;
}

nlohmann::json frf_json(const Frf& frf) {
  nlohmann::json frequencies = nlohmann::json::array();
  nlohmann::json real = nlohmann::json::array();
  nlohmann::json imag = nlohmann::json::array();
  nlohmann::json variance = nlohmann::json::array();
  nlohmann::json coherence = nlohmann::json::array();
  const auto nullable = [](double x) { return std::isfinite(x) ? nlohmann::json(x) : nullptr; };
  const bool coherent = frf.coherence.size() == frf.frequencies.size();
  for (Eigen::Index k = 0; k < frf.frequencies.size(); ++k) {
    frequencies.push_back(frf.frequencies(k));
    real.push_back(frf.response(k).real());
    imag.push_back(frf.response(k).imag());
    variance.push_back(nullable(frf.variance(k)));
    if (coherent) coherence.push_back(nullable(frf.coherence(k)));
  }
  nlohmann::json out = {
      {"frequencies", frequencies}, {"real", real}, {"imag", imag}, {"variance", variance}};
  // The figures shade the lines of low coherence (python/ctid/plotting.py).
  if (coherent) out["coherence"] = std::move(coherence);
  return out;
}

std::vector<std::filesystem::path> draw_model_figures(
    const std::filesystem::path& package_dir, const std::filesystem::path& dir,
    const AdditiveModel& model, const Eigen::MatrixXd& covariance, const SampledData& data,
    const Eigen::VectorXd& simulated, bool modes, const std::string& title) {
  const TemporaryDirectory work;
  const double nyquist = std::numbers::pi / data.sample_time();

  nlohmann::json frequency_input = {{"model", io::to_json(model)}};
  if (covariance.size() > 0) {
    nlohmann::json rows = nlohmann::json::array();
    for (Eigen::Index i = 0; i < covariance.rows(); ++i) {
      nlohmann::json row = nlohmann::json::array();
      for (Eigen::Index j = 0; j < covariance.cols(); ++j) row.push_back(covariance(i, j));
      rows.push_back(row);
    }
    frequency_input["covariance"] = rows;
  }
  double low = 1e-3 * nyquist;
  if (data.size() >= 16) {
    WelchOptions options;
    options.segment_length = default_segment_length(data.size());
    const Frf frf = welch_frf(data, options);
    frequency_input["frf"] = frf_json(frf);
    if (frf.frequencies.size() > 0) low = frf.frequencies(0);
  }
  frequency_input["frequency_range"] = {low, nyquist};
  const std::filesystem::path frequency_file = work.path() / "model.json";
  io::write_json(frequency_file, frequency_input);

  io::CsvTable table;
  table.source = "validation";
  table.add_column("t", data.time());
  table.add_column("u", data.input());
  table.add_column("y", data.output());
  table.add_column("y_model", simulated);
  const std::filesystem::path signals_file = work.path() / "signals.csv";
  io::write_csv(signals_file, table);

  std::vector<PlotJob> jobs{{"bode", frequency_file, dir / "bode.png", title},
                            {"validation", signals_file, dir / "validation.png", title},
                            {"residuals", signals_file, dir / "residuals.png", title}};
  if (modes) jobs.push_back({"modes", frequency_file, dir / "modes.png", title});
  plot(package_dir, jobs);
  std::vector<std::filesystem::path> written;
  for (const PlotJob& job : jobs) written.push_back(job.output);
  return written;
}

std::vector<std::string> mimo_figure_names(bool modes) {
  std::vector<std::string> names{"frf_matrix_overlay.png"};
  if (modes) {
    names.emplace_back("mode_shapes.png");
    names.emplace_back("mac.png");
  }
  return names;
}

std::vector<std::filesystem::path> draw_mimo_figures(const std::filesystem::path& package_dir,
                                                     const std::filesystem::path& dir,
                                                     const nlohmann::json& result,
                                                     const MimoData& data,
                                                     const std::string& title) {
  MimoFrf frf;
  if (data.size() >= 16) {  // as draw_model_figures: too short a record has no FRF to show
    WelchOptions options;
    options.segment_length = default_segment_length(data.size());
    frf = excited_lines(welch_frf(data, options), PeriodicFrfOptions{}.line_threshold);
  }
  return draw_mimo_figures(package_dir, dir, result, frf, title);
}

std::vector<std::filesystem::path> draw_mimo_figures(const std::filesystem::path& package_dir,
                                                     const std::filesystem::path& dir,
                                                     const nlohmann::json& result,
                                                     const MimoFrf& frf, const std::string& title) {
  const TemporaryDirectory work;
  const std::filesystem::path result_file = work.path() / "result.json";
  io::write_json(result_file, result);
  std::vector<PlotJob> jobs;
  if (frf.frequencies.size() > 0) {
    const std::filesystem::path frf_file = work.path() / "frf.json";
    io::write_json(frf_file, io::to_json(frf));
    jobs.push_back({"frf_matrix_overlay",
                    result_file,
                    dir / "frf_matrix_overlay.png",
                    title,
                    {"--frf", frf_file.string()}});
  }
  const auto modes = result.find("modes");
  if (modes != result.end() && modes->is_array() && !modes->empty()) {
    jobs.push_back({"mode_shapes", result_file, dir / "mode_shapes.png", title});
    jobs.push_back({"mac", result_file, dir / "mac.png", title});
  }
  plot(package_dir, jobs);
  std::vector<std::filesystem::path> written;
  for (const PlotJob& job : jobs) written.push_back(job.output);
  return written;
}

std::filesystem::path draw_comparison_figure(
    const std::filesystem::path& package_dir, const std::filesystem::path& dir,
    const SampledData& data, const std::vector<std::string>& labels,
    const std::vector<AdditiveModel>& models, const ValidationOptions& options,
    const std::vector<ValidationReport>& reports, const std::string& title) {
  const TemporaryDirectory work;
  const Eigen::VectorXd t = data.time();
  nlohmann::json input;
  input["t"] = std::vector<double>(t.data(), t.data() + t.size());
  input["y"] = std::vector<double>(data.output().data(), data.output().data() + data.size());
  input["window"] = {reports.front().window_start, reports.front().window_end};
  input["initial_state"] = std::string(enum_name(options.initial_state));
  nlohmann::json lines = nlohmann::json::array();
  for (std::size_t i = 0; i < models.size(); ++i) {
    const Eigen::VectorXd y = validation_output(models[i], data, options);
    lines.push_back({{"label", std::filesystem::path(labels[i]).filename().string()},
                     {"fit", reports[i].fit_percent},
                     {"output", std::vector<double>(y.data(), y.data() + y.size())}});
  }
  input["models"] = std::move(lines);
  const std::filesystem::path file = work.path() / "compare.json";
  io::write_json(file, input);
  const std::filesystem::path output = dir / "validation.png";
  plot(package_dir, {{"compare", file, output, title}});
  return output;
}

}  // namespace ctid::cli
