// `ctid fit-frf`: a modal model with poles shared by every channel fitted to a measured FRF
// matrix (identify(MimoFrf, ...), identification/frf_matrix.h, which runs frf_matrix_fit), for
// users with an analyser's FRF and no time records.
// Reads the CSV table `ctid frf -o X.csv` writes or a universal file (dataset 58), prints the
// mode table, every channel's fit and the verdict like `ctid fit` with several inputs and
// outputs, and writes an frf_matrix_fit_result document. No numerics here.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "command.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/identification/frf_matrix.h"
#include "ctid/io/documents.h"
#include "ctid/io/json.h"
#include "ctid/io/mimo_frf_file.h"
#include "ctid/io/model_json.h"
#include "ctid/io/provenance.h"
#include "ctid/io/report_json.h"
#include "field_flags.h"
#include "plot_support.h"
#include "progress.h"

namespace ctid::cli {
namespace {

struct FitFrfFlags {
  std::string file;
  int modes = 0;
  std::vector<std::string> submodels;  // N,M
  FrfMatrixFitOptions options;         ///< every field a flag (field_flags.h) but the band's
  std::string band;                    // LO:HI [Hz]: min_frequency, max_frequency
  std::string initial;
  std::string output;
  std::string plot;  // DIR
  bool force = false;
  bool quiet = false;
};

std::vector<SubmodelOrder> orders_of(const FitFrfFlags& f, const CLI::App& app) {
  const bool modes = app.count("--modes") > 0;
  const bool submodels = !f.submodels.empty();
  if (modes == submodels) {
    usage_error(
        "give the structure: --modes K (K modes b0 + b1 s over 1 + a1 s + a2 s^2) or "
        "--submodel N,M repeated");
  }
  if (modes) {
    if (f.modes < 1) usage_error("--modes must be at least 1, not " + std::to_string(f.modes));
    return std::vector<SubmodelOrder>(static_cast<std::size_t>(f.modes), SubmodelOrder{2, 1, 0});
  }
  std::vector<SubmodelOrder> orders;
  for (const std::string& text : f.submodels) {
    const auto comma = text.find(',');
    const std::optional<int> n = parse_number<int>(text.substr(0, comma));
    const std::optional<int> m =
        comma == std::string::npos ? std::nullopt : parse_number<int>(text.substr(comma + 1));
    if (!n || !m || *n < 0 || *m < 0) {
      usage_error("--submodel '" + text + "': expected N,M (poles, zeros), e.g. 2,1");
    }
    orders.push_back(SubmodelOrder{*n, *m, 0});
  }
  return orders;
}

// "LO:HI" in Hz (either side may be empty) as [min, max] in rad/s (max 0: no limit).
std::pair<double, double> band_of(const std::string& text) {
  if (text.empty()) return {0.0, 0.0};
  const auto colon = text.find(':');
  if (colon == std::string::npos) usage_error("--band '" + text + "': expected LO:HI in Hz");
  const std::string lo = text.substr(0, colon);
  const std::string hi = text.substr(colon + 1);
  const std::optional<double> a =
      lo.empty() ? std::optional<double>(0.0) : parse_number<double>(lo);
  const std::optional<double> b =
      hi.empty() ? std::optional<double>(0.0) : parse_number<double>(hi);
  if (!a || !b || *a < 0.0 || *b < 0.0 || (*b > 0.0 && *a >= *b)) {
    usage_error("--band '" + text + "': expected LO:HI in Hz with 0 <= LO < HI (e.g. 20:220)");
  }
  return {2.0 * std::numbers::pi * *a, 2.0 * std::numbers::pi * *b};
}

// The starting model in a mimo_additive_model file, or the model of a mimo_estimation_result
// (ctid fit --input-columns ... -o) or frf_matrix_fit_result (ctid fit-frf -o) document.
MimoAdditiveModel initial_model(const std::string& path) {
  const nlohmann::json value = io::read_json(path);
  if (value.is_object() && value.value("type", "") == io::kMimoAdditiveModelType) {
    return io::mimo_additive_model_from_json(value, path);
  }
  const io::ResultDocument document = io::result_from_json(value, path);
  std::optional<MimoAdditiveModel> model;
  if (const auto* r = std::get_if<MimoEstimationResult>(&document)) model = r->model;
  if (const auto* r = std::get_if<FrfMatrixFitResult>(&document)) model = r->model;
  if (!model) {
    usage_error("--initial " + path + " holds a " + std::string(io::document_type(document)) +
                " without a model of several inputs and outputs; give a mimo_additive_model, a "
                "mimo_estimation_result or an frf_matrix_fit_result");
  }
  return *model;
}

ExitStatus run_fit_frf(const FitFrfFlags& f, const CLI::App& app) {
  const std::vector<SubmodelOrder> orders = orders_of(f, app);
  FrfIdentificationOptions options;
  FrfMatrixFitOptions& fit = options.frf_fit;
  fit = f.options;
  std::tie(fit.min_frequency, fit.max_frequency) = band_of(f.band);
  fit.validate();  // named as FrfMatrixFitOptions, before the FRF is read
  std::filesystem::path package;
  if (!f.plot.empty()) {
    package = require_plotting();
    const bool modes =
        std::any_of(orders.begin(), orders.end(), [](const SubmodelOrder& o) { return o.n == 2; });
    prepare_plot_directory(f.plot, mimo_figure_names(modes), f.force);
  }
  const MimoFrf frf = io::read_mimo_frf(f.file);
  if (!f.initial.empty()) options.initial_model = initial_model(f.initial);
  // Vector fitting and Levenberg-Marquardt on a large FRF matrix take seconds: one progress
  // line counts both (against the most they may run; a converging fit stops sooner).
  Progress progress("ctid fit-frf", f.quiet);
  const FrfMatrixFitResult result = identify(frf, orders, options, progress.callback("step"));
  progress.clear();

  nlohmann::json document = io::to_json(result);
  document["data"] =
      io::to_json(io::DataProvenance{.files = {f.file},
                                     .lines = static_cast<long long>(frf.frequencies.size()),
                                     .inputs = frf.input_names,
                                     .outputs = frf.output_names});
  if (!f.output.empty()) {
    io::write_json(f.output, document, f.force ? io::Overwrite::yes : io::Overwrite::no);
  }
  if (!f.quiet) {
    if (!result.verdict.usable) std::cout << "WARNING: " << result.verdict.summary() << "\n";
    const double hz = 1.0 / (2.0 * std::numbers::pi);
    std::cout << "ctid fit-frf: " << result.message << "\n"
              << f.file << ": " << result.lines << " lines fitted";
    if (result.lines > 0 && !f.band.empty()) std::cout << " (band " << f.band << " Hz)";
    std::cout << ", " << frf.input_count() << " inputs x " << frf.output_count() << " outputs\n";
    const bool errors =
        !result.modes.empty() && std::isfinite(result.modes.front().natural_frequency_se);
    std::cout << (errors ? "modes (± one standard error):\n" : "modes:\n");
    for (std::size_t i = 0; i < result.modes.size(); ++i) {
      const MimoMode& m = result.modes[i];
      std::cout << "  mode " << i + 1  // modes counted from 1, whatever submodels precede
                << ": f_n = " << plus_minus(m.natural_frequency * hz, m.natural_frequency_se * hz)
                << " Hz, zeta = " << plus_minus(m.damping_ratio, m.damping_ratio_se)
                << ", rank-one share " << format_brief(m.rank_one_share) << "\n";
    }
    for (int j = 0; j < result.fit_percent.rows(); ++j) {  // none when the fit did not run
      std::cout << "  fit " << frf.output_names[static_cast<std::size_t>(j)] << ":";
      for (int k = 0; k < result.fit_percent.cols(); ++k) {
        std::cout << " " << format_brief(result.fit_percent(j, k)) << " % ("
                  << frf.input_names[static_cast<std::size_t>(k)] << ")";
      }
      std::cout << "\n";
    }
  } else if (!result.verdict.usable) {
    std::cerr << "ctid fit-frf: WARNING: " << result.verdict.summary() << "\n";
  }
  if (!f.plot.empty() && result.model) {
    const auto written =
        draw_mimo_figures(package, f.plot, document, frf,
                          "ctid fit-frf on " + std::filesystem::path(f.file).filename().string());
    if (!f.quiet) {
      for (const auto& file : written) std::cout << "wrote " << file.string() << "\n";
    }
  }
  return result.verdict.usable ? kExitOk : kExitNoUsableModel;
}

Command add_fit_frf_command(CLI::App& parent) {
  auto flags = std::make_shared<FitFrfFlags>();
  FitFrfFlags& f = *flags;
  CLI::App* app = parent.add_subcommand(
      "fit-frf",
      "Fit a modal model with poles shared by every channel to a measured FRF matrix (CSV or "
      "universal file dataset 58) and write the result as JSON.");
  app->footer(
      "Input: the CSV table 'ctid frf --input-columns ... -o X.csv' writes (frequency, "
      "<output>/<input>_real, _imag[, _variance]), or a universal file (.uff, .unv: ASCII "
      "dataset 58, FRF records, abscissa in Hz) - docs/frf-fit.md.\n"
      "Structure: --modes K (K modes (b0 + b1 s) / (1 + a1 s + a2 s^2), general complex "
      "residues) or --submodel N,M repeated (N = 1 or 2); --direct adds D (accelerances).\n"
      "Method: vector fitting for the shared poles, numerators by least squares, then "
      "Levenberg-Marquardt on all parameters (docs/decisions/0019-frf-matrix-fit.md).\n"
      "Exit status: 0 ran and the model passed the quality verdict, 3 ran but no usable model "
      "(a WARNING line says why; outputs are still written), 2 bad usage or input, 1 other "
      "error.");
  app->add_option("frf", f.file, "FRF matrix: CSV table or universal file (.uff/.unv)")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--modes", f.modes, "K second-order modes (--submodel 2,1 K times)")
      ->group("Structure");
  app->add_option("--submodel", f.submodels, "One submodel N,M (poles 1 or 2, zeros); repeat")
      ->take_all()
      ->allow_extra_args(false)
      ->group("Structure");
  app->add_option(flag_of<FrfMatrixFitOptions>("min_frequency"), f.band,
                  "Fit only the lines in LO:HI Hz (either side may be empty)")
      ->group("Fit");
  app->add_option("--initial", f.initial,
                  "Start from this model instead of vector fitting: a mimo_additive_model, or "
                  "the model of a mimo_estimation_result (ctid fit -o) or frf_matrix_fit_result")
      ->check(CLI::ExistingFile)
      ->group("Fit");
  FieldFlagSettings settings;
  settings.group = "Fit";
  settings.by_hand = {"min_frequency", "max_frequency"};  // --band LO:HI in Hz, above
  add_field_flags(*app, f.options, settings);
  app->add_option("--output,-o", f.output, "Result JSON to write (frf_matrix_fit_result)")
      ->group("Output");
  app->add_option("--plot", f.plot,
                  "Draw the figures into DIR (frf_matrix_overlay.png: the model over the fitted "
                  "FRF; mode_shapes.png, mac.png) with python3 -m ctid.plot")
      ->group("Output");
  app->add_flag("--force", f.force, "Replace an output file that exists")->group("Output");
  app->add_flag("--quiet,-q", f.quiet, "Print no summary")->group("Output");

  Command command;
  command.app = app;
  command.run = [flags, app] { return run_fit_frf(*flags, *app); };
  return command;
}

}  // namespace

CTID_REGISTER_COMMAND(22, add_fit_frf_command);

}  // namespace ctid::cli
