// `ctid step` and `ctid impulse`: the step or impulse response of a fitted model (a `ctid fit`
// result) or of a model file, exact on a time grid, with its characteristics (DC gain, rise
// time, settling time, overshoot, peak time), each +- one standard error by the delta method
// from the result's parameter covariance, and the pointwise band; CSV t,y[,y_std,lower,upper]
// and a figure through ctid.plot. The numerics are ctid::time_response
// (simulation/time_response.h, docs/time-responses.md).
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "command.h"
#include "ctid/core/format.h"
#include "ctid/identification/identification.h"
#include "ctid/io/csv.h"
#include "ctid/io/fields_json.h"
#include "ctid/io/json.h"
#include "ctid/io/result_json.h"
#include "ctid/simulation/time_response.h"
#include "field_flags.h"
#include "plot_support.h"

namespace ctid::cli {
namespace {

struct ResponseFlags {
  std::string model;
  // Every field a flag (field_flags.h) but kind, the command's name, and final_time and
  // sample_time, added below to keep their short forms -t and -T.
  TimeResponseOptions options;
  double final_time = 0.0;
  double sample_time = 0.0;
  std::string output;
  std::string plot;
  bool force = false;
  bool quiet = false;
  CLI::Option* final_time_option = nullptr;
  CLI::Option* points_option = nullptr;
  CLI::Option* sample_time_option = nullptr;
};

// The documents a model with (maybe) a covariance is read from; anything else is refused by
// name before it is parsed as a model.
void check_document_type(const nlohmann::json& document, const std::string& file,
                         const std::string& command) {
  const auto type = document.is_object() ? document.find("type") : document.end();
  if (type == document.end() || !type->is_string()) return;  // the model reader says why
  const std::string name = type->get<std::string>();
  for (const char* known :
       {"estimation_result", "mode_relocation_result", "input_delay_scan_result",
        "process_model_result", "transfer_function", "additive_model"}) {
    if (name == known) return;
  }
  usage_error(file + " is a " + name + " document; ctid " + command +
              " reads a ctid fit result (estimation_result, mode_relocation_result, "
              "input_delay_scan_result, process_model_result) or a transfer_function / "
              "additive_model file");
}

// The estimate of a `ctid fit --process` result; nullopt for every other document.
std::optional<ProcessModelResult> process_result_in(const nlohmann::json& document,
                                                    const std::string& file) {
  const auto type = document.is_object() ? document.find("type") : document.end();
  if (type == document.end() || *type != "process_model_result") return std::nullopt;
  nlohmann::json fields = document;
  for (const char* written_beside : {"type", "model", "data"}) fields.erase(written_beside);
  ProcessModelResult result;
  io::fields_from_json(fields, result, file);
  return result;
}

TimeResponseOptions options_from(const ResponseFlags& f, ResponseKind kind) {
  TimeResponseOptions options = f.options;
  options.kind = kind;
  if (f.final_time_option->count() > 0) options.final_time = f.final_time;
  if (f.sample_time_option->count() > 0) options.sample_time = f.sample_time;
  options.validate();  // named by its flags
  return options;
}

std::string seconds(double value, double error) { return plus_minus(value, error) + " s"; }

void print_characteristics(const StepCharacteristics& c, double settling_band) {
  if (!c.defined()) {
    if (std::isfinite(c.dc_gain.value)) {
      std::cout << "DC gain: " << plus_minus(c.dc_gain.value, c.dc_gain.standard_error) << "\n";
    } else {
      std::cout << "DC gain: none\n";
    }
    std::cout << "rise time, settling time, overshoot: not defined: " << c.not_defined_reason
              << "\n";
    return;
  }
  std::cout << "DC gain: " << plus_minus(c.dc_gain.value, c.dc_gain.standard_error) << "\n"
            << "rise time (10-90 %): " << seconds(c.rise_time.value, c.rise_time.standard_error)
            << "\n"
            << "settling time (" << format_number(100.0 * settling_band) << " %): "
            << (std::isfinite(c.settling_time.value)
                    ? seconds(c.settling_time.value, c.settling_time.standard_error)
                    : std::string("not found (the response has not settled)"))
            << "\n";
  if (c.overshoot_percent.value > 0.0) {
    std::cout << "overshoot: "
              << plus_minus(c.overshoot_percent.value, c.overshoot_percent.standard_error)
              << " %, peak at " << seconds(c.peak_time.value, c.peak_time.standard_error) << "\n";
  } else {
    std::cout << "overshoot: none (the response does not pass its final value)\n";
  }
  if (c.undershoot_percent.value > 0.0) {
    std::cout << "undershoot: "
              << plus_minus(c.undershoot_percent.value, c.undershoot_percent.standard_error)
              << " % (the response first goes the wrong way: non-minimum phase)\n";
  }
}

io::CsvTable response_table(const TimeResponse& r) {
  io::CsvTable table;
  table.add_column("t", r.time);
  table.add_column("y", r.output);
  if (r.standard_deviation.size() > 0) {
    table.add_column("y_std", r.standard_deviation);
    table.add_column("lower", r.lower);
    table.add_column("upper", r.upper);
  }
  return table;
}

// What the band comes from, after "by the delta method from ".
struct ResponseSource {
  std::string model;  // the model as text
  std::string covariance = "the parameter covariance";
  bool delay_error = false;  // the delay's standard error joins it
};

void print_summary(const ResponseFlags& f, const ResponseSource& source, const TimeResponse& r,
                   const std::string& command) {
  const bool band = r.standard_deviation.size() > 0;
  std::cout << "ctid " << command << ": " << f.model << "\n"
            << "model: " << source.model << "\n";
  print_characteristics(r.characteristics, f.options.settling_band);
  if (band) {
    std::cout << "± one standard error by the delta method from " << source.covariance;
    if (source.delay_error) std::cout << " and the delay's standard error";
    std::cout << "; band: ± " << format_brief(r.z) << " standard deviations ("
              << format_number(100.0 * f.options.confidence) << " %)\n";
  } else {
    std::cout << "no standard errors: " << f.model << " holds no parameter covariance\n";
  }
  if (r.kind == ResponseKind::impulse) {
    std::cout << "characteristics above are of the step response\n";
    if (r.dirac_weight != 0.0) {
      std::cout << "the model is biproper: its impulse response also has a Dirac impulse of "
                   "weight "
                << format_brief(r.dirac_weight) << " at the delay, not in the table\n";
    }
  }
  std::cout << r.time.size() << " points from 0 to " << format_brief(r.time(r.time.size() - 1))
            << " s\n";
}

void run_response(const ResponseFlags& f, ResponseKind kind) {
  const std::string command(enum_name(kind));
  if (f.points_option->count() > 0 && f.sample_time_option->count() > 0) {
    usage_error("--points and --sample-time both set the grid; give one");
  }
  const nlohmann::json document = io::read_json(f.model);  // read once, judged by its type
  check_document_type(document, f.model, command);
  std::filesystem::path package;
  if (!f.plot.empty()) {
    package = require_plotting();
    prepare_plot_directory(f.plot, {command + ".png"}, f.force);
  }
  ResponseSource source;
  TimeResponse r;
  if (const std::optional<ProcessModelResult> process = process_result_in(document, f.model)) {
    r = time_response(*process, options_from(f, kind));
    source.model = process->structure + ": " + process->transfer_function().to_string();
    source.covariance = "the covariance of the process parameters";
  } else {
    const io::FittedModel fitted = io::fitted_model_from_json(document, f.model);
    r = time_response(fitted.model, fitted.covariance, options_from(f, kind),
                      fitted.delay_standard_error);
    source.model = fitted.model.to_string();
    source.delay_error = fitted.delay_standard_error > 0.0;
  }
  const io::CsvTable table = response_table(r);
  if (!f.output.empty()) {
    io::write_csv(f.output, table, f.force ? io::Overwrite::yes : io::Overwrite::no);
  }
  if (!f.quiet) print_summary(f, source, r, command);
  if (!f.plot.empty()) {
    const TemporaryDirectory scratch;
    const std::filesystem::path csv = scratch.path() / "response.csv";
    io::write_csv(csv, table);
    const std::filesystem::path figure = std::filesystem::path(f.plot) / (command + ".png");
    plot(package, {PlotJob{command, csv, figure,
                           "ctid " + command + " of " +
                               std::filesystem::path(f.model).filename().string()}});
    if (!f.quiet) std::cout << "wrote " << figure.string() << "\n";
  }
  if (!f.quiet && !f.output.empty()) std::cout << "wrote " << f.output << "\n";
}

Command add_response_command(CLI::App& parent, ResponseKind kind) {
  auto flags = std::make_shared<ResponseFlags>();
  ResponseFlags& f = *flags;
  const std::string name(enum_name(kind));
  CLI::App* app = parent.add_subcommand(
      name, "The " + name +
                " response of a fitted model with its characteristics (DC gain, rise and "
                "settling time, overshoot) ± one standard error and a confidence band.");
  app->footer(
      "MODEL: the result JSON of 'ctid fit' (its covariance gives the standard errors and the\n"
      "band) or a transfer_function / additive_model JSON (no standard errors).\n"
      "The response is exact (matrix exponential) at t = 0, h, 2h, ... up to --final-time,\n"
      "the input delay included. Characteristics are of the step response: rise time 10-90 %\n"
      "of the final value, settling time into ± --settling-band of it, overshoot and\n"
      "undershoot in % of it; not defined for a model with an integrator or an unstable pole.\n"
      "Output CSV columns: t, y and, with a covariance, y_std, lower, upper.\n"
      "Exit status: 0 ran, 2 bad usage or input, 1 other error.");
  app->add_option("model", f.model, "Result or model JSON")->required()->check(CLI::ExistingFile);
  f.final_time_option =
      app->add_option(flag_of<TimeResponseOptions>("final_time") + ",-t", f.final_time,
                      "Last time [s] (default: 1.5 settling times, or 10 time constants of the "
                      "slowest pole when the response does not settle)")
          ->check(positive_number());
  f.sample_time_option =
      app->add_option(flag_of<TimeResponseOptions>("sample_time") + ",-T", f.sample_time,
                      "Spacing of the grid [s] (instead of --points)")
          ->check(positive_number());
  FieldFlagSettings settings;
  settings.by_hand = {"final_time", "sample_time"};
  settings.none = {"kind"};  // the command: step or impulse
  add_field_flags(*app, f.options, settings);
  f.points_option = app->get_option("--points");
  app->add_option("--output,-o", f.output, "CSV to write: t, y[, y_std, lower, upper]")
      ->group("Output");
  app->add_option("--plot", f.plot, "Directory for " + name + ".png")->group("Output");
  app->add_flag("--force", f.force, "Replace output files that exist")->group("Output");
  app->add_flag("--quiet,-q", f.quiet, "Print nothing")->group("Output");
  Command command;
  command.app = app;
  command.run = [flags, kind] {
    run_response(*flags, kind);
    return kExitOk;
  };
  return command;
}

Command add_step_command(CLI::App& parent) {
  return add_response_command(parent, ResponseKind::step);
}
Command add_impulse_command(CLI::App& parent) {
  return add_response_command(parent, ResponseKind::impulse);
}

}  // namespace

CTID_REGISTER_COMMAND(32, add_step_command);
CTID_REGISTER_COMMAND(33, add_impulse_command);

}  // namespace ctid::cli
