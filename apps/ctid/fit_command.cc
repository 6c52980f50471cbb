// `ctid fit`: estimates a continuous-time model from sampled data (CSV) with the refined IV
// estimators of González et al. through the library's front door, identify()
// (identification/identification.h), which chooses SRIVC / CLSRIVC or the additive open/closed-loop
// iteration (29) and runs the delay scan and mode relocation. This file turns the flags into a
// ModelStructure and IdentificationOptions, writes the result as JSON (io/result_json.h plus
// what was run on what), prints a summary, and draws figures on request (plot_support.h).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "command.h"
#include "ctid/core/error.h"
#include "ctid/core/fields.h"
#include "ctid/core/format.h"
#include "ctid/estimation/validation.h"
#include "ctid/identification/identification.h"
#include "ctid/identification/mimo.h"
#include "ctid/io/documents.h"
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
#include "progress.h"
#include "structure_flags.h"

namespace ctid::cli {
namespace {

struct FitFlags {
  DataFlags data;

  std::string model;  // "unfactored" or "additive"; empty: from the structure flags
  int poles = 0;
  int zeros = 0;
  int integrators = 0;
  std::vector<std::string> submodels;
  int modes = 0;

  // Every field a flag (field_flags.h) but those read in another form below: the controller,
  // delay_scan, delay_range, record_delay_samples, two_stage, the start and initial_model.
  IdentificationOptions options;
  std::string delay_scan;
  std::string delay_range;
  std::string record_delays;  // D1,D2,...
  // Several inputs and outputs: the shared-pole estimator's own fields a flag each (--direct,
  // --input-delays-samples, --rank-one, --siso-engine); those it shares with RefinedIvOptions come
  // from the flags above (assign_shared_fields).
  MimoRefinedIvOptions mimo;

  std::string controller;
  bool two_stage = false;             // closed loop, unknown controller (decision 0043)
  TwoStageOptions two_stage_options;  // with --two-stage
  std::string initial;
  std::string start = "auto";
  bool irregular = false;  // fit on the time stamps as logged (decision 0034)

  // Process models (decision 0040): --process P1D and its parameters' settings.
  std::string process;
  std::vector<std::string> process_start;  // NAME=VALUE
  std::vector<std::string> process_fix;    // NAME=VALUE
  std::vector<std::string> process_bound;  // NAME=LO:HI (either side may be empty)
  std::vector<std::string> fix;            // NAME=VALUE, held coefficients (decision 0057)
  std::vector<std::string> bound;          // NAME=LO:HI
  std::optional<double> dc_gain;
  ProcessModelOptions process_options;  // max_delay from its field's flag; the rest by hand

  std::string output;
  std::string model_output;
  std::string plot;
  bool force = false;
  bool quiet = false;
};

DelayRange parse_delay_range(const std::string& text) {
  const auto colon = text.find(':');
  if (colon == std::string::npos) {
    usage_error("--delay-scan-samples '" + text + "': expected MIN:MAX in samples, e.g. 0:10");
  }
  DelayRange range;
  range.min = parse_count(text.substr(0, colon), "--delay-scan-samples minimum");
  range.max = parse_count(text.substr(colon + 1), "--delay-scan-samples maximum");
  return range;
}

// --delay-range MIN:MAX in seconds; the library checks the values (non-negative, ordered,
// inside the record) and names the field.
DelayInterval parse_delay_interval(const std::string& text) {
  const auto colon = text.find(':');
  const std::optional<double> min =
      colon == std::string::npos ? std::nullopt : parse_number<double>(text.substr(0, colon));
  const std::optional<double> max =
      colon == std::string::npos ? std::nullopt : parse_number<double>(text.substr(colon + 1));
  if (!min || !max) {
    usage_error("--delay-range '" + text + "': expected MIN:MAX in seconds, e.g. 0:0.5");
  }
  return DelayInterval{*min, *max};
}

// The answers in the engineer's units (issue 35): the parameters with their standard errors,
// the DC gain with its delta-method standard error, and the time constants of real poles.
// Parameters are theta_i = (a_i1..a_in, b_i0..b_im) per submodel with A_i(0) = 1, so a
// submodel's DC gain is its b_i0 (none with an integrator), and the model's the sum.
void print_engineering_quantities(std::ostream& out, const EstimationResult& r) {
  const std::vector<std::string> names = io::parameter_names(r.model);
  const auto n = static_cast<Eigen::Index>(names.size());
  const bool covariance = r.covariance.rows() == n && r.covariance.cols() == n;
  if (r.parameters.size() != n) return;
  const auto se = [&](Eigen::Index j) {
    return covariance ? std::sqrt(r.covariance(j, j)) : std::numeric_limits<double>::quiet_NaN();
  };
  if (n <= 12) {
    out << "parameters" << (covariance ? " (± one standard error)" : "") << ":";
    for (Eigen::Index j = 0; j < n; ++j) {
      out << (j == 0 ? " " : ", ") << names[static_cast<std::size_t>(j)] << " = "
          << (covariance ? plus_minus(r.parameters(j), se(j)) : format_brief(r.parameters(j)));
    }
    out << "\n";
  }
  Eigen::VectorXd gradient = Eigen::VectorXd::Zero(n);
  double dc_gain = 0.0;
  bool integrator = false;
  std::vector<std::string> time_constants;
  Eigen::Index at = 0;
  for (int i = 0; i < r.model.size(); ++i) {
    const SubmodelOrder order = r.model.orders()[static_cast<std::size_t>(i)];
    integrator = integrator || order.integrators > 0;
    dc_gain += r.parameters(at + order.n);  // b_i0
    gradient(at + order.n) = 1.0;
    const Eigen::VectorXcd poles =
        r.model[i].a.degree() >= 1 ? r.model[i].a.roots() : Eigen::VectorXcd(0);
    for (Eigen::Index k = 0; k < poles.size(); ++k) {
      if (poles(k).imag() != 0.0 || !(poles(k).real() < 0.0)) continue;
      // A first-order submodel's time constant is its a_1, with a_1's standard error.
      const std::string tau = order.n == 1 && covariance ? plus_minus(r.parameters(at), se(at))
                                                         : format_brief(-1.0 / poles(k).real());
      time_constants.push_back(tau + " s");
    }
    at += order.n + order.m + 1;
  }
  if (integrator) {
    out << "DC gain: none (the model integrates)\n";
  } else {
    const double dc_se = covariance ? std::sqrt(gradient.dot(r.covariance * gradient))
                                    : std::numeric_limits<double>::quiet_NaN();
    out << "DC gain: " << (covariance ? plus_minus(dc_gain, dc_se) : format_brief(dc_gain)) << "\n";
  }
  if (!time_constants.empty()) {
    out << "time constants (real poles):";
    for (std::size_t k = 0; k < time_constants.size(); ++k) {
      out << (k == 0 ? " " : ", ") << time_constants[k];
    }
    out << "\n";
  }
}

// RIVC's noise model: D v = C e with each coefficient +- one standard error.
void print_noise_model(std::ostream& out, const ArmaModel& m) {
  const int p = m.ar_order();
  const int q = m.ma_order();
  auto coefficients = [&](const Eigen::VectorXd& c, int first) {
    std::string text = "[";
    for (Eigen::Index i = 1; i < c.size(); ++i) {
      text += (i > 1 ? ", " : "") + plus_minus(c(i), m.standard_errors(first + i - 1));
    }
    return text + "]";
  };
  out << "noise model: ARMA(" << p << ", " << q
      << "), D v = C e with d_1.. = " << coefficients(m.ar, 0)
      << ", c_1.. = " << coefficients(m.ma, p) << ", innovation variance "
      << format_brief(m.innovation_variance) << "\n";
}

// `step` names h: "h" for a uniform record, "median step" for irregular time stamps.
void print_summary(std::ostream& out, const EstimationResult& r, const std::string& estimator,
                   double h, int samples, const std::string& file, const std::string& preprocessing,
                   const char* step = "h") {
  // A model that failed the quality verdict is announced before anything else.
  if (!r.verdict.usable) out << "WARNING: " << r.verdict.summary() << "\n";
  out << "ctid fit: " << estimator << " on " << file << " (N = " << samples << ", " << step << " = "
      << format_number(h) << " s)\n";
  if (!preprocessing.empty()) out << "preprocessing: " << preprocessing << "\n";
  // The estimator's message restates the reason; print it only when it explains a failure.
  out << "termination: " << r.brief_report() << "\n";
  if (r.delay_standard_error > 0.0) {
    // Estimated as a continuous parameter: tau with its standard error, and in samples.
    out << "input delay: " << plus_minus(r.model.input_delay(), r.delay_standard_error) << " s ("
        << format_brief(r.model.input_delay() / h) << " samples)\n";
  } else {
    out << "input delay: " << format_brief(r.input_delay_samples + r.input_delay_fraction)
        << " samples (" << format_number(r.model.input_delay()) << " s)\n";
  }
  for (int i = 0; i < r.model.size(); ++i) {
    out << "submodel " << i + 1 << ": " << r.model[i].to_string() << "\n";
  }
  if (!r.modes.empty()) {
    // Without a covariance there is no standard error to announce.
    const bool errors = std::isfinite(r.modes.front().standard_error.natural_frequency);
    out << (errors ? "modes (± one standard error):\n" : "modes:\n");
    for (const ModalEstimate& m : r.modes) {
      const double two_pi = 2.0 * std::numbers::pi;
      out << "  submodel " << m.submodel + 1
          << ": w_n = " << plus_minus(m.value.natural_frequency, m.standard_error.natural_frequency)
          << " rad/s ("
          << plus_minus(m.value.natural_frequency / two_pi,
                        m.standard_error.natural_frequency / two_pi)
          << " Hz), zeta = " << plus_minus(m.value.damping_ratio, m.standard_error.damping_ratio)
          << ", gain = " << plus_minus(m.value.gain, m.standard_error.gain) << "\n";
    }
  }
  print_engineering_quantities(out, r);
  // In the output's unit: the RMS of the simulation error beside the fit; the paper's checks
  // (Lemma 4.4's norm, the sensitivity fallbacks) stay in the result document.
  out << "fit: " << format_brief(r.fit_percent) << " %, RMS error "
      << format_brief(std::sqrt(r.mean_squared_error)) << " (output units), noise variance "
      << format_brief(r.noise_variance) << "\n";
  if (!std::isnan(r.closed_loop_fit_percent)) {
    out << "closed-loop fit from r: " << format_brief(r.closed_loop_fit_percent) << " %\n";
  }
  if (r.noise_model) print_noise_model(out, *r.noise_model);
  if (r.sensitivity_fallbacks > 0) {
    out << "iterates the controller did not stabilise: " << r.sensitivity_fallbacks << "\n";
  }
  // Decision 0058: enforced stability and coefficients at a bound.
  for (const std::string& note : r.verdict.active_constraints) {
    out << "constraint acted: " << note << "\n";
  }
  for (const std::string& warning : r.checks.warnings) out << "warning: " << warning << "\n";
}

// The delay scan's table, the chosen delay marked, and a note when the choice is not clear.
void print_delay_scan(std::ostream& out, const InputDelayScanResult& scan) {
  out << "delay scan (samples, output-error MSE, termination, verdict):\n";
  for (std::size_t k = 0; k < scan.delays.size(); ++k) {
    out << (scan.delays[k] == scan.best.input_delay_samples ? "* " : "  ") << scan.delays[k] << "  "
        << format_brief(scan.mean_squared_errors[k]) << "  " << to_string(scan.terminations[k])
        << "  " << (scan.usable[k] ? "usable" : "not usable") << "\n";
  }
  if (!scan.note.empty()) out << "warning: " << scan.note << "\n";
}

// Stage 1 of --two-stage and what the estimate assumes (decision 0043).
void print_two_stage(std::ostream& out, const TwoStageResult& stage) {
  out << "two-stage (unknown controller): r -> u by a " << enum_name(stage.sensitivity_model)
      << " model of order " << stage.sensitivity_order << ", fit";
  for (const double fit : stage.sensitivity_fit_percent) out << " " << format_brief(fit) << " %";
  out << "\n  assumes " << stage.assumptions << "\n";
}

// The output-error polish beside the IV estimate (decision 0057): the polished model, its
// delay, the criterion and the fit before and after, and why it ran when not asked for.
void print_polish(std::ostream& out, const IdentificationResult& identified) {
  const OutputErrorPolishResult& p = *identified.polish;
  if (identified.restarted_from_polish) {
    out << "the refined IV iteration had not converged; restarted from the output-error polish, "
           "it did (the estimate above)\n";
  }
  out << "polish (" << p.criterion << "): " << p.model.with_input_delay(0.0).to_string()
      << "; input delay "
      << (p.delay_standard_error > 0.0 ? plus_minus(p.model.input_delay(), p.delay_standard_error)
                                       : format_brief(p.model.input_delay()))
      << " s";
  out << "\n  criterion per sample " << format_brief(p.start_cost) << " -> " << format_brief(p.cost)
      << ", fit " << format_brief(p.start_fit_percent) << " % -> " << format_brief(p.fit_percent)
      << " %; " << p.brief_report()
      << (p.stability_constraint_active ? "; the stability constraint acted" : "") << "\n";
  auto listed = [](const std::vector<std::string>& names) {
    std::string text;
    for (const std::string& n : names) text += (text.empty() ? "" : ", ") + n;
    return text;
  };
  if (!p.held_parameters.empty()) out << "  held: " << listed(p.held_parameters) << "\n";
  if (!p.active_bounds.empty()) out << "  at a bound: " << listed(p.active_bounds) << "\n";
  if (p.noise_model) print_noise_model(out, *p.noise_model);
  if (!p.verdict.usable) out << "  polish: " << p.verdict.summary() << "\n";
}

void add_constraints(const FitFlags& f, CoefficientConstraints& constraints);

// The flags as IdentificationOptions (the controller and --initial read from their files).
IdentificationOptions identification_options(const FitFlags& f) {
  IdentificationOptions options = f.options;
  if (!f.controller.empty()) {
    read_controller(f.controller, options.controller, options.continuous_controller);
  }
  if (!f.delay_scan.empty()) options.delay_scan_samples = parse_delay_range(f.delay_scan);
  if (!f.delay_range.empty()) options.delay_range = parse_delay_interval(f.delay_range);
  if (f.two_stage) options.two_stage = f.two_stage_options;
  RefinedIvOptions& refined = options.refined_iv;
  if (!f.record_delays.empty()) {
    refined.record_delay_samples =
        parse_counts(f.record_delays, "--record-delay-samples '" + f.record_delays + "'");
  }
  if (!f.initial.empty() && f.start != "auto") {
    usage_error("give --start or --initial, not both");
  }
  if (f.start == "lssvf") {
    refined.start = StartMethod::lssvf;
  } else if (f.start == "frf") {
    refined.start = StartMethod::frf;
  } else if (f.start != "auto") {
    if (!std::filesystem::is_regular_file(f.start)) {
      usage_error("--start is '" + f.start +
                  "': neither auto, lssvf nor frf, and not a model or result file");
    }
    refined.initial_model = io::read_fitted_model(f.start).model;
  }
  if (!f.initial.empty()) refined.initial_model = io::read_fitted_model(f.initial).model;
  add_constraints(f, options.constraints);
  return options;
}

// A start file (--start FILE / --initial) whose poles the structure cannot hold, refused
// naming the file before the data is read: the estimator would otherwise stop with a message
// about its own conversion of the start.
void check_start_poles(const AdditiveModel& start, const ModelStructure& structure,
                       const FitFlags& f) {
  int poles = 0;
  int origin = 0;
  for (int i = 0; i < start.size(); ++i) {
    poles += start[i].n();
    origin += start[i].integrators;
  }
  int wanted = 0;
  int wanted_origin = 0;
  for (const SubmodelOrder& o : structure.orders) {
    wanted += o.n;
    wanted_origin += o.integrators;
  }
  if (poles == wanted && origin == wanted_origin) return;
  const bool initial = !f.initial.empty();
  usage_error(internal::concat(
      initial ? f.initial : f.start, " (", initial ? "--initial" : "--start", "): the start has ",
      poles, " poles and ", origin, " at the origin; the structure asks for ", wanted, " and ",
      wanted_origin, "; give a start of the structure's order"));
}

// A start for several inputs and outputs (--initial / --start FILE): a mimo_additive_model
// document or the model of a mimo_estimation_result, checked against the structure flags
// (submodels, their poles and zeros, the direct term); the channels are checked against the
// data once it is read (check_start_channels).
MimoAdditiveModel read_mimo_start(const std::string& file, const std::string& flag,
                                  const std::vector<SubmodelOrder>& orders, bool direct_term) {
  const nlohmann::json document = io::read_json(file);
  const auto type = document.is_object() ? document.find("type") : document.end();
  const std::string kind =
      type != document.end() && type->is_string() ? type->get<std::string>() : "";
  std::optional<MimoAdditiveModel> model;
  if (kind == io::kMimoAdditiveModelType) {
    model = io::mimo_additive_model_from_json(document, file);
  } else if (kind == io::kMimoEstimationResultType) {
    model = std::get<MimoEstimationResult>(io::result_from_json(document, file)).model;
    if (!model) usage_error(file + " (" + flag + "): the result holds no model");
  } else {
    usage_error(file + " (" + flag + "): a start for several inputs and outputs is a " +
                io::kMimoAdditiveModelType + " or " + io::kMimoEstimationResultType +
                " document, not " +
                (kind.empty() ? "a document without a type" : "'" + kind + "'"));
  }
  if (model->size() != static_cast<int>(orders.size())) {
    usage_error(internal::concat(file, " (", flag, "): the start has ", model->size(),
                                 " submodels; the structure flags give ", orders.size()));
  }
  for (int i = 0; i < model->size(); ++i) {
    const SubmodelOrder& o = orders[static_cast<size_t>(i)];
    int zeros = 0;
    for (const Polynomial& b : (*model)[i].b) zeros = std::max(zeros, b.degree());
    if ((*model)[i].a.degree() != o.n || zeros > o.m) {
      usage_error(internal::concat(file, " (", flag, "): submodel ", i + 1, " of the start has ",
                                   (*model)[i].a.degree(), " poles and numerators of degree up to ",
                                   zeros, "; the structure flags give ", o.n, " poles and ", o.m,
                                   " zeros"));
    }
  }
  if (model->has_direct_term() && !direct_term) {
    usage_error(file + " (" + flag + "): the start has a direct term D; pass --direct to fit one");
  }
  return *model;
}

// "a,b,c": channel names for a message.
std::string listed(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ",") + name;
  return text;
}

void check_start_channels(const MimoAdditiveModel& start, const std::string& file,
                          const std::string& flag, const MimoData& data) {
  if (start.inputs() == data.input_count() && start.outputs() == data.output_count()) return;
  usage_error(internal::concat(file, " (", flag, "): the start has ", start.inputs(),
                               " inputs and ", start.outputs(), " outputs but the data have ",
                               data.input_count(), " (", listed(data.input_names()), ") and ",
                               data.output_count(), " (", listed(data.output_names()), ")"));
}

// Several inputs and outputs (--input-columns / --output-columns): the shared-pole estimator
// (mimo_srivc) through identify(MimoData, orders, ...), open loop, from the automatic start or
// a model file.
ExitStatus run_mimo_fit(const FitFlags& f, const CLI::App& app) {
  ModelStructure structure = model_structure(f, app);
  // --modes K: a mode's residues differ in phase from channel to channel (complex shapes,
  // and accelerations from forces: D + (b0 + b1 p) / A), so each mode gets a first-degree
  // numerator here (docs/decisions/0018).
  if (app.count("--modes") > 0) {
    structure = ModelStructure::additive(
        std::vector<SubmodelOrder>(static_cast<std::size_t>(f.modes), SubmodelOrder{2, 1, 0}));
  }
  if (!structure.is_additive()) {
    usage_error(
        "with --input-columns / --output-columns give the modes (--modes K or "
        "--submodel N,M repeated); an unfactored model has no shared modes");
  }
  // Every structure, loop, process, iteration and constraint flag the shared-pole estimator
  // does not read is refused, not ignored: the list is derived from the field tables.
  std::set<std::string> taken = {"--model",    "--poles", "--zeros", "--integrators",
                                 "--submodel", "--modes", "--start", "--initial"};
  for (const std::string& name : shared_field_names<MimoRefinedIvOptions, RefinedIvOptions>()) {
    taken.insert(flag_of<IdentificationOptions>("refined_iv." + name));
  }
  refuse_flags_not_taken(
      app, {"Structure", "Closed loop", "Process model", "Iteration", "Constraints"}, taken,
      " is not available with --input-columns / --output-columns yet (the shared-pole estimator "
      "is open loop; known per-input delays: --input-delays-samples)");
  if (!f.initial.empty() && f.start != "auto") usage_error("give --start or --initial, not both");
  if (f.start == "lssvf" || f.start == "frf") {
    usage_error("--start " + f.start +
                " is for one input and output; with --input-columns / --output-columns --start "
                "is auto or a mimo_additive_model / mimo_estimation_result file");
  }
  if (f.start != "auto" && !std::filesystem::is_regular_file(f.start)) {
    usage_error("--start is '" + f.start + "': neither auto nor a model or result file");
  }
  std::filesystem::path package;
  if (!f.plot.empty()) {
    package = require_plotting();
    const bool second_order = std::any_of(structure.orders.begin(), structure.orders.end(),
                                          [](const SubmodelOrder& o) { return o.n == 2; });
    prepare_plot_directory(f.plot, mimo_figure_names(second_order), f.force);
  }
  MimoIdentificationOptions options;
  options.refined_iv = f.mimo;
  assign_shared_fields(options.refined_iv, f.options.refined_iv);
  options.refined_iv.validate();  // named as MimoRefinedIvOptions, before the data is read
  const std::string start_file = f.initial.empty() ? (f.start == "auto" ? "" : f.start) : f.initial;
  const std::string start_flag = f.initial.empty() ? "--start" : "--initial";
  std::optional<MimoAdditiveModel>& start = options.initial_model;
  if (!start_file.empty()) {
    start = read_mimo_start(start_file, start_flag, structure.orders, f.mimo.direct_term);
  }
  const MimoData data = f.data.load_mimo(app);
  if (start) check_start_channels(*start, start_file, start_flag, data);
  const std::vector<double>& input_delays = f.mimo.input_delays_samples;
  if (!input_delays.empty() && static_cast<int>(input_delays.size()) != data.input_count()) {
    usage_error(internal::concat("--input-delays-samples has ", input_delays.size(),
                                 " values but the data have ", data.input_count(), " inputs (",
                                 listed(data.input_names()), "): give one delay per input"));
  }
  // A long record of many outputs iterates for tens of seconds: the iterations as a progress
  // line (of at most --max-iterations; a converging fit stops before the total).
  Progress progress("ctid fit", f.quiet);
  const MimoEstimationResult result =
      identify(data, structure.orders, options, progress.callback("mimo_srivc iteration"));
  progress.clear();

  nlohmann::json document = io::to_json(result);
  document["data"] = io::to_json(io::DataProvenance{.files = {f.data.files.front()},
                                                    .samples = data.size(),
                                                    .sample_time = data.sample_time(),
                                                    .inputs = data.input_names(),
                                                    .outputs = data.output_names(),
                                                    .input_hold = data.input_hold()});
  const io::Overwrite overwrite = f.force ? io::Overwrite::yes : io::Overwrite::no;
  if (!f.output.empty()) io::write_json(f.output, document, overwrite);
  if (!f.model_output.empty()) {
    if (result.model) {
      io::write_json(f.model_output, io::to_json(*result.model), overwrite);
    } else {
      std::cerr << "ctid fit: note: no model was computed; " << f.model_output
                << " is not written\n";
    }
  }
  flush_diagnostics();  // the data's warnings, now that nothing refused it
  if (!f.quiet) {
    if (!result.verdict.usable) std::cout << "WARNING: " << result.verdict.summary() << "\n";
    std::cout << result.message << "\n"
              << f.data.files.front() << ": " << data.size() << " samples, " << data.input_count()
              << " inputs x " << data.output_count()
              << " outputs, h = " << format_number(data.sample_time()) << " s\n";
    if (start) std::cout << "start: " << start_file << "\n";
    if (result.model && result.model->has_input_delays()) {
      std::cout << "input delays (known):";
      for (int k = 0; k < data.input_count(); ++k) {
        const double tau = result.model->input_delays()(k);
        std::cout << (k > 0 ? "," : "") << " " << data.input_names()[static_cast<std::size_t>(k)]
                  << " " << format_number(tau) << " s (" << format_brief(tau / data.sample_time())
                  << " samples)";
      }
      std::cout << "\n";
    }
    for (const MimoMode& m : result.modes) {
      std::cout << "  mode " << m.submodel + 1 << ": f_n = "
                << plus_minus(m.natural_frequency / (2.0 * M_PI),
                              m.natural_frequency_se / (2.0 * M_PI))
                << " Hz, zeta = " << plus_minus(m.damping_ratio, m.damping_ratio_se)
                << ", rank-one share " << format_brief(m.rank_one_share) << "\n";
    }
    for (int j = 0; j < data.output_count(); ++j) {
      std::cout << "  fit " << data.output_names()[static_cast<size_t>(j)] << ": "
                << format_brief(result.fit_percent(j)) << " %\n";
    }
  } else if (!result.verdict.usable) {
    std::cerr << "ctid fit: WARNING: " << result.verdict.summary() << "\n";
  }
  if (!f.plot.empty() && result.model) {
    const auto written =
        draw_mimo_figures(package, f.plot, document, data,
                          "ctid fit: mimo_srivc on " +
                              std::filesystem::path(f.data.files.front()).filename().string());
    if (!f.quiet) {
      for (const auto& file : written) std::cout << "wrote " << file.string() << "\n";
    }
  }
  return result.verdict.usable ? kExitOk : kExitNoUsableModel;
}

// What --irregular does not take yet, each refused naming the flag (decision 0034).
void check_irregular_flags(const FitFlags& f, const CLI::App& app) {
  const std::string why =
      " does not go with --irregular (an unfactored open-loop SISO SRIVC on the time stamps; "
      "docs/decisions/0034)";
  if (f.data.mimo_asked(app)) usage_error("--input-columns / --output-columns" + why);
  for (const char* flag :
       {"--controller", "--two-stage", "--submodel", "--modes", "--input-delay-samples",
        "--delay-scan-samples", "--delay-range", "--record-delay-samples", "--relocate-modes",
        "--rank-one", "--input-delays-samples", "--direct", "--plot", "--polish", "--fix",
        "--bound", "--dc-gain"}) {
    if (app.count(flag) > 0) usage_error(std::string(flag) + why);
  }
  if (f.model == "additive") usage_error("--model additive" + why);
  if (f.options.refined_iv.initial_conditions != InitialConditions::zero)
    usage_error("--initial-conditions estimate" + why);
  if (f.data.files.size() > 1) usage_error("several data files" + why);
}

// --irregular: srivc_irregular through identify() on the stamps as logged.
ExitStatus run_irregular_fit(const FitFlags& f, const CLI::App& app) {
  check_irregular_flags(f, app);
  const ModelStructure structure = model_structure(f, app);
  const IdentificationOptions options = identification_options(f);
  validate_identification(structure, options);
  const IrregularRecord record = f.data.load_irregular(app);
  const IdentificationResult identified = identify(record, structure, options);
  const EstimationResult& result = identified.estimate;
  const std::string estimator(enum_name(identified.estimator));
  const auto samples = static_cast<int>(record.time.size());
  const double median = record.median_step();
  const int duplicates = duplicate_stamps(record.time);
  const io::Overwrite overwrite = f.force ? io::Overwrite::yes : io::Overwrite::no;
  if (!f.output.empty()) {
    nlohmann::json document = io::to_json(result);
    document["estimator"] = estimator;
    document["loop"] = "open";
    document["data"] = io::to_json(io::DataProvenance{.files = {f.data.files.front()},
                                                      .samples = samples,
                                                      .sample_time = median,
                                                      .input_hold = record.input_hold,
                                                      .duplicate_stamps = duplicates,
                                                      .detrend = f.data.detrend});
    io::write_json(f.output, document, overwrite);
  }
  if (!f.model_output.empty()) {
    io::write_model(f.model_output, io::ContinuousModel(result.model), overwrite);
  }
  if (!f.quiet) {
    print_summary(std::cout, result, estimator, median, samples, f.data.files.front(), "",
                  "median step");
    std::cout << "time stamps: irregular, " << duplicates << " duplicate"
              << (duplicates == 1 ? "" : "s") << ", steps " << format_brief(median)
              << " s median, input " << enum_name(record.input_hold) << "\n";
  } else if (!result.verdict.usable) {
    std::cerr << "ctid fit: WARNING: " << result.verdict.summary() << "\n";
  }
  return result.verdict.usable ? kExitOk : kExitNoUsableModel;
}

// --- Process models (--process) ---------------------------------------------------------------

// "NAME=VALUE" split at the first '='; the flag names the entry in the message.
std::pair<std::string, std::string> parameter_entry(const std::string& text, const char* flag,
                                                    const char* form) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0) {
    usage_error(std::string(flag) + " '" + text + "': expected " + form);
  }
  return {text.substr(0, eq), text.substr(eq + 1)};
}

double parameter_number(const std::string& text, const std::string& entry, const char* flag,
                        const char* form) {
  const std::optional<double> value = parse_number<double>(text);
  if (!value) usage_error(std::string(flag) + " '" + entry + "': expected " + form);
  return *value;
}

// "NAME=LOWER:UPPER" (either bound may be empty): the name and the bounds given.
struct BoundEntry {
  std::string name;
  std::optional<double> lower, upper;
};
BoundEntry bound_entry(const std::string& entry, const char* flag, const char* form) {
  const auto [name, text] = parameter_entry(entry, flag, form);
  const auto colon = text.find(':');
  if (colon == std::string::npos)
    usage_error(std::string(flag) + " '" + entry + "': expected " + form);
  BoundEntry b{name, std::nullopt, std::nullopt};
  const std::string lo = text.substr(0, colon);
  const std::string hi = text.substr(colon + 1);
  if (!lo.empty()) b.lower = parameter_number(lo, entry, flag, form);
  if (!hi.empty()) b.upper = parameter_number(hi, entry, flag, form);
  return b;
}

ProcessParameterSetting& setting_for(ProcessModelOptions& options, const std::string& name) {
  for (ProcessParameterSetting& s : options.parameters) {
    if (s.name == name) return s;
  }
  options.parameters.push_back(ProcessParameterSetting{name, {}, false, {}, {}});
  return options.parameters.back();
}

ProcessModelOptions process_options(const FitFlags& f) {
  ProcessModelOptions options = f.process_options;
  options.max_iterations = f.options.refined_iv.max_iterations;  // one --max-iterations
  for (const std::string& entry : f.process_start) {
    const auto [name, text] = parameter_entry(entry, "--process-start", "NAME=VALUE, e.g. Tp1=2");
    ProcessParameterSetting& s = setting_for(options, name);
    if (s.value) usage_error("--process-start and --process-fix both give " + name);
    s.value = parameter_number(text, entry, "--process-start", "NAME=VALUE, e.g. Tp1=2");
  }
  for (const std::string& entry : f.process_fix) {
    const auto [name, text] = parameter_entry(entry, "--process-fix", "NAME=VALUE, e.g. Td=0.5");
    ProcessParameterSetting& s = setting_for(options, name);
    if (s.value) usage_error("--process-start and --process-fix both give " + name);
    s.value = parameter_number(text, entry, "--process-fix", "NAME=VALUE, e.g. Td=0.5");
    s.fixed = true;
  }
  for (const std::string& entry : f.process_bound) {
    const BoundEntry b = bound_entry(entry, "--process-bound",
                                     "NAME=LOWER:UPPER (either may be empty), e.g. Tp1=0.1:10");
    ProcessParameterSetting& s = setting_for(options, b.name);
    if (b.lower) s.lower = b.lower;
    if (b.upper) s.upper = b.upper;
  }
  return options;
}

// --fix NAME=VALUE, --bound NAME=LO:HI and --dc-gain K as the coefficient constraints.
void add_constraints(const FitFlags& f, CoefficientConstraints& constraints) {
  auto setting = [&](const std::string& name) -> CoefficientSetting& {
    for (CoefficientSetting& s : constraints.coefficients) {
      if (s.name == name) return s;
    }
    constraints.coefficients.push_back(CoefficientSetting{name, {}, {}, {}});
    return constraints.coefficients.back();
  };
  for (const std::string& entry : f.fix) {
    constexpr const char* form = "NAME=VALUE, e.g. theta1.b0=2";
    const auto [name, text] = parameter_entry(entry, "--fix", form);
    setting(name).fixed = parameter_number(text, entry, "--fix", form);
  }
  for (const std::string& entry : f.bound) {
    const BoundEntry b =
        bound_entry(entry, "--bound", "NAME=LOWER:UPPER (either may be empty), e.g. theta1.a1=0:2");
    CoefficientSetting& s = setting(b.name);
    if (b.lower) s.lower = b.lower;
    if (b.upper) s.upper = b.upper;
  }
  constraints.dc_gain = f.dc_gain;
}

// The parameters in the engineer's units, each with its standard error.
void print_process_summary(std::ostream& out, const ProcessModelResult& r, double h, int samples,
                           const std::string& file, Hold hold, const std::string& preprocessing) {
  if (!r.verdict.usable) out << "WARNING: " << r.verdict.summary() << "\n";
  out << "ctid fit: process model " << r.structure << " on " << file << " (N = " << samples
      << ", h = " << format_number(h) << " s, input " << enum_name(hold) << ")\n";
  if (!preprocessing.empty()) out << "preprocessing: " << preprocessing << "\n";
  out << "termination: " << r.brief_report() << "\n";
  out << "start: " << r.start_method << " (fit " << format_brief(r.start_fit_percent) << " %)\n";
  out << "parameters (± one standard error):\n";
  for (std::size_t i = 0; i < r.parameter_names.size(); ++i) {
    const std::string& name = r.parameter_names[i];
    const auto k = static_cast<Eigen::Index>(i);
    const bool held = std::find(r.fixed_parameters.begin(), r.fixed_parameters.end(), name) !=
                      r.fixed_parameters.end();
    out << "  " << name << " = "
        << (held ? format_brief(r.parameters(k))
                 : plus_minus(r.parameters(k), r.standard_errors(k)))
        << (name == "K" || name == "Zeta" ? "" : " s");
    if (name == "Td") out << " (" << format_brief(r.parameters(k) / h) << " samples)";
    if (held) out << " (held)";
    out << "\n";
  }
  out << "transfer function: " << r.transfer_function().to_string() << "\n";
  out << "fit: " << format_brief(r.fit_percent) << " %, RMS error "
      << format_brief(std::sqrt(r.mean_squared_error)) << " (output units), noise variance "
      << format_brief(r.noise_variance) << "\n";
}

// --process NAME: identify(data, ProcessStructure, ProcessModelOptions).
ExitStatus run_process_fit(const FitFlags& f, const CLI::App& app) {
  const std::string why =
      " does not go with --process (a process model is named by its structure, e.g. P1D; its "
      "dead time is estimated, its settings are --process-start/--process-fix/--process-bound)";
  if (f.irregular) usage_error("--irregular" + why);
  if (f.data.mimo_asked(app)) usage_error("--input-columns / --output-columns" + why);
  // Every fit flag but the one --max-iterations is refused, derived from the help groups.
  refuse_flags_not_taken(
      app, {"Structure", "Several inputs and outputs", "Closed loop", "Iteration", "Constraints"},
      {flag_of<IdentificationOptions>("refined_iv.max_iterations")}, why);
  if (app.count("--plot") > 0) usage_error("--plot" + why);
  if (f.data.files.size() > 1) usage_error("several data files" + why);
  const ProcessStructure structure = ProcessStructure::parse(f.process);
  const ProcessModelOptions options = process_options(f);
  validate_identification(structure, options);  // before the data is read
  const SampledData data = f.data.load_all(app, false).front();
  const ProcessModelResult result = identify(data, structure, options);
  const TransferFunction model = result.transfer_function();

  const io::Overwrite overwrite = f.force ? io::Overwrite::yes : io::Overwrite::no;
  if (!f.output.empty()) {
    nlohmann::json document = io::fields_to_json(result);
    document["type"] = "process_model_result";
    document["model"] = io::to_json(io::ContinuousModel(model));
    document["data"] = io::to_json(io::DataProvenance{.files = {f.data.files.front()},
                                                      .samples = data.size(),
                                                      .sample_time = data.sample_time(),
                                                      .input_hold = data.input_hold(),
                                                      .preprocessing = f.data.preprocessing});
    io::write_json(f.output, document, overwrite);
  }
  if (!f.model_output.empty())
    io::write_model(f.model_output, io::ContinuousModel(model), overwrite);
  flush_diagnostics();
  if (!f.quiet) {
    print_process_summary(std::cout, result, data.sample_time(), data.size(), f.data.files.front(),
                          data.input_hold(),
                          f.data.preprocessing_asked(app) ? f.data.preprocessing.summary() : "");
  } else if (!result.verdict.usable) {
    std::cerr << "ctid fit: WARNING: " << result.verdict.summary() << "\n";
  }
  return result.verdict.usable ? kExitOk : kExitNoUsableModel;
}

ExitStatus run_fit(const FitFlags& f, const CLI::App& app) {
  if (!f.process.empty()) return run_process_fit(f, app);
  refuse_flags_not_taken(app, {"Process model"}, {}, " goes with --process NAME");
  if (f.irregular) return run_irregular_fit(f, app);
  if (f.data.mimo_asked(app)) return run_mimo_fit(f, app);
  if (app.count("--rank-one") > 0) {
    usage_error(
        "--rank-one goes with --input-columns / --output-columns (a single channel's residue is "
        "always rank one)");
  }
  if (app.count("--siso-engine") > 0) {
    usage_error("--siso-engine goes with --input-columns / --output-columns");
  }
  if (app.count("--input-delays-samples") > 0) {
    usage_error(
        "--input-delays-samples goes with --input-columns / --output-columns (one delay per "
        "input); "
        "with one input give --input-delay-samples");
  }
  if (app.count("--direct") > 0) {
    usage_error(
        "--direct goes with --input-columns / --output-columns (a SISO additive model "
        "carries its direct term in a biproper submodel: --submodel N,N)");
  }
  const ModelStructure structure = model_structure(f, app);
  if (static_cast<int>(app.count("--input-delay-samples") > 0) +
          static_cast<int>(!f.delay_scan.empty()) + static_cast<int>(!f.delay_range.empty()) >
      1) {
    usage_error("give one of --input-delay-samples, --delay-scan-samples and --delay-range");
  }
  std::filesystem::path package;
  if (!f.plot.empty()) {
    package = require_plotting();
    prepare_plot_directory(f.plot, model_figure_names(structure.is_additive()), f.force);
  }

  const IdentificationOptions options = identification_options(f);
  if (options.refined_iv.initial_model) {
    check_start_poles(*options.refined_iv.initial_model, structure, f);
  }
  validate_identification(structure, options);  // before the data is read
  const std::optional<DiscreteTransferFunction>& controller = options.controller;
  if (!f.record_delays.empty() &&
      options.refined_iv.record_delay_samples.size() != f.data.files.size()) {
    usage_error("--record-delay-samples gives " +
                std::to_string(options.refined_iv.record_delay_samples.size()) + " delays for " +
                std::to_string(f.data.files.size()) + " data files; give one per file");
  }
  const std::vector<SampledData> records =
      f.data.load_all(app, controller.has_value() || options.continuous_controller.has_value() ||
                               options.two_stage.has_value());
  const SampledData& data = records.front();
  int samples = 0;
  for (std::size_t k = 0; k < records.size(); ++k) {
    samples += records[k].size();
    if (!same_sample_time(records[k].sample_time(), data.sample_time())) {
      usage_error(internal::concat(
          f.data.files[k], " is sampled every ", format_number(records[k].sample_time()), " s but ",
          f.data.files.front(), " every ", format_number(data.sample_time()),
          " s; records fitted together share their sample time"));
    }
  }
  if (controller && !same_sample_time(controller->sample_time(), data.sample_time())) {
    usage_error(internal::concat("the controller in ", f.controller, " has sample time ",
                                 format_number(controller->sample_time()), " s but ",
                                 f.data.file_list(), " is sampled every ",
                                 format_number(data.sample_time()), " s"));
  }

  Progress progress("ctid fit", f.quiet);
  const IdentificationResult identified =
      identify(records, structure, options,
               {progress.callback("delay scan"), progress.callback("mode relocation trial")});
  progress.clear();
  const EstimationResult& result = identified.estimate;
  const std::string estimator(enum_name(identified.estimator));
  const std::optional<InputDelayScanResult>& scanned = identified.delay_scan;
  const std::optional<ModeRelocationResult>& relocated = identified.mode_relocation;

  // What the fit writes, ctid must read back (validate, simulate, --initial): the model goes
  // through the model reader before anything is written.
  if (!f.output.empty() || !f.model_output.empty()) {
    try {
      (void)io::continuous_model_from_json(io::to_json(io::ContinuousModel(result.model)),
                                           "the fitted model");
    } catch (const InvalidArgument& e) {
      throw ComputationError(std::string(e.what()) +
                             "; ctid could not read the fitted model back, so nothing was "
                             "written (try fewer modes or a lower order)");
    }
  }

  if (!f.output.empty()) {
    nlohmann::json document = io::to_json(result);
    document["estimator"] = estimator;
    document["loop"] = identified.closed_loop ? "closed" : "open";
    io::DataProvenance provenance{.files = f.data.files,
                                  .samples = samples,
                                  .sample_time = data.sample_time(),
                                  .input_hold = data.input_hold(),
                                  .preprocessing = f.data.preprocessing};
    if (records.size() > 1) {
      for (const SampledData& record : records) provenance.record_samples.push_back(record.size());
    }
    document["data"] = io::to_json(provenance);
    if (controller) document["controller"] = io::to_json(*controller);
    if (options.continuous_controller) {
      document["controller"] = io::to_json(*options.continuous_controller);
    }
    if (identified.two_stage) document["two_stage"] = io::fields_to_json(*identified.two_stage);
    if (identified.polish) {
      document["polish"] = io::fields_to_json(*identified.polish);
      document["polish"]["restarted_from_polish"] = identified.restarted_from_polish;
    }
    if (scanned) document["delay_scan"] = io::delay_scan_summary_to_json(*scanned);
    if (relocated) {
      document["mode_relocation"] = io::relocation_summary_to_json(*relocated);
      document["mode_relocation"]["criterion"] =
          std::string(enum_name(options.relocation.criterion));
    }
    io::write_json(f.output, document, f.force ? io::Overwrite::yes : io::Overwrite::no);
  }
  if (!f.model_output.empty()) {
    io::write_model(f.model_output, io::ContinuousModel(result.model),
                    f.force ? io::Overwrite::yes : io::Overwrite::no);
  }
  flush_diagnostics();  // the data's warnings, now that nothing refused it
  if (!f.quiet) {
    print_summary(std::cout, result, estimator, data.sample_time(), samples, f.data.file_list(),
                  f.data.preprocessing_asked(app) ? f.data.preprocessing.summary() : "");
    if (scanned) print_delay_scan(std::cout, *scanned);
    if (relocated) std::cout << "mode relocation: " << relocated->message << "\n";
    if (identified.two_stage) print_two_stage(std::cout, *identified.two_stage);
    if (identified.polish) print_polish(std::cout, identified);
  }

  if (!f.plot.empty()) {
    const Eigen::VectorXd simulated =
        model_output(result.model, data.input(), data.sample_time(), data.input_hold());
    const auto written = draw_model_figures(
        package, f.plot, result.model, result.covariance, data, simulated, structure.is_additive(),
        "ctid fit: " + estimator + " on " +
            std::filesystem::path(f.data.files.front()).filename().string());
    if (!f.quiet) {
      for (const auto& file : written) std::cout << "wrote " << file.string() << "\n";
    }
  }
  if (f.quiet && !result.verdict.usable) {
    std::cerr << "ctid fit: WARNING: " << result.verdict.summary() << "\n";
  }
  return result.verdict.usable ? kExitOk : kExitNoUsableModel;
}

Command add_fit_command(CLI::App& parent) {
  auto flags = std::make_shared<FitFlags>();
  FitFlags& f = *flags;
  CLI::App* app = parent.add_subcommand(
      "fit",
      "Estimate a continuous-time model from sampled data with the refined IV estimators "
      "(SRIVC, CLSRIVC, additive open/closed loop) and write the result as JSON.");
  app->footer(
      "Structure: --poles N --zeros M [--integrators L] (one unfactored B/(p^L A)), or "
      "--submodel N,M[,L] repeated, in any order (additive), or --modes K (K second-order "
      "modes, M = 0).\n"
      "Several inputs and outputs: --input-columns u1,u2 --output-columns y1:y28 (names or "
      "ranges of the file's columns) fit modes shared by every channel (open loop; --direct "
      "adds D; --start/--initial take a mimo_additive_model or mimo_estimation_result); the "
      "summary lists the modes and every output's fit.\n"
      "Closed loop: --controller C.json (a discrete_transfer_function: digital controller) uses "
      "CLSRIVC / additive CL and needs the reference column; a transfer_function in p (analog "
      "controller) fits one unfactored model by clsrivc_continuous; with the controller unknown, "
      "--two-stage fits r -> u first "
      "and the plant from the simulated input.\n"
      "Output: --output RESULT.json holds everything; its \"model\" field (or --model-output) "
      "is a model file for 'ctid validate' and 'ctid simulate --model'.\n"
      "Formats: docs/formats.md, docs/cli-estimation.md. Exit status: 0 ran and the model passed "
      "the quality verdict (whatever the termination), 3 ran but no usable model (a WARNING "
      "line says why and what to try; outputs are still written), 2 bad usage or input, 1 "
      "other error.");

  f.data.add_to(*app, "data", true, true);
  f.data.add_mimo_columns(*app);

  app->add_option("--model", f.model,
                  "Model kind: unfactored or additive (default: from the "
                  "structure flags)")
      ->check(CLI::IsMember({"unfactored", "additive"}))
      ->group("Structure");
  app->add_option("--poles", f.poles, "Unfactored: poles n (deg A), besides integrators")
      ->check(non_negative_number())
      ->group("Structure");
  app->add_option("--zeros", f.zeros, "Unfactored: zeros m (deg B)")
      ->check(non_negative_number())
      ->group("Structure");
  app->add_option("--integrators", f.integrators, "Unfactored: poles at the origin l")
      ->check(non_negative_number())
      ->group("Structure");
  app->add_option("--submodel", f.submodels,
                  "Additive: one submodel N,M[,L] (poles, zeros, integrators); repeat (any "
                  "order: the start gives slower poles to earlier submodels that fit them)")
      ->take_all()
      ->allow_extra_args(false)
      ->group("Structure");
  app->add_option("--modes", f.modes,
                  "Additive: K second-order modes (--submodel 2,0 K times; with "
                  "--input-columns/--output-columns --submodel 2,1: complex residues)")
      ->group("Structure");
  FieldFlagSettings mimo;
  mimo.group = "Several inputs and outputs";
  // Given by IdentificationOptions' flags below (one --max-iterations, --noise, ...).
  mimo.by_hand = shared_field_names<MimoRefinedIvOptions, RefinedIvOptions>();
  add_field_flags(*app, f.mimo, mimo);
  app->add_option(flag_of<IdentificationOptions>("delay_scan_samples"), f.delay_scan,
                  "Estimate the delay: fit every delay MIN:MAX (samples), keep the smallest "
                  "output error")
      ->group("Structure");
  app->add_option(flag_of<IdentificationOptions>("refined_iv.record_delay_samples"),
                  f.record_delays,
                  "Several files: whole samples by which each file's input lags more than the "
                  "model's delay (D1,D2,..., one per file)")
      ->group("Structure");
  app->add_option(flag_of<IdentificationOptions>("delay_range"), f.delay_range,
                  "Estimate the delay as a continuous parameter in MIN:MAX (seconds): the "
                  "whole samples are scanned, then the delay is refined with its standard error")
      ->group("Structure");

  app->add_option("--process", f.process,
                  "Process model as procest names it: P + poles 0..3, then D (dead time), Z "
                  "(zero), I (integrator), U (underdamped pair), e.g. P1D, P2DU, P1DI "
                  "(docs/process-models.md)")
      ->group("Process model");
  app->add_option("--process-start", f.process_start,
                  "Start of process parameters, NAME=VALUE (K, Tp1, Tp2, Tp3, Tw, Zeta, Tz, Td), "
                  "comma-separated or repeated")
      ->delimiter(',')
      ->group("Process model");
  app->add_option("--process-fix", f.process_fix,
                  "Process parameters held at a value, NAME=VALUE, comma-separated or repeated")
      ->delimiter(',')
      ->group("Process model");
  app->add_option("--process-bound", f.process_bound,
                  "Bounds of process parameters, NAME=LOWER:UPPER (either may be empty), "
                  "comma-separated or repeated")
      ->delimiter(',')
      ->group("Process model");
  FieldFlagSettings process;
  process.group = "Process model";
  // --process-start/-fix/-bound above (NAME=VALUE lists); one --max-iterations for every fit.
  process.by_hand = {"parameters", "max_iterations"};
  add_field_flags(*app, f.process_options, process);

  app->add_option(flag_of<IdentificationOptions>("controller") + ",-c", f.controller,
                  "Controller JSON: a discrete_transfer_function in q (digital) or a "
                  "transfer_function in p (analog): closed loop")
      ->check(CLI::ExistingFile)
      ->group("Closed loop");
  add_two_stage_flags(
      *app, f.two_stage, f.two_stage_options, flag_of<IdentificationOptions>("two_stage"),
      "IdentificationOptions.two_stage", "Closed loop",
      "Closed loop with an unknown controller: model r -> u (discrete, refined IV), "
      "then fit the plant from the simulated noise-free input (needs the "
      "reference column; decision 0043)");

  app->add_option(flag_of<IdentificationOptions>("refined_iv.start"), f.start,
                  "Start: auto (LSSVF grid and FRF peaks, best output error), lssvf, frf, or a "
                  "model/result JSON")
      ->capture_default_str()
      ->group("Iteration");
  app->add_option(flag_of<IdentificationOptions>("refined_iv.initial_model"), f.initial,
                  "Starting model or result JSON (same as --start FILE)")
      ->check(CLI::ExistingFile)
      ->group("Iteration");
  FieldFlagSettings settings;
  settings.group = "Iteration";
  // Read from files or as MIN:MAX, D1,D2,... and auto|lssvf|frf|FILE above; two_stage's own.
  settings.by_hand = {"controller",         "continuous_controller",
                      "delay_scan_samples", "delay_range",
                      "two_stage",          "refined_iv.initial_model",
                      "refined_iv.start",   "refined_iv.record_delay_samples",
                      "constraints"};
  add_field_flags(*app, f.options, settings);
  app->add_option("--fix", f.fix,
                  "Coefficients held at a value, NAME=VALUE (theta1.a1, theta1.b0, ..., tau), "
                  "comma-separated or repeated; in the iteration (unfactored) and the polish, "
                  "which it implies")
      ->delimiter(',')
      ->group("Constraints");
  app->add_option("--bound", f.bound,
                  "Bounds of coefficients, NAME=LOWER:UPPER (either may be empty), "
                  "comma-separated or repeated; in the polish, which it implies")
      ->delimiter(',')
      ->group("Constraints");
  app->add_option("--dc-gain", f.dc_gain,
                  "Known static gain G(0), held to rounding; in the iteration (unfactored) and "
                  "the polish, which it implies")
      ->group("Constraints");
  app->add_flag("--irregular", f.irregular,
                "Fit on the time stamps as logged (jitter, gaps, duplicate stamps), the filters "
                "discretised on each interval for --input-hold; unfactored, open loop, one "
                "input and output (docs/decisions/0034)")
      ->group("Data");
  app->add_option("--output,-o", f.output, "Result JSON to write (everything in the estimate)")
      ->group("Output");
  app->add_option("--model-output", f.model_output,
                  "Also write the fitted model alone (additive_model JSON; "
                  "mimo_additive_model with several inputs/outputs)")
      ->group("Output");
  app->add_option("--plot", f.plot,
                  "Directory for bode.png, validation.png, residuals.png (and modes.png, "
                  "additive; several inputs/outputs: frf_matrix_overlay.png, mode_shapes.png, "
                  "mac.png) drawn by python3 -m ctid.plot")
      ->group("Output");
  app->add_flag("--force", f.force, "Replace output files that exist (never replaced otherwise)")
      ->group("Output");
  app->add_flag("--quiet,-q", f.quiet, "Print no summary")->group("Output");

  Command command;
  command.app = app;
  command.run = [flags, app] { return run_fit(*flags, *app); };
  return command;
}

}  // namespace

CTID_REGISTER_COMMAND(20, add_fit_command);

}  // namespace ctid::cli
