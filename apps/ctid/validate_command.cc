// `ctid validate`: judges a fitted model (a result or model JSON) against a data record:
// the exact ZOH response of the model to the measured input, fit %, residual mean and
// standard deviation, the whiteness test of the residual autocorrelation (lags 1-20) and the
// residual-input cross-correlation (lags -20..20), both against the 99 % band 2.58/sqrt(N).
// The numerics are ctid::validate_model and ctid::model_output (estimation/validation.h). A
// closed loop with delayed feedback (a `ctid feedback` result or a delayed_feedback_loop
// model) is simulated with the measured input continued by --hold (validate_loop,
// delayed_feedback/loop_parameters.h) and judged by the same statistics.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "command.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/delayed_feedback/loop_parameters.h"
#include "ctid/delayed_feedback/output_error.h"
#include "ctid/estimation/validation.h"
#include "ctid/io/feedback_result_json.h"
#include "ctid/io/fields_json.h"
#include "ctid/io/json.h"
#include "ctid/io/model_json.h"
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
  std::string hold = "foh";
  int substeps = OutputErrorOptions{}.substeps;
  bool force = false;
  bool quiet = false;
};

// The loop of a `ctid feedback` result or of a delayed_feedback_loop model file; nullopt for
// every other document (a continuous-time model or a `ctid fit` result).
std::optional<DelayedFeedbackLoop> loop_in(const std::string& file) {
  const nlohmann::json document = io::read_json(file);
  if (io::is_delayed_feedback_result(document)) {
    return io::delayed_feedback_result_from_json(document, file).identification.loop;
  }
  if (io::is_delayed_feedback_loop(document)) {
    return io::delayed_feedback_loop_from_json(document, file);
  }
  return std::nullopt;
}

void run_validate(const ValidateFlags& f, const CLI::App& app) {
  if (!f.output.empty() && !f.force && std::filesystem::exists(f.output)) {
    usage_error(f.output + ": file exists; pass --force to replace it (--output)");
  }
  const std::optional<DelayedFeedbackLoop> loop = loop_in(f.model);
  if (loop && !f.plot.empty()) {
    usage_error("--plot draws continuous-time models; " + f.model +
                " holds a closed loop with delayed feedback");
  }
  std::optional<io::FittedModel> fitted;
  if (!loop) fitted = io::read_fitted_model(f.model);
  const bool modes = fitted && fitted->model.size() > 1;
  std::filesystem::path package;
  if (!f.plot.empty()) {
    package = require_plotting();
    prepare_plot_directory(f.plot, model_figure_names(modes), f.force);
  }
  const SampledData data = f.data.load(app, false);
  if (fitted) {
    const double delay_samples = fitted->model.input_delay() / data.sample_time();
    if (std::abs(delay_samples - std::round(delay_samples)) > 1e-9 * std::max(1.0, delay_samples)) {
      usage_error(internal::concat("the model's input delay ",
                                   format_number(fitted->model.input_delay()),
                                   " s is not a whole number of samples of ", f.data.file,
                                   " (h = ", format_number(data.sample_time()), " s)"));
    }
  }

  const Hold hold = f.hold == "zoh" ? Hold::zero_order_hold : Hold::first_order_hold;
  const ValidationReport report = loop ? validate_loop(*loop, data, hold, f.substeps, kMaxLag)
                                       : validate_model(fitted->model, data, kMaxLag);
  const double bound = report.whiteness_bound;
  const bool white = report.residual_white();
  const bool uncorrelated = report.residual_uncorrelated_with_input();
  const double max_cross = report.max_cross_correlation;

  if (!f.output.empty()) {
    nlohmann::json document = io::to_json(report);
    document["model_file"] = f.model;
    document["data"] = {{"file", f.data.file},
                        {"samples", data.size()},
                        {"sample_time", data.sample_time()},
                        {"input_hold", enum_name(data.input_hold())},
                        {"preprocessing", io::fields_to_json(f.data.preprocessing)}};
    io::write_json(f.output, document, f.force ? io::Overwrite::yes : io::Overwrite::no);
  }
  if (!f.quiet) {
    std::cout << "ctid validate: " << f.model << " on " << f.data.file << " (N = " << data.size()
              << ", h = " << format_number(data.sample_time()) << " s)\n";
    if (f.data.preprocessing_asked(app)) {
      std::cout << "preprocessing: " << f.data.preprocessing.summary() << "\n";
    }
    std::cout << "fit: " << format_number(report.fit_percent) << " %, mean squared error "
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
    const Eigen::VectorXd simulated = model_output(fitted->model, data.input(), data.sample_time());
    const auto written = draw_model_figures(
        package, f.plot, fitted->model, fitted->covariance, data, simulated, modes,
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
      "MODEL: the result JSON of 'ctid fit' or a transfer_function / additive_model JSON, or\n"
      "a closed loop with delayed feedback: the result JSON of 'ctid feedback' or a\n"
      "delayed_feedback_loop JSON (simulated with the input continued by --hold).\n"
      "The model is simulated from rest with the measured input (exact ZOH). Tests use lags "
      "1-20 (autocorrelation) and -20..20 (cross-correlation) against 2.58/sqrt(N).\n"
      "Exit status: 0 ran (whatever the verdict), 2 bad usage or input, 1 other error.");
  app->add_option("model", f.model, "Model or result JSON")->required()->check(CLI::ExistingFile);
  f.data.add_to(*app, "data", false);
  app->add_option("--output,-o", f.output, "Report JSON to write")->group("Output");
  app->add_option("--plot", f.plot,
                  "Directory for bode.png, validation.png, residuals.png (and modes.png)")
      ->group("Output");
  app->add_option("--hold", f.hold,
                  "Delayed-feedback loops: the input between samples (zoh or foh)")
      ->check(CLI::IsMember({"zoh", "foh"}))
      ->capture_default_str();
  app->add_option("--substeps", f.substeps,
                  "Delayed-feedback loops: integration steps per sample period")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app->add_flag("--force", f.force, "Replace output files that exist")->group("Output");
  app->add_flag("--quiet,-q", f.quiet, "Print nothing")->group("Output");

  Command command;
  command.app = app;
  command.run = [flags, app] {
    run_validate(*flags, *app);
    return kExitOk;
  };
  return command;
}

}  // namespace

CTID_REGISTER_COMMAND(30, add_validate_command);

}  // namespace ctid::cli
