// Figures for the CLI's --plot flags: runs the Python entry point
// `/usr/bin/python3 -m ctid.plot KIND INPUT OUTPUT` (docs/python.md) with PYTHONPATH set to
// the folder holding the built `ctid` package, found next to the executable (build tree
// <build>/python, or an install's lib/ctid/python) or given by $CTID_PYTHONPATH. No
// drawing here: matplotlib draws, through ctid.plotting.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "ctid/core/additive_model.h"
#include "ctid/core/mimo_data.h"
#include "ctid/core/sampled_data.h"
#include "ctid/estimation/validation.h"
#include "ctid/frequency/frf.h"
#include "ctid/frequency/mimo_frf.h"

namespace ctid::cli {

/// The folder holding the `ctid` Python package (ctid/plot.py and the _ctid extension), or
/// nullopt when none is found.
std::optional<std::filesystem::path> find_python_package();

/// Throws ComputationError, naming where it looked, unless /usr/bin/python3 and the ctid
/// package are available. Call before any work so --plot fails early.
std::filesystem::path require_plotting();

/// As require_plotting, for another use of the package: the message names `flag` (e.g.
/// --scheduler, which runs `python3 -m ctid.batch`).
std::filesystem::path require_python_package(const std::string& flag);

/// The Python interpreter the CLI runs (/usr/bin/python3).
std::string python_executable();

/// Runs `words` (python_executable() and its arguments) as a child process that shares this
/// process's streams, and returns its exit status. Throws ComputationError naming `what`
/// ("python3 -m ctid.batch") when it cannot start or is ended by a signal.
int run_python(std::vector<std::string> words, const std::string& what);

/// One figure: `python3 -m ctid.plot kind input output [--title title] [arguments...]`.
struct PlotJob {
  std::string kind;
  std::filesystem::path input;
  std::filesystem::path output;
  std::string title;
  /// Further arguments of the kind, e.g. {"--frf", FRF.json} for frf_matrix_overlay.
  std::vector<std::string> arguments = {};
};

/// Draws the figures, all at once (one Python process each, run concurrently, since the
/// interpreter's start-up dominates). Throws InvalidArgument if a figure's input was
/// rejected (exit status 2) and ComputationError otherwise, with the plotter's stderr line.
void plot(const std::filesystem::path& package_dir, const std::vector<PlotJob>& jobs);

/// Runs `/usr/bin/python3 -m module arguments...` (e.g. ctid.distributed for `ctid study
/// --scheduler`) with PYTHONPATH set to `package_dir` (find_python_package), the environment
/// otherwise inherited and stdout discarded, and waits for it. Throws InvalidArgument if it
/// exits with status 2 and ComputationError on any other failure, with `what` and the last
/// line it wrote to stderr.
void run_python_module(const std::filesystem::path& package_dir, const std::string& module,
                       const std::vector<std::string>& arguments, const std::string& what);

/// A fresh, empty directory under the system's temporary directory, removed with the object.
class TemporaryDirectory {
 public:
  TemporaryDirectory();
  ~TemporaryDirectory();
  TemporaryDirectory(const TemporaryDirectory&) = delete;
  TemporaryDirectory& operator=(const TemporaryDirectory&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// Checks an output folder (`flag` DIR, e.g. --plot) before any work: refuses (InvalidArgument)
/// a DIR that is not a folder or cannot be made, and to replace any of `figures` (file names)
/// there unless `force`. Creates nothing: plot() creates the figures' folders, and a command
/// that writes other files there calls create_output_directory first.
void prepare_plot_directory(const std::filesystem::path& dir,
                            const std::vector<std::string>& figures, bool force,
                            const std::string& flag = "--plot");

/// Creates DIR (and its parents) if missing; InvalidArgument naming `flag` if it cannot.
void create_output_directory(const std::filesystem::path& dir, const std::string& flag);

/// The figure files of a model judged on data: bode.png, validation.png, residuals.png and,
/// with `modes`, modes.png.
std::vector<std::string> model_figure_names(bool modes);

/// The FRF as the "frf" object of the ctid.plot JSON input (with its coherence, if known).
nlohmann::json frf_json(const Frf& frf);

/// Draws model_figure_names(modes) into `dir`: the model over the Welch H1 FRF of `data`
/// with the confidence band of `covariance` (of model.parameters(); may be empty), the
/// measured against the simulated output `simulated`, the residual correlations, and the
/// separate modes. Returns the files written.
std::vector<std::filesystem::path> draw_model_figures(
    const std::filesystem::path& package_dir, const std::filesystem::path& dir,
    const AdditiveModel& model, const Eigen::MatrixXd& covariance, const SampledData& data,
    const Eigen::VectorXd& simulated, bool modes, const std::string& title);

/// The figure files of a fit with several inputs and outputs: frf_matrix_overlay.png and,
/// with `modes`, mode_shapes.png and mac.png.
std::vector<std::string> mimo_figure_names(bool modes);

/// Draws mimo_figure_names into `dir` from `result` (a mimo_estimation_result document with
/// the channels' names under "data"): the modes' shapes and their MAC matrix when the result
/// has modes, and the model over the Welch H1 FRF matrix of `data` (default segments, the
/// excited lines) for the channels with the largest response. Returns the files written.
std::vector<std::filesystem::path> draw_mimo_figures(const std::filesystem::path& package_dir,
                                                     const std::filesystem::path& dir,
                                                     const nlohmann::json& result,
                                                     const MimoData& data,
                                                     const std::string& title);
/// The same figures over a measured FRF matrix `frf` (e.g. the one ctid fit-frf fitted): the
/// overlay only when it has lines.
std::vector<std::filesystem::path> draw_mimo_figures(const std::filesystem::path& package_dir,
                                                     const std::filesystem::path& dir,
                                                     const nlohmann::json& result,
                                                     const MimoFrf& frf, const std::string& title);

/// Draws `dir`/validation.png: the measured output of `data` with each model's output
/// (validation_output with `options`) over it, labelled by its file name and fit on the window
/// (reports[i].fit_percent), like MATLAB's `compare`. Returns the file written.
std::filesystem::path draw_comparison_figure(
    const std::filesystem::path& package_dir, const std::filesystem::path& dir,
    const SampledData& data, const std::vector<std::string>& labels,
    const std::vector<AdditiveModel>& models, const ValidationOptions& options,
    const std::vector<ValidationReport>& reports, const std::string& title);

}  // namespace ctid::cli
