// `ctid simulate`: the sampled response of a continuous-time model (JSON) to an input read
// from a CSV column or generated from an excitation spec, in open loop or in closed loop
// with a discrete controller (the input then is the reference r), with optional output
// noise; writes CSV t,u,y[,r]. The numerics are ctid::simulate / simulate_closed_loop, and
// simulate_delayed for a delayed_feedback_loop model (De Iuliis et al. 2017, Fig. 1). --hold
// says how the sampled input is continued: a model in open loop defaults to zoh (held, exact
// with ctid::simulate) and takes foh (piecewise linear, exact with model_output, declared in
// the CSV so `ctid fit` reads it); closed loop is held by the controller's DAC; a
// delayed_feedback_loop defaults to foh (what `ctid feedback` assumes).
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <variant>

#include "command.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/core/mimo_data.h"
#include "ctid/core/mimo_model.h"
#include "ctid/estimation/validation.h"
#include "ctid/io/csv.h"
#include "ctid/io/excitation_spec.h"
#include "ctid/io/feedback_result_json.h"
#include "ctid/io/json.h"
#include "ctid/io/mimo_data_csv.h"
#include "ctid/io/model_json.h"
#include "ctid/io/npy.h"
#include "ctid/io/result_json.h"
#include "ctid/io/sampled_data_csv.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/delayed_feedback.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/noise.h"
#include "ctid/simulation/simulate.h"
#include "ctid/simulation/stamps.h"
#include "data_flags.h"
#include "field_flags.h"

namespace ctid::cli {
namespace {

struct NoiseFlags {
  std::string filter;
  double snr = 0.0;
  double standard_deviation = 0.0;
  std::uint64_t seed = 2;
  CLI::Option* snr_option = nullptr;
  CLI::Option* std_option = nullptr;
  CLI::Option* seed_option = nullptr;

  bool wanted() const { return snr_option->count() > 0 || std_option->count() > 0; }
};

struct SimulateFlags {
  std::string model;
  std::string output;
  bool force = false;

  std::string input;
  std::string input_column = io::CsvColumns{}.input;
  std::string time_column = io::CsvColumns{}.time;

  std::string excitation;
  std::string excitation_spec;
  io::ExcitationSpec spec;
  double sample_time = 0.0;

  std::string controller;

  NoiseFlags noise;
  double nsr = 0.0;
  bool quiet = false;

  std::string hold;        ///< zoh or foh; empty: zoh for a model, foh for a delayed_feedback_loop
  bool irregular = false;  ///< simulate at the input file's time stamps as given (0053)
  // Delayed-feedback loop only.
  // Not DelayedSimulationOptions{}.substeps (20): `ctid simulate` has documented 4
  // (docs/cli.md) since it was written, and changing it would change the data it writes.
  int substeps = 4;
};

// Flags that mean something for a delayed_feedback_loop model only.
const char* const kLoopOnlyFlags[] = {"--substeps", "--nsr"};

// Flags of the generated input, and the one signal each applies to (none: every signal).
struct SignalFlag {
  const char* field;
  std::optional<io::ExcitationKind> only;
};
constexpr io::ExcitationKind kWhite = io::ExcitationKind::white_noise;
constexpr io::ExcitationKind kPrbs = io::ExcitationKind::prbs;
constexpr io::ExcitationKind kMultisine = io::ExcitationKind::multisine;
// The signal each field applies to (none: every signal), by field.
const SignalFlag kSignalFlags[] = {{"samples", std::nullopt},
                                   {"seed", std::nullopt},
                                   {"standard_deviation", kWhite},
                                   {"amplitude", kPrbs},
                                   {"register_length", kPrbs},
                                   {"samples_per_bit", kPrbs},
                                   {"periods", kMultisine},
                                   {"min_frequency_hz", kMultisine},
                                   {"max_frequency_hz", kMultisine},
                                   {"grid", kMultisine},
                                   {"rms", kMultisine}};

// A flag that would silently have no effect is a usage error: the user meant something.
void reject_unused_signal_flags(CLI::App& app, const std::string& source,
                                std::optional<io::ExcitationKind> kind) {
  for (const SignalFlag& signal : kSignalFlags) {
    const std::string flag = flag_of<io::ExcitationSpec>(signal.field);
    if (app.count(flag) == 0) continue;
    if (!kind) usage_error(flag + " has no effect with " + source);
    if (signal.only && *signal.only != *kind) {
      usage_error(flag + " applies to --excitation " + io::to_string(*signal.only) + " only, not " +
                  io::to_string(*kind));
    }
  }
}

struct InputSignal {
  Eigen::VectorXd values;
  double sample_time = 0.0;
  double start_time = 0.0;
};

InputSignal read_input_column(const SimulateFlags& f, CLI::App& app,
                              const std::optional<DiscreteTransferFunction>& controller) {
  reject_unused_signal_flags(app, "--input (it applies to generated input)", std::nullopt);
  const io::CsvTable table = io::read_table(f.input);
  InputSignal in;
  const bool time_flag_given = app.count("--time-column") > 0;
  if (table.has_column(f.time_column)) {
    const io::TimedSignal s = io::timed_signal_from_table(table, f.time_column, f.input_column);
    in.values = s.values;
    in.sample_time = s.sample_time;
    in.start_time = s.start_time;
    if (app.count("--sample-time") > 0 && !same_sample_time(f.sample_time, s.sample_time)) {
      usage_error(internal::concat("--sample-time ", format_number(f.sample_time),
                                   " disagrees with the time column '", f.time_column, "' of ",
                                   f.input, " (step ", format_number(s.sample_time), " s)"));
    }
    return in;
  }
  if (time_flag_given) {
    table.column(f.time_column);  // throws, naming the columns present
  }
  in.values = table.column(f.input_column);
  if (app.count("--sample-time") > 0) {
    in.sample_time = f.sample_time;
  } else if (controller) {
    in.sample_time = controller->sample_time();
  } else {
    usage_error(internal::concat(f.input, " has no time column '", f.time_column,
                                 "'; give --sample-time (or --time-column)"));
  }
  return in;
}

// The most samples a generated input may have: 10^7 take about 1.2 GB and 20 s; -n 1e8 ran
// out of memory after minutes (issue 16), so larger records are refused before any work.
constexpr int kMaxGeneratedSamples = 10'000'000;

// The excitation the flags or the spec file describe, validated.
io::ExcitationSpec excitation_spec(const SimulateFlags& f, CLI::App& app,
                                   const std::optional<DiscreteTransferFunction>& controller) {
  io::ExcitationSpec spec;
  if (!f.excitation_spec.empty()) {
    reject_unused_signal_flags(app, "--excitation-spec (the spec file sets it)", std::nullopt);
    spec = io::read_excitation_spec(f.excitation_spec);
    if (app.count("--sample-time") > 0 && !same_sample_time(f.sample_time, spec.sample_time)) {
      usage_error(internal::concat("--sample-time ", format_number(f.sample_time),
                                   " disagrees with sample_time ", format_number(spec.sample_time),
                                   " in ", f.excitation_spec));
    }
  } else {
    spec = f.spec;
    spec.kind = io::excitation_kind_from_string(f.excitation);
    reject_unused_signal_flags(app, "", spec.kind);
    if (app.count("--sample-time") > 0) {
      spec.sample_time = f.sample_time;
    } else if (controller) {
      spec.sample_time = controller->sample_time();
    } else {
      usage_error("--excitation needs --sample-time (or --controller, whose sample time is used)");
    }
  }
  spec.validate();
  if (spec.samples > kMaxGeneratedSamples) {
    usage_error(internal::concat(
        f.excitation_spec.empty() ? "--samples is " : f.excitation_spec + ": samples is ",
        spec.samples, "; ctid simulate generates at most ", kMaxGeneratedSamples,
        " samples (about 120 bytes each while simulating and writing)"));
  }
  return spec;
}

InputSignal generate_input(const SimulateFlags& f, CLI::App& app,
                           const std::optional<DiscreteTransferFunction>& controller) {
  const io::ExcitationSpec spec = excitation_spec(f, app, controller);
  return InputSignal{io::generate_excitation(spec), spec.sample_time, 0.0};
}

// v_k = H(q) e_k with e white of standard deviation `std` (H = 1 without a filter file).
Eigen::VectorXd raw_noise(const NoiseFlags& f, Eigen::Index n, double h, double std) {
  if (f.filter.empty()) return white_noise(static_cast<int>(n), std, f.seed);
  const DiscreteTransferFunction filter = io::read_discrete_transfer_function(f.filter);
  if (!same_sample_time(filter.sample_time(), h)) {
    usage_error(internal::concat("the noise filter in ", f.filter, " has sample time ",
                                 format_number(filter.sample_time()),
                                 " s but the input is sampled every ", format_number(h), " s"));
  }
  return colored_noise(filter, static_cast<int>(n), std * std, f.seed);
}

// The noise to add, or an empty vector. With --snr the noise is scaled against
// `noise_free`, the output without noise.
Eigen::VectorXd output_noise(const NoiseFlags& f, const Eigen::VectorXd& noise_free, double h) {
  if (!f.wanted()) {
    if (!f.filter.empty()) usage_error("--noise-filter needs --noise-std or --snr");
    if (f.seed_option->count() > 0)
      usage_error("--noise-seed needs a noise level: --noise-std or --snr (or --nsr for a loop)");
    return Eigen::VectorXd();
  }
  if (f.std_option->count() > 0) return raw_noise(f, noise_free.size(), h, f.standard_deviation);
  return scale_noise_to_snr(noise_free, raw_noise(f, noise_free.size(), h, 1.0), f.snr);
}

void add_noise_flags(CLI::App& app, NoiseFlags& f) {
  app.add_option("--noise-filter", f.filter,
                 "Noise filter JSON (discrete_transfer_function H(q), e.g. (q + 0.5)/(q - 0.85)); "
                 "default H = 1 (white noise)")
      ->check(CLI::ExistingFile)
      ->group("Output noise");
  f.std_option = app.add_option("--noise-std", f.standard_deviation,
                                "Standard deviation of the white noise e driving H(q)")
                     ->check(positive_number())
                     ->group("Output noise");
  f.snr_option = app.add_option("--snr", f.snr,
                                "Signal-to-noise ratio in dB, 10 log10(var y0 / var v), y0 the "
                                "output without noise (in closed loop: the loop's response to r "
                                "alone)")
                     ->group("Output noise");
  f.std_option->excludes(f.snr_option);
  f.seed_option = app.add_option("--noise-seed", f.seed, "Seed of the noise e")
                      ->check(seed_validator())
                      ->capture_default_str()
                      ->group("Output noise");
}

// A model file, or the result document of `ctid fit` (its fitted model is simulated).
io::ContinuousModel read_model_or_result(const nlohmann::json& document, const std::string& path) {
  const auto type = document.find("type");
  if (type != document.end() && type->is_string() && *type == "estimation_result") {
    return io::fitted_model_from_json(document, path).model;
  }
  return io::continuous_model_from_json(document, path);
}

// The loop is already closed and its noise model is the paper's (white, at the output), so
// the flags of the discrete closed loop and of coloured noise have no meaning here.
void run_simulate_loop(const SimulateFlags& f, CLI::App& app, const nlohmann::json& document) {
  const std::filesystem::path output = f.output;
  if (!f.controller.empty()) {
    usage_error(internal::concat("--controller does not apply to ", f.model,
                                 ": a delayed_feedback_loop is already a closed loop"));
  }
  if (!f.noise.filter.empty()) {
    usage_error(internal::concat("--noise-filter does not apply to ", f.model,
                                 ": a delayed_feedback_loop gets white output noise only "
                                 "(--noise-std, --snr or --nsr)"));
  }
  // A delayed_feedback_result (ctid feedback) is simulated through its identified loop.
  const DelayedFeedbackLoop loop =
      io::is_delayed_feedback_result(document)
          ? io::delayed_feedback_result_from_json(document, f.model).identification.loop
          : io::delayed_feedback_loop_from_json(document, f.model);
  loop.validate();
  const DelayedSimulationOptions options{f.substeps};
  options.validate();
  const Hold hold = f.hold == "zoh" ? Hold::zero_order_hold : Hold::first_order_hold;
  const std::string hold_name = f.hold.empty() ? "foh" : f.hold;

  const InputSignal in = f.input.empty() ? generate_input(f, app, std::nullopt)
                                         : read_input_column(f, app, std::nullopt);
  const double h = in.sample_time;
  const Eigen::VectorXd& u = in.values;
  const Eigen::VectorXd noise_free =
      simulate_delayed(to_delayed_state_space(loop), u, h, hold, options);
  Eigen::VectorXd y = noise_free;
  if (app.count("--nsr") > 0) {
    y = add_noise_at_nsr(noise_free, f.nsr, f.noise.seed).output;
  } else {
    const Eigen::VectorXd v = output_noise(f.noise, noise_free, h);
    if (v.size() != 0) y += v;
  }

  const SampledData data(h, u, y, std::nullopt, in.start_time);
  io::write_sampled_data(output, data, io::CsvColumns{},
                         f.force ? io::Overwrite::yes : io::Overwrite::no);
  if (!f.quiet) {
    std::cout << "wrote " << u.size() << " samples (t,u,y, h = " << h
              << " s, delayed feedback loop, delay " << loop.delay << " s, " << hold_name
              << " input) to " << output.string() << "\n";
  }
}

// A mimo_additive_model driven by orthogonal (Hadamard-phased) multisines: n_e experiments,
// each simulated from rest, written one after another as t, u1..u{n_u}, y1..y{n_y}, ready for
// `ctid frf --input-columns u1:u{n_u} --output-columns y1:y{n_y} --period N --experiments n_e`.
void run_simulate_mimo(const SimulateFlags& f, CLI::App& app, const nlohmann::json& document) {
  for (const char* flag : {"--input", "--controller", "--noise-filter", "--snr", "--nsr"}) {
    if (app.get_option_no_throw(flag) != nullptr && app.count(flag) > 0) {
      usage_error(internal::concat(flag,
                                   " is not available for a mimo_additive_model yet; it is "
                                   "driven by orthogonal multisines (--excitation multisine)"));
    }
  }
  if (f.hold == "foh") usage_error("--hold foh is not available for a mimo_additive_model yet");
  const MimoAdditiveModel model = io::mimo_additive_model_from_json(document, f.model);
  const io::ExcitationSpec spec = excitation_spec(f, app, std::nullopt);
  if (spec.kind != io::ExcitationKind::multisine) {
    usage_error(
        internal::concat("a mimo_additive_model is driven by orthogonal multisines; the "
                         "excitation is ",
                         io::to_string(spec.kind), ", not multisine"));
  }
  const MultisineOptions options = spec.multisine_options();
  const OrthogonalMultisines design = orthogonal_multisines(options, model.inputs());
  const double h = spec.sample_time;
  const auto experiments = static_cast<Eigen::Index>(design.experiments.size());
  const Eigen::Index n = design.experiments.front().rows();
  Eigen::MatrixXd u(n * experiments, model.inputs());
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(n * experiments, model.outputs());
  for (Eigen::Index e = 0; e < experiments; ++e) {
    const Eigen::MatrixXd& ue = design.experiments[static_cast<std::size_t>(e)];
    u.middleRows(e * n, n) = ue;
    for (int j = 0; j < model.outputs(); ++j) {
      for (int k = 0; k < model.inputs(); ++k) {
        y.col(j).segment(e * n, n) += simulate(model.channel(j, k), ue.col(k).eval(), h);
      }
    }
  }
  if (f.noise.std_option->count() > 0) {
    // Output j's noise is white_noise(N, std, seed + j) over the whole record.
    for (int j = 0; j < model.outputs(); ++j) {
      y.col(j) += white_noise(static_cast<int>(y.rows()), f.noise.standard_deviation,
                              f.noise.seed + static_cast<std::uint64_t>(j));
    }
  }
  io::write_mimo_data(f.output, MimoData(h, u, y), "t",
                      f.force ? io::Overwrite::yes : io::Overwrite::no);
  if (!f.quiet) {
    std::cout << "wrote " << u.rows() << " samples (t, u1..u" << model.inputs() << ", y1..y"
              << model.outputs() << ", h = " << h << " s): " << experiments
              << " experiments of Hadamard-phased multisines, " << options.periods << " periods of "
              << options.period_length << " samples each, to " << f.output << "\n";
  }
}

// --irregular: the model at the time stamps of --input as they are (jitter, gaps, equal
// stamps), the input continued by --hold, nothing resampled (docs/decisions/0053). What needs
// a uniform grid is refused naming the flag.
void run_simulate_irregular(const SimulateFlags& f, CLI::App& app, const nlohmann::json& document) {
  const std::string why =
      " does not go with --irregular (an open-loop model at the input file's time stamps; "
      "docs/decisions/0053)";
  if (io::is_delayed_feedback_loop(document) || io::is_delayed_feedback_result(document)) {
    usage_error(f.model + " holds a delayed_feedback_loop;" + why.substr(1));
  }
  if (document.is_object() && document.value("type", "") == io::kMimoAdditiveModelType) {
    usage_error(f.model + " holds a mimo_additive_model;" + why.substr(1));
  }
  for (const char* flag : {"--excitation", "--excitation-spec", "--controller", "--sample-time",
                           "--noise-filter", "--nsr", "--substeps"}) {
    if (app.count(flag) > 0) usage_error(std::string(flag) + why);
  }
  if (f.input.empty()) usage_error("--irregular needs --input, a file with a time column");
  reject_unused_signal_flags(app, "--input (it applies to generated input)", std::nullopt);
  const io::CsvTable table = io::read_table(f.input);
  if (!table.has_column(f.time_column)) {
    usage_error(internal::concat("--irregular needs the time stamps, but ", f.input,
                                 " has no time column '", f.time_column,
                                 "'; name it with --time-column"));
  }
  const Eigen::VectorXd& t = table.column(f.time_column);
  const Eigen::VectorXd& u = table.column(f.input_column);
  check_stamp_order(t, f.input + ": time column '" + f.time_column + "'");
  const io::ContinuousModel model = read_model_or_result(document, f.model);
  const Hold hold = f.hold == "foh" ? Hold::first_order_hold : Hold::zero_order_hold;
  const Eigen::VectorXd noise_free =
      std::visit([&](const auto& g) { return simulate_on_stamps(g, t, u, hold); }, model);
  const Eigen::VectorXd v = output_noise(f.noise, noise_free, 1.0);
  io::CsvTable written;
  if (hold == Hold::first_order_hold) written.declarations.push_back({"input_hold", "foh", 0});
  written.add_column("t", t);
  written.add_column("u", u);
  written.add_column("y", v.size() == 0 ? noise_free : Eigen::VectorXd(noise_free + v));
  io::write_csv(f.output, written, f.force ? io::Overwrite::yes : io::Overwrite::no);
  if (!f.quiet) {
    const int duplicates = duplicate_stamps(t);
    std::cout << "wrote " << t.size() << " samples (t,u,y at the time stamps of " << f.input << ", "
              << duplicates << " duplicate" << (duplicates == 1 ? "" : "s") << ", open loop, input "
              << (hold == Hold::first_order_hold ? "foh" : "zoh") << ") to " << f.output << "\n";
  }
}

void run_simulate(const SimulateFlags& f, CLI::App& app) {
  const std::filesystem::path output = f.output;
  const nlohmann::json document = io::read_json(f.model);
  if (f.irregular) {
    run_simulate_irregular(f, app, document);
    return;
  }
  if (io::is_delayed_feedback_loop(document) || io::is_delayed_feedback_result(document)) {
    run_simulate_loop(f, app, document);
    return;
  }
  for (const char* flag : kLoopOnlyFlags) {
    if (app.count(flag) > 0) {
      usage_error(internal::concat(flag, " applies to a delayed_feedback_loop model only; ",
                                   f.model, " is simulated with a zero-order hold, exactly"));
    }
  }
  if (document.is_object() && document.value("type", "") == io::kMimoAdditiveModelType) {
    run_simulate_mimo(f, app, document);
    return;
  }
  const io::ContinuousModel model = read_model_or_result(document, f.model);
  std::optional<DiscreteTransferFunction> controller;
  std::optional<TransferFunction> analog;  // an analog controller C(p) (decision 0067)
  if (!f.controller.empty()) read_controller(f.controller, controller, analog);
  const Hold hold = f.hold == "foh" ? Hold::first_order_hold : Hold::zero_order_hold;
  if (controller && hold == Hold::first_order_hold) {
    usage_error("--hold foh: in closed loop the controller's output is held (zoh) by its DAC");
  }

  const InputSignal in =
      f.input.empty() ? generate_input(f, app, controller) : read_input_column(f, app, controller);
  const double h = in.sample_time;
  if (controller && !same_sample_time(controller->sample_time(), h)) {
    usage_error(internal::concat("the controller in ", f.controller, " has sample time ",
                                 format_number(controller->sample_time()),
                                 " s but the input is sampled every ", format_number(h), " s"));
  }
  const Eigen::Index n = in.values.size();

  Eigen::VectorXd u;
  Eigen::VectorXd y;
  std::optional<Eigen::VectorXd> r;
  if (controller) {
    r = in.values;
    Eigen::VectorXd v;
    if (f.noise.wanted()) {
      // The SNR reference is the loop's noise-free response to r.
      const Eigen::VectorXd noise_free = std::visit(
          [&](const auto& plant) { return simulate_closed_loop(plant, *controller, *r).output; },
          model);
      v = output_noise(f.noise, noise_free, h);
    } else {
      v = output_noise(f.noise, Eigen::VectorXd::Zero(n), h);
    }
    const ClosedLoopSimulation loop = std::visit(
        [&](const auto& plant) { return simulate_closed_loop(plant, *controller, *r, v); }, model);
    u = loop.input;
    y = loop.output;
  } else if (analog) {
    r = in.values;
    const auto loop_with = [&](const Eigen::VectorXd& v) {
      return std::visit(
          [&](const auto& plant) { return simulate_closed_loop(plant, *analog, *r, h, v, hold); },
          model);
    };
    // As above, the SNR reference is the loop's noise-free response to r.
    const Eigen::VectorXd v = output_noise(
        f.noise, f.noise.wanted() ? loop_with(Eigen::VectorXd()).output : Eigen::VectorXd::Zero(n),
        h);
    const ClosedLoopSimulation loop = loop_with(v);
    u = loop.input;
    y = loop.output;
  } else {
    u = in.values;
    const Eigen::VectorXd noise_free =
        hold == Hold::zero_order_hold
            ? std::visit([&](const auto& g) { return simulate(g, u, h); }, model)
            : model_output(std::holds_alternative<AdditiveModel>(model)
                               ? std::get<AdditiveModel>(model)
                               : io::as_additive_model(std::get<TransferFunction>(model)),
                           u, h, Hold::first_order_hold);
    const Eigen::VectorXd v = output_noise(f.noise, noise_free, h);
    y = v.size() == 0 ? noise_free : Eigen::VectorXd(noise_free + v);
  }

  const SampledData data = SampledData(h, u, y, r, in.start_time).with_input_hold(hold);
  io::CsvColumns columns;
  if (r) columns.reference = "r";
  io::write_sampled_data(output, data, columns, f.force ? io::Overwrite::yes : io::Overwrite::no);
  if (!f.quiet) {
    std::cout << "wrote " << n << " samples (" << (r ? "t,u,y,r" : "t,u,y") << ", h = " << h
              << " s, "
              << (controller ? "closed loop"
                  : analog   ? "analog closed loop"
                             : "open loop")
              << (hold == Hold::first_order_hold ? (r ? ", reference foh" : ", input foh") : "")
              << ") to " << output.string() << "\n";
  }
}

Command add_simulate_command(CLI::App& parent) {
  auto flags = std::make_shared<SimulateFlags>();
  SimulateFlags& f = *flags;
  CLI::App* app = parent.add_subcommand(
      "simulate",
      "Simulate a continuous-time model (JSON) driven by a zero-order-hold input, in open loop "
      "or in closed loop with a discrete controller, or a delayed_feedback_loop model, and "
      "write CSV t,u,y[,r].");
  app->footer(
      "Input: exactly one of --input (a CSV column) or --excitation/--excitation-spec.\n"
      "Closed loop (--controller): the input is the reference r, u_k = C_d(q)(r_k - y_k), and "
      "the CSV gets an r column. A transfer_function controller C(p) closes an analog loop, "
      "u = C(p)(r - y), exact at the samples with r held as --hold says and the noise held "
      "(zoh) as a disturbance the controller sees; give --sample-time.\n"
      "Delayed feedback loop (model type delayed_feedback_loop): y = F e, e = u - (H y)(t - "
      "delay), input continued by --hold, RK4 with --substeps per sample; white noise only.\n"
      "Several inputs and outputs (model type mimo_additive_model): the multisine of the "
      "excitation flags, one per input (seed + i), Hadamard-phased over 2^ceil(log2 n_u) "
      "experiments written one after another, each from rest, as t,u1..,y1..; --noise-std adds "
      "white noise to output j (seed + j). ctid frf --input-columns u1:uN --output-columns "
      "y1:yM --period N reads it back.\n"
      "Noise: v_k = H(q) e_k added to y at the samples; H = 1 unless --noise-filter; its size "
      "from --noise-std (std of e) or --snr (dB, 10 log10 var(y without noise)/var(v)).\n"
      "Formats: docs/formats.md. Exit status: 0 ran, 2 bad usage or input, 1 other error.");

  app->add_option("--model,-m", f.model,
                  "Model JSON file: a transfer_function, an additive_model, a "
                  "mimo_additive_model or a delayed_feedback_loop (coefficients in ascending "
                  "powers of s)")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--output,-o", f.output, "CSV file to write (columns t,u,y and r in closed loop)")
      ->required();
  app->add_flag("--force", f.force, "Replace --output if it exists (never replaced otherwise)");
  app->add_flag("--quiet,-q", f.quiet, "Print nothing on success");

  auto* input =
      app->add_option("--input,-i", f.input,
                      "CSV file (or .npy array, columns 0, 1, ...) holding the input (or, "
                      "with --controller, the reference) in a named column")
          ->check(CLI::ExistingFile)
          ->group("Input from a file");
  app->add_option("--input-column", f.input_column, "Column of --input to use")
      ->capture_default_str()
      ->group("Input from a file");
  app->add_option("--time-column", f.time_column,
                  "Time column of --input; if present, its uniform step is the sample time")
      ->capture_default_str()
      ->group("Input from a file");

  app->add_flag("--irregular", f.irregular,
                "Simulate at the time stamps of --input as they are (jitter, gaps, equal "
                "stamps), the input continued by --hold; open loop, nothing resampled "
                "(docs/decisions/0053)")
      ->group("Input from a file");

  auto* excitation = app->add_option(flag_of<io::ExcitationSpec>("kind") + ",-e", f.excitation,
                                     "Generate the input: white, prbs or multisine")
                         ->check(CLI::IsMember({"white", "prbs", "multisine"}))
                         ->group("Generated input");
  auto* spec_file = app->add_option("--excitation-spec", f.excitation_spec,
                                    "Excitation JSON file (type \"excitation\") instead of the "
                                    "excitation flags")
                        ->check(CLI::ExistingFile)
                        ->group("Generated input");
  app->add_option(flag_of<io::ExcitationSpec>("samples") + ",-n", f.spec.samples,
                  "Number of samples N")
      ->capture_default_str()
      ->check(CLI::Range(2, kMaxGeneratedSamples))
      ->group("Generated input");
  app->add_option(flag_of<io::ExcitationSpec>("sample_time") + ",-T", f.sample_time,
                  "Sample time h in seconds (default: from the input's time column or the "
                  "controller)")
      ->check(positive_number())
      ->group("Generated input");
  app->add_option(flag_of<io::ExcitationSpec>("seed"), f.spec.seed,
                  "Seed of the white noise or multisine phases; for prbs it picks the start "
                  "state")
      ->check(seed_validator())
      ->capture_default_str()
      ->group("Generated input");
  FieldFlagSettings signal;
  signal.group = "Generated input";
  // --excitation (optional: a file may give the input), -n, -T (a file's too) and the seed's
  // range check are added above under the fields' spellings.
  signal.by_hand = {"kind", "samples", "sample_time", "seed"};
  add_field_flags(*app, f.spec, signal);

  app->add_option("--controller,-c", f.controller,
                  "Discrete controller JSON (discrete_transfer_function in q): closed loop, the "
                  "input becomes the reference r")
      ->check(CLI::ExistingFile)
      ->group("Closed loop");

  add_noise_flags(*app, f.noise);
  auto* nsr = app->add_option("--nsr", f.nsr,
                              "delayed_feedback_loop: white noise scaled to the noise-to-signal "
                              "ratio mean|v| / mean|y0| (De Iuliis et al.), e.g. 0.05")
                  ->check(positive_number())
                  ->group("Output noise");
  nsr->excludes(f.noise.std_option);
  nsr->excludes(f.noise.snr_option);

  app->add_option("--hold", f.hold,
                  "The input between samples: zoh (held; default for a model) or foh (linear; "
                  "default for a delayed_feedback_loop, what `ctid feedback` assumes). A model "
                  "simulated with foh writes '# input_hold: foh' into the CSV")
      ->check(CLI::IsMember({"zoh", "foh"}));
  app->add_option("--substeps", f.substeps, "delayed_feedback_loop: RK4 steps per sample period")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str()
      ->group("Delayed feedback loop");

  input->excludes(excitation);
  input->excludes(spec_file);
  excitation->excludes(spec_file);

  Command command;
  command.app = app;
  command.run = [flags, app] {
    const SimulateFlags& g = *flags;
    const int sources = (g.input.empty() ? 0 : 1) + (g.excitation.empty() ? 0 : 1) +
                        (g.excitation_spec.empty() ? 0 : 1);
    if (sources != 1)
      usage_error("give one input: --input FILE, --excitation KIND or --excitation-spec FILE");
    run_simulate(g, *app);
    return kExitOk;
  };
  return command;
}

}  // namespace

CTID_REGISTER_COMMAND(10, add_simulate_command);

}  // namespace ctid::cli
