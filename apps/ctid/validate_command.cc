// `ctid validate`: judges a fitted model (a result or model JSON) against a data record:
// the exact ZOH response of the model to the measured input, fit %, residual mean and
// standard deviation, the whiteness test of the residual autocorrelation (lags 1-20) and the
// residual-input cross-correlation (lags -20..20), both against the 99 % band 2.58/sqrt(N).
// The numerics are ctid::validate_model and ctid::model_output (estimation/validation.h).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "command.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/estimation/validation.h"
#include "ctid/io/json.h"
#include "ctid/io/report_json.h"
#include "ctid/io/result_json.h"
#include "data_flags.h"
#include "plot_support.h"

namespace ctid::cli {
namespace {

constexpr int kMaxLag = 20;

struct ValidateFlags {
  std::string model;
  DataFlags data;
  std::string output;
  std::string plot;
  bool force = false;
  bool quiet = false;
};

void run_validate(const ValidateFlags& f, const CLI::App& app) {
  if (!f.output.empty() && !f.force && std::filesystem::exists(f.output)) {
    usage_error(f.output + ": file exists; pass --force to replace it (--output)");
  }
  const io::FittedModel fitted = io::read_fitted_model(f.model);
  const bool modes = fitted.model.size() > 1;
  std::filesystem::path package;
  if (!f.plot.empty()) {
    package = require_plotting();
    prepare_plot_directory(f.plot, model_figure_names(modes), f.force);
  }
  const SampledData data = f.data.load(app, false);
  const double delay_samples = fitted.model.input_delay() / data.sample_time();
  if (std::abs(delay_samples - std::round(delay_samples)) > 1e-9 * std::max(1.0, delay_samples)) {
    usage_error(internal::concat("the model's input delay ",
                                 format_number(fitted.model.input_delay()),
                                 " s is not a whole number of samples of ", f.data.file,
                                 " (h = ", format_number(data.sample_time()), " s)"));
  }

  const ValidationReport report = validate_model(fitted.model, data, kMaxLag);
  const Eigen::VectorXd simulated = model_output(fitted.model, data.input(), data.sample_time());
  const double bound = report.whiteness_bound;
  const bool white = report.residual_white();
  const bool uncorrelated = report.residual_uncorrelated_with_input();
  const double max_cross = report.max_cross_correlation;

  if (!f.output.empty()) {
    nlohmann::json document = io::to_json(report);
    document["model_file"] = f.model;
    document["data"] = {
        {"file", f.data.file}, {"samples", data.size()}, {"sample_time", data.sample_time()}};
    io::write_json(f.output, document, f.force ? io::Overwrite::yes : io::Overwrite::no);
  }
  if (!f.quiet) {
    std::cout << "ctid validate: " << f.model << " on " << f.data.file << " (N = " << data.size()
              << ", h = " << format_number(data.sample_time()) << " s)\n"
              << "fit: " << format_number(report.fit_percent) << " %, mean squared error "
              << format_number(report.mean_squared_error) << "\n"
              << "residual: mean " << format_number(report.residual_mean) << ", std "
              << format_number(report.residual_std) << "\n"
              << "whiteness (autocorrelation, lags 1-" << kMaxLag
              << "): max |r| = " << format_number(report.max_residual_autocorrelation)
              << " against " << format_number(bound)
              << " (99 %): " << (white ? "white" : "not white") << "\n"
              << "cross-correlation with the input (lags -" << kMaxLag << ".." << kMaxLag
              << "): max |r| = " << format_number(max_cross) << " against " << format_number(bound)
              << " (99 %): " << (uncorrelated ? "uncorrelated" : "correlated") << "\n";
  }
  if (!f.plot.empty()) {
    const auto written = draw_model_figures(
        package, f.plot, fitted.model, fitted.covariance, data, simulated, modes,
        "ctid validate on " + std::filesystem::path(f.data.file).filename().string());
    if (!f.quiet) {
      for (const auto& file : written) std::cout << "wrote " << file.string() << "\n";
    }
  }
}

Command add_validate_command(CLI::App& parent) {
  auto flags = std::make_shared<ValidateFlags>();
  ValidateFlags& f = *flags;
  CLI::App* app = parent.add_subcommand(
      "validate",
      "Judge a fitted model against a data record: fit %, residual statistics, whiteness "
      "and cross-correlation tests.");
  app->footer(
      "MODEL: the result JSON of 'ctid fit' or a transfer_function / additive_model JSON.\n"
      "The model is simulated from rest with the measured input (exact ZOH). Tests use lags "
      "1-20 (autocorrelation) and -20..20 (cross-correlation) against 2.58/sqrt(N).\n"
      "Exit status: 0 ran (whatever the verdict), 2 bad usage or input, 1 other error.");
  app->add_option("model", f.model, "Model or result JSON")->required()->check(CLI::ExistingFile);
  f.data.add_to(*app, "data", false);
  app->add_option("--output,-o", f.output, "Report JSON to write")->group("Output");
  app->add_option("--plot", f.plot,
                  "Directory for bode.png, validation.png, residuals.png (and modes.png)")
      ->group("Output");
  app->add_flag("--force", f.force, "Replace output files that exist")->group("Output");
  app->add_flag("--quiet,-q", f.quiet, "Print nothing")->group("Output");

  Command command;
  command.app = app;
  command.run = [flags, app] { run_validate(*flags, *app); };
  return command;
}

}  // namespace

CTID_REGISTER_COMMAND(30, add_validate_command);

}  // namespace ctid::cli
