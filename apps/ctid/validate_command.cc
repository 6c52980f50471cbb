// `ctid validate`: judges a fitted model (a result or model JSON) against a data record:
// the exact ZOH response of the model to the measured input, fit %, residual mean and
// standard deviation, the whiteness test of the residual autocorrelation (lags 1-20) and the
// residual-input cross-correlation (lags -20..20), both against the 99 % band 2.58/sqrt(N).
// The numerics are ctid::validate_model and ctid::model_output (estimation/validation.h). A
// closed loop with delayed feedback (a `ctid feedback` result or a delayed_feedback_loop
// model) is simulated with the measured input continued by --hold (validate_model's loop
// overload, identification/feedback_loop.h) and judged by the same statistics.
// --initial-state estimate starts the simulation from the least-squares initial state and
// --window A:B scores part of the record (simulated from its start); both fits, from rest and
// from the estimated state, are printed beside each other, one row per model when several
// models are compared on the same record (MATLAB's `compare`).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "command.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/core/preprocessing.h"
#include "ctid/estimation/prediction.h"
#include "ctid/estimation/validation.h"
#include "ctid/identification/feedback_loop.h"
#include "ctid/identification/irregular_validation.h"
#include "ctid/io/feedback_result_json.h"
#include "ctid/io/fields_json.h"
#include "ctid/io/json.h"
#include "ctid/io/model_json.h"
#include "ctid/io/provenance.h"
#include "ctid/io/report_json.h"
#include "ctid/io/result_json.h"
#include "ctid/simulation/stamps.h"
#include "data_flags.h"
#include "field_flags.h"
#include "plot_support.h"

namespace ctid::cli {
namespace {

struct ValidateFlags {
  std::string model;
  std::vector<std::string> more_models;
  DataFlags data;
  // Every field a flag (field_flags.h); --window START:END gives window_start and window_end
  // at once.
  ValidationOptions options;
  std::string window;
  std::string output;
  std::string plot;
  std::string hold = "foh";
  int substeps = OutputErrorOptions{}.substeps;
  bool irregular = false;  ///< judge the model on the record's time stamps as logged (0053)
  int horizon = 0;         ///< k-step-ahead prediction with the result's noise model; 0: none
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

// "A:B", "A:" or ":B" (seconds on the record's time axis) into the options' window.
void parse_window(const std::string& text, ValidationOptions& options) {
  const auto colon = text.find(':');
  const auto bad = [&] {
    usage_error("--window '" + text + "': expected START:END in seconds (either may be empty)");
  };
  if (colon == std::string::npos || text.find(':', colon + 1) != std::string::npos) bad();
  const auto number = [&](const std::string& part) -> std::optional<double> {
    if (part.empty()) return std::nullopt;
    const std::optional<double> value = parse_number<double>(part);
    if (!value || !std::isfinite(*value)) bad();
    return value;
  };
  options.window_start = number(text.substr(0, colon));
  options.window_end = number(text.substr(colon + 1));
  if (options.window_start && options.window_end &&
      !(*options.window_end > *options.window_start)) {
    usage_error("--window '" + text + "': the end must be later than the start");
  }
}

// The summary in the output's own unit (RMS error beside the fit), six significant digits
// like ctid fit's; every digit is in the --output document.
void print_statistics(const ValidationReport& report) {
  const double bound = report.whiteness_bound;
  std::cout << "fit: " << format_fixed(report.fit_percent, 2) << " %, RMS error "
            << format_brief(std::sqrt(report.mean_squared_error))
            << " (output units), mean squared error " << format_brief(report.mean_squared_error)
            << "\n"
            << "residual: mean " << format_brief(report.residual_mean) << ", std "
            << format_brief(report.residual_std) << "\n"
            << "whiteness (autocorrelation, lags 1-" << report.max_lag
            << "): max |r| = " << format_brief(report.max_residual_autocorrelation) << " against "
            << format_brief(bound)
            << " (99 %): " << (report.residual_white() ? "white" : "not white") << "\n"
            << "cross-correlation with the input (lags -" << report.max_lag << ".."
            << report.max_lag << "): max |r| = " << format_brief(report.max_cross_correlation)
            << " against " << format_brief(bound) << " (99 %): "
            << (report.residual_uncorrelated_with_input() ? "uncorrelated" : "correlated") << "\n";
}

std::string percent(double fit) { return format_fixed(fit, 2) + " %"; }

std::string padded(const std::string& text, std::size_t width) {
  return text.size() >= width ? text + " " : text + std::string(width - text.size(), ' ');
}

// One row per model: the fit from rest and from the estimated state, beside each other.
void print_table(const std::vector<std::string>& names,
                 const std::vector<ValidationReport>& reports) {
  std::size_t width = 5;
  for (const auto& name : names) width = std::max(width, name.size() + 2);
  std::cout << padded("model", width) << padded("fit zero state", 17)
            << padded("fit estimated state", 22) << "window\n";
  for (std::size_t i = 0; i < names.size(); ++i) {
    const ValidationReport& r = reports[i];
    std::cout << padded(names[i], width) << padded(percent(r.fit_zero_state), 17)
              << padded(percent(r.fit_estimated_state), 22) << format_number(r.window_start)
              << " to " << format_number(r.window_end) << " s (" << r.window_samples
              << " samples)\n";
  }
}

// --detrend fit: the record minus the trend the estimation record's preprocessing removed
// (its offsets and slopes, scaled as this record is), so a model fitted to detrended data is
// judged at its own operating point. The record's preprocessing entry then names that trend.
SampledData without_fit_trend(const ValidateFlags& f, const std::vector<std::string>& files,
                              bool loop, const SampledData& data) {
  if (loop) {
    usage_error("--detrend fit takes the trend of a ctid fit result; " + f.model +
                " holds a closed loop with delayed feedback");
  }
  const std::optional<PreprocessingRecord> trend = io::fit_preprocessing(files.front());
  if (!trend) {
    usage_error("--detrend fit takes the trend from the fit's record, but " + f.model +
                " holds no preprocessing record (a plain model file, or a result written "
                "before version 1 documents carried it); give --detrend mean or none");
  }
  for (std::size_t i = 1; i < files.size(); ++i) {
    const std::optional<PreprocessingRecord> other = io::fit_preprocessing(files[i]);
    if (!other || other->input_offset != trend->input_offset ||
        other->output_offset != trend->output_offset || other->input_slope != trend->input_slope ||
        other->output_slope != trend->output_slope) {
      usage_error("--detrend fit: " + f.more_models[i - 1] +
                  " was fitted with another trend than " + f.model +
                  "; compare models with --detrend fit only when they share it");
    }
  }
  PreprocessingRecord& record = f.data.preprocessing;
  if (trend->input_scale != record.input_scale || trend->output_scale != record.output_scale) {
    usage_error(internal::concat("--detrend fit: the fit scaled u by ", trend->input_scale,
                                 " and y by ", trend->output_scale, ", this record by ",
                                 record.input_scale, " and ", record.output_scale,
                                 "; give the fit's --scale-input and --scale-output"));
  }
  PreprocessingRecord scaled = *trend;
  scaled.input_offset *= record.input_scale;
  scaled.input_slope *= record.input_scale;
  scaled.output_offset *= record.output_scale;
  scaled.output_slope *= record.output_scale;
  scaled.reference_offset *= record.output_scale;
  scaled.reference_slope *= record.output_scale;
  record.detrend = trend->detrend;
  record.input_offset = trend->input_offset;
  record.input_slope = trend->input_slope;
  record.output_offset = trend->output_offset;
  record.output_slope = trend->output_slope;
  record.reference_offset = trend->reference_offset;
  record.reference_slope = trend->reference_slope;
  return remove_trend(data, scaled);
}

// A window outside the record is the user's input: the validation's refusal with the file
// and the flag that set the window.
[[noreturn]] void window_error(const ValidateFlags& f, const InvalidArgument& error) {
  usage_error(
      f.data.file + ": " + error.what() + " (" +
      (f.window.empty() ? std::string("--window-start/--window-end") : "--window " + f.window) +
      ")");
}

// The model of a document with several inputs or outputs: a `ctid fit --input-columns`
// result or a mimo_additive_model file; nullopt for every other document.
std::optional<MimoAdditiveModel> mimo_model_in(const std::string& file) {
  const nlohmann::json document = io::read_json(file);
  const auto type = document.is_object() ? document.find("type") : document.end();
  if (type == document.end() || !type->is_string()) return std::nullopt;
  if (*type == io::kMimoEstimationResultType) {
    const auto model = document.find("model");
    if (model == document.end() || model->is_null()) {
      usage_error(file + ": the result holds no model (its fit computed none)");
    }
    return io::mimo_additive_model_from_json(*model, file + ": model");
  }
  if (*type == io::kMimoAdditiveModelType) return io::mimo_additive_model_from_json(document, file);
  return std::nullopt;
}

// One row per output: the fits from rest and from the estimated state and the residual tests.
void print_mimo_table(const MimoData& data, const MimoValidationReport& report, int max_lag) {
  std::size_t width = 6;
  for (const std::string& name : data.output_names()) width = std::max(width, name.size() + 2);
  std::cout << padded("output", width) << padded("fit zero state", 17)
            << padded("fit estimated state", 22) << padded("max |r_ee|", 12) << "max |r_eu|\n";
  for (int j = 0; j < data.output_count(); ++j) {
    std::cout << padded(data.output_names()[static_cast<std::size_t>(j)], width)
              << padded(percent(report.fit_zero_state(j)), 17)
              << padded(percent(report.fit_estimated_state(j)), 22)
              << padded(format_brief(report.max_residual_autocorrelation(j)), 12)
              << format_brief(report.max_cross_correlation(j)) << "\n";
  }
  std::cout << "residual tests: lags 1-" << max_lag << " (whiteness) and -" << max_lag << ".."
            << max_lag << " over every input (cross-correlation) against "
            << format_brief(report.whiteness_bound) << " (99 %)\n";
}

// A model with several inputs or outputs against a record of as many columns
// (--input-columns, --output-columns): validate_model(MimoAdditiveModel, MimoData), output by
// output.
void run_validate_mimo(const ValidateFlags& f, const CLI::App& app, const MimoAdditiveModel& model,
                       const ValidationOptions& options, bool several, bool windowed) {
  const std::string channels = std::to_string(model.inputs()) + " input(s) and " +
                               std::to_string(model.outputs()) + " output(s)";
  if (several) usage_error(f.model + " has " + channels + "; it is validated alone");
  if (!f.plot.empty()) {
    usage_error("--plot draws models of one input and one output; " + f.model + " has " + channels);
  }
  if (f.data.detrend == "fit") {
    usage_error("--detrend fit takes the trend of a one-channel fit; " + f.model + " has " +
                channels + " (give --detrend mean, linear or none)");
  }
  if (!f.data.mimo_asked(app)) {
    usage_error(f.model + " has " + channels +
                ": name the record's columns with --input-columns and --output-columns");
  }
  const MimoData data = f.data.load_mimo(app);
  if (data.input_count() != model.inputs() || data.output_count() != model.outputs()) {
    usage_error(internal::concat(f.model, " has ", channels, "; ", f.data.file, " gives ",
                                 data.input_count(), " input column(s) and ", data.output_count(),
                                 " output column(s)"));
  }
  MimoValidationReport report;
  try {
    report = validate_model(model, data, options);
  } catch (const InvalidArgument& error) {
    if (!windowed) throw;
    window_error(f, error);
  }
  if (!f.output.empty()) {
    nlohmann::json document = io::fields_to_json(report);
    document["type"] = "mimo_validation_report";
    document["model_file"] = f.model;
    document["data"] = io::to_json(io::DataProvenance{.files = {f.data.file},
                                                      .samples = data.size(),
                                                      .sample_time = data.sample_time(),
                                                      .inputs = data.input_names(),
                                                      .outputs = data.output_names(),
                                                      .input_hold = data.input_hold()});
    io::write_json(f.output, document, f.force ? io::Overwrite::yes : io::Overwrite::no);
  }
  if (f.quiet) return;
  std::cout << "ctid validate: " << f.model << " (" << channels << ") on " << f.data.file
            << " (N = " << data.size() << ", h = " << format_number(data.sample_time())
            << " s), scored " << format_number(report.window_start) << " to "
            << format_number(report.window_end) << " s (" << report.window_samples << " samples)\n";
  std::cout << "initial state: " << enum_name(options.initial_state)
            << " (residual statistics below)\n";
  print_mimo_table(data, report, options.max_lag);
  if (!f.output.empty()) std::cout << "wrote " << f.output << "\n";
}

// What --irregular does not take, each refused naming the flag (decision 0053).
void check_validate_irregular_flags(const ValidateFlags& f, const CLI::App& app, bool several) {
  const std::string why =
      " does not go with --irregular (a SISO model simulated from rest at the record's time "
      "stamps; docs/decisions/0053)";
  if (several) usage_error("several models" + why);
  if (f.data.mimo_asked(app)) usage_error("--input-columns / --output-columns" + why);
  for (const char* flag : {"--plot", "--hold", "--substeps"}) {
    if (app.count(flag) > 0) usage_error(std::string(flag) + why);
  }
  if (f.options.initial_state == InitialState::estimate) {
    usage_error("--initial-state estimate" + why);
  }
  if (f.data.detrend == "fit") usage_error("--detrend fit" + why);
  if (mimo_model_in(f.model))
    usage_error(f.model + " has several inputs or outputs;" + why.substr(1));
  if (loop_in(f.model)) {
    usage_error(f.model + " holds a closed loop with delayed feedback;" + why.substr(1));
  }
}

// --irregular: validate_model on the stamps as logged (identification/irregular_validation.h).
void run_validate_irregular(const ValidateFlags& f, const CLI::App& app,
                            const ValidationOptions& options, bool windowed) {
  const io::FittedModel fitted = io::read_fitted_model(f.model);
  const IrregularRecord record = f.data.load_irregular(app);
  ValidationReport report;
  try {
    report = validate_model(fitted.model, record, options);
  } catch (const InvalidArgument& error) {
    if (!windowed) throw;
    window_error(f, error);
  }
  const auto samples = static_cast<int>(record.time.size());
  const double median = record.median_step();
  const int duplicates = duplicate_stamps(record.time);
  if (!f.output.empty()) {
    nlohmann::json document = io::to_json(report);
    document["model_file"] = f.model;
    document["data"] = io::to_json(io::DataProvenance{.files = {f.data.file},
                                                      .samples = samples,
                                                      .sample_time = median,
                                                      .input_hold = record.input_hold,
                                                      .duplicate_stamps = duplicates,
                                                      .detrend = f.data.detrend});
    io::write_json(f.output, document, f.force ? io::Overwrite::yes : io::Overwrite::no);
  }
  if (f.quiet) return;
  std::cout << "ctid validate: " << f.model << " on " << f.data.file << " (N = " << samples
            << ", irregular time stamps, " << duplicates << " duplicate"
            << (duplicates == 1 ? "" : "s") << ", steps " << format_brief(median)
            << " s median, input " << enum_name(record.input_hold) << ")\n"
            << "initial state: zero; scored " << format_number(report.window_start) << " to "
            << format_number(report.window_end) << " s (" << report.window_samples
            << " stamps); correlation lags count samples, not time\n";
  print_statistics(report);
  if (!f.output.empty()) std::cout << "wrote " << f.output << "\n";
}

void print_prediction(const PredictionReport& p, const ArmaModel& noise) {
  std::cout << p.horizon << "-step-ahead prediction (noise model ARMA(" << noise.ar_order() << ", "
            << noise.ma_order() << ")): fit " << format_fixed(p.fit_percent, 2) << " %, RMS error "
            << format_brief(std::sqrt(p.mean_squared_error)) << " (simulation: fit "
            << format_fixed(p.simulation_fit_percent, 2) << " %)\n";
}

void run_validate(const ValidateFlags& f, const CLI::App& app) {
  std::vector<std::string> files{f.model};
  files.insert(files.end(), f.more_models.begin(), f.more_models.end());
  const bool several = files.size() > 1;
  if (several && !f.output.empty()) {
    usage_error("--output writes the report of one model; " + std::to_string(files.size()) +
                " models were given");
  }
  ValidationOptions options = f.options;
  if (!f.window.empty()) {
    if (options.window_start || options.window_end) {
      usage_error("give --window START:END or --window-start/--window-end, not both");
    }
    parse_window(f.window, options);
  }
  const bool windowed = options.window_start || options.window_end;
  options.validate();  // named by its flags, before anything is read
  if (f.horizon > 0 && (several || f.irregular || f.data.mimo_asked(app))) {
    usage_error(
        "--horizon predicts one model's output on one regularly sampled record; give one "
        "result file, without --irregular or several columns");
  }
  if (f.horizon > 0 && (windowed || options.initial_state == InitialState::estimate)) {
    usage_error(
        "--horizon scores the prediction on the whole record from rest; it does not take "
        "--window or --initial-state estimate");
  }
  if (f.irregular) {
    check_validate_irregular_flags(f, app, several);
    run_validate_irregular(f, app, options, windowed);
    return;
  }

  if (const std::optional<MimoAdditiveModel> mimo = mimo_model_in(f.model)) {
    run_validate_mimo(f, app, *mimo, options, several, windowed);
    return;
  }
  if (f.data.mimo_asked(app)) {
    usage_error(
        "--input-columns / --output-columns validate a model of several inputs or "
        "outputs; " +
        f.model +
        " has one input and one output (use --input-column and "
        "--output-column)");
  }
  const std::optional<DelayedFeedbackLoop> loop = loop_in(f.model);
  if (loop && f.horizon > 0) {
    usage_error("--horizon predicts with a noise model; " + f.model +
                " holds a closed loop with delayed feedback");
  }
  if (loop) {
    if (several) {
      usage_error(f.model + " holds a closed loop with delayed feedback; it is validated alone");
    }
    if (!f.plot.empty()) {
      usage_error("--plot draws continuous-time models; " + f.model +
                  " holds a closed loop with delayed feedback");
    }
    if (options.initial_state == InitialState::estimate || windowed) {
      usage_error("--initial-state estimate and --window apply to continuous-time models; " +
                  f.model + " holds a closed loop with delayed feedback");
    }
  }
  std::vector<io::FittedModel> fitted;
  if (!loop) {
    for (const auto& file : files) {
      if (several && loop_in(file)) {
        usage_error(file + " holds a closed loop with delayed feedback; it is validated alone");
      }
      fitted.push_back(io::read_fitted_model(file));
    }
  }
  if (f.horizon > 0 && !fitted.front().noise_model) {
    usage_error("--horizon predicts with a noise model; " + f.model +
                " has none (fit with --noise-model P,Q or auto and -o RESULT.json, then "
                "validate RESULT.json)");
  }
  const bool modes = !several && !fitted.empty() && fitted.front().model.size() > 1;
  std::filesystem::path package;
  if (!f.plot.empty()) {
    package = require_plotting();
    prepare_plot_directory(
        f.plot, several ? std::vector<std::string>{"validation.png"} : model_figure_names(modes),
        f.force);
  }
  SampledData data = f.data.load(app, false);
  if (f.data.detrend == "fit") data = without_fit_trend(f, files, loop.has_value(), data);

  std::vector<ValidationReport> reports;
  try {
    if (loop) {
      const Hold hold = f.hold == "zoh" ? Hold::zero_order_hold : Hold::first_order_hold;
      reports.push_back(validate_model(*loop, data, hold, f.substeps, options.max_lag));
    } else {
      for (const auto& each : fitted) reports.push_back(validate_model(each.model, data, options));
    }
  } catch (const InvalidArgument& error) {
    if (!windowed) throw;
    window_error(f, error);
  }

  std::optional<PredictionReport> predicted;
  if (f.horizon > 0) {
    predicted = predict_ahead(fitted.front().model, *fitted.front().noise_model, data, f.horizon);
  }
  if (!f.output.empty()) {
    nlohmann::json document = io::to_json(reports.front());
    if (predicted) {
      document["prediction"] = io::fields_to_json(*predicted);
      document["prediction"].erase("prediction");  // the series is the plot's, not the report's
    }
    document["model_file"] = f.model;
    document["data"] = io::to_json(io::DataProvenance{.files = {f.data.file},
                                                      .samples = data.size(),
                                                      .sample_time = data.sample_time(),
                                                      .input_hold = data.input_hold(),
                                                      .preprocessing = f.data.preprocessing});
    io::write_json(f.output, document, f.force ? io::Overwrite::yes : io::Overwrite::no);
  }
  if (!f.quiet) {
    std::cout << "ctid validate: " << (several ? std::to_string(files.size()) + " models" : f.model)
              << " on " << f.data.file << " (N = " << data.size()
              << ", h = " << format_number(data.sample_time()) << " s)\n";
    if (f.data.preprocessing_asked(app)) {
      std::cout << "preprocessing: " << f.data.preprocessing.summary() << "\n";
    }
    if (!loop) {
      std::cout << "initial state: " << enum_name(options.initial_state)
                << " (residual statistics below)\n";
      print_table(files, reports);
    }
    for (std::size_t i = 0; i < reports.size(); ++i) {
      if (several) std::cout << files[i] << ":\n";
      print_statistics(reports[i]);
    }
    if (predicted) print_prediction(*predicted, *fitted.front().noise_model);
  }
  if (!f.plot.empty()) {
    const std::string title =
        "ctid validate on " + std::filesystem::path(f.data.file).filename().string();
    std::vector<std::filesystem::path> written;
    if (several) {
      std::vector<AdditiveModel> models;
      for (const auto& each : fitted) models.push_back(each.model);
      written.push_back(
          draw_comparison_figure(package, f.plot, data, files, models, options, reports, title));
    } else {
      const Eigen::VectorXd simulated = validation_output(fitted.front().model, data, options);
      written = draw_model_figures(package, f.plot, fitted.front().model, fitted.front().covariance,
                                   data, simulated, modes, title);
    }
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
      "A model of several inputs or outputs ('ctid fit --input-columns' result or a\n"
      "mimo_additive_model JSON) is judged output by output on the columns of --input-columns\n"
      "and --output-columns.\n"
      "MODEL2...: more models compared on the same record (one table row each; --plot draws\n"
      "them all over the measured output in validation.png).\n"
      "The model is simulated from the record's first sample with the measured input (exact\n"
      "ZOH), from rest or from the least-squares initial state (--initial-state), and scored\n"
      "on --window; the fits from rest and from the estimated state are printed side by side.\n"
      "Tests use lags 1-20 (autocorrelation) and -20..20 (cross-correlation) against\n"
      "2.58/sqrt(N), N the samples scored.\n"
      "--detrend fit removes the fit's trend (the offsets and slopes its record's --detrend\n"
      "removed, from the result document) instead of this record's own, so a model fitted\n"
      "to detrended data is judged at the operating point it was fitted at.\n"
      "Exit status: 0 ran (whatever the verdict), 2 bad usage or input, 1 other error.");
  app->add_option("model", f.model, "Model or result JSON")->required()->check(CLI::ExistingFile);
  f.data.detrend_fit = true;
  f.data.add_to(*app, "data", false);
  f.data.add_mimo_columns(*app);
  app->add_option("models", f.more_models, "More model JSON files to compare on the same data")
      ->check(CLI::ExistingFile);
  add_field_flags(*app, f.options);
  app->add_flag("--irregular", f.irregular,
                "Judge the model on the record's time stamps as logged (jitter, gaps, equal "
                "stamps), simulated from rest with the input hold of --input-hold or the file; "
                "one input and output, nothing resampled (docs/decisions/0053)")
      ->group("Data");
  app->add_option("--horizon", f.horizon,
                  "K-step-ahead prediction with the noise model of a `ctid fit --noise-model` "
                  "result (K >= 1 samples; decision 0056), beside the simulation")
      ->check(CLI::Range(1, 1 << 30));
  app->add_option("--window", f.window,
                  "Score only START:END (seconds on the record's time axis, inclusive; either "
                  "may be empty); the simulation still starts at the record's first sample");
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
