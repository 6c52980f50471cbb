// `ctid track`: follows the modes of one channel through time (issue 17) with the library's
// track_modes (identification/mode_tracking.h): consecutive windows of the record, each fitted with
// a warm start from the previous window's model, the modes matched into tracks; several outputs
// with track_mimo_modes, and records with no input (--output-only) with track_output_only_modes.
// Writes the whole result as JSON (io/tracking_json.h), the per-window table as CSV and the
// tracking figure, and prints one line per track.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "command.h"
#include "ctid/core/error.h"
#include "ctid/core/fields.h"
#include "ctid/core/format.h"
#include "ctid/identification/mode_tracking.h"
#include "ctid/io/fields_json.h"
#include "ctid/io/json.h"
#include "ctid/io/model_json.h"
#include "ctid/io/provenance.h"
#include "ctid/io/result_json.h"
#include "ctid/io/tracking_json.h"
#include "data_flags.h"
#include "field_flags.h"
#include "output_only_data.h"
#include "plot_support.h"
#include "progress.h"
#include "structure_flags.h"

namespace ctid::cli {
namespace {

struct TrackFlags {
  DataFlags data;

  std::string model;
  int poles = 0;
  int zeros = 0;
  int integrators = 0;
  std::vector<std::string> submodels;
  int modes = 0;

  // Every field a flag (field_flags.h) but those read in another form below (the controller,
  // the start and initial_model) and those a window's fit does not take from the command line
  // (kNoFlag). Each window's initial state is estimated by default, as the several-output
  // estimator's (MimoTrackingOptions).
  TrackingOptions options = [] {
    TrackingOptions o;
    o.identification.refined_iv.initial_conditions = InitialConditions::estimate;
    return o;
  }();
  // Several outputs: MimoTrackingOptions' own fields a flag each (--mac-weight, --min-mac,
  // --direct, --rank-one, ...); those it shares with TrackingOptions come from the flags above.
  MimoTrackingOptions mimo;
  // No input (--output-only): each window analysed by ctid oma's method; OmaTrackingOptions'
  // own fields a flag each (its window and gates come from the flags above).
  bool output_only = false;
  OmaTrackingOptions oma;
  std::vector<std::string> reference_columns;
  std::string controller;
  std::string start = "auto";
  std::string initial;

  std::string output;
  std::string table;
  std::string plot;
  bool force = false;
  bool quiet = false;
};

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Fields of TrackingOptions with no flag: a delay scan, a continuous delay, a two-stage fit and
// per-record delays are whole-record questions, not one window's (decision 0051).
const std::vector<std::string> kNoFlag = {
    "identification.delay_scan_samples", "identification.delay_range", "identification.two_stage",
    "identification.refined_iv.record_delay_samples",
    // The polish and the constraints are ctid fit's (decision 0057).
    "identification.polish", "identification.polish_options", "identification.constraints"};

TrackingOptions tracking_options(const TrackFlags& f) {
  TrackingOptions options = f.options;
  IdentificationOptions& identification = options.identification;
  if (!f.controller.empty()) {
    identification.controller = io::read_discrete_transfer_function(f.controller);
  }
  RefinedIvOptions& refined = identification.refined_iv;
  if (!f.initial.empty() && f.start != "auto") usage_error("give --start or --initial, not both");
  if (!f.initial.empty()) refined.initial_model = io::read_fitted_model(f.initial).model;
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
  return options;
}

// "1, 4 and 9" (at most `shown` numbers, then "...").
std::string window_list(const std::vector<int>& windows, std::size_t shown = 10) {
  std::string text;
  for (std::size_t i = 0; i < windows.size() && i < shown; ++i) {
    if (i > 0) text += (i + 1 == windows.size()) ? " and " : ", ";
    text += std::to_string(windows[i]);
  }
  if (windows.size() > shown) text += ", ...";
  return text;
}

// The summary of either result (a MimoTrackingResult's tracks add their smallest MAC).
template <class Result, class Data>
void print_summary(std::ostream& out, const Result& r, const Data& data, const std::string& file) {
  const double h = data.sample_time();
  out << "ctid track: " << r.windows.size() << " windows of " << format_number(r.window_samples * h)
      << " s (" << r.window_samples << " samples, step " << r.step_samples << ") on " << file
      << " (N = " << data.size() << ", h = " << format_number(h) << " s";
  if constexpr (std::is_same_v<Result, MimoTrackingResult>) {
    out << ", " << data.output_count() << " outputs, " << data.input_count()
        << (data.input_count() == 1 ? " input" : " inputs");
  }
  out << ")\n";
  int warm = 0;
  for (const auto& w : r.windows) warm += w.start == WindowStart::previous_window;
  out << "usable windows: " << r.usable_windows << " of " << r.windows.size()
      << "; warm starts: " << warm << "\n";
  for (std::size_t t = 0; t < r.tracks.size(); ++t) {
    const auto& track = r.tracks[t];
    out << "track " << t + 1
        << ": mean f_n = " << format_significant(track.mean_natural_frequency / kTwoPi, 6)
        << " Hz, drift " << format_brief(track.frequency_drift / kTwoPi) << " Hz ("
        << format_brief(100.0 * track.frequency_drift / track.mean_natural_frequency)
        << " %), matched in " << track.windows_matched << " of " << r.windows.size() << " windows";
    if constexpr (std::is_same_v<Result, MimoTrackingResult>) {
      double smallest = std::numeric_limits<double>::infinity();
      for (double mac : track.mac) {
        if (std::isfinite(mac)) smallest = std::min(smallest, mac);
      }
      if (std::isfinite(smallest)) out << ", smallest MAC " << format_significant(smallest, 4);
    }
    out << "\n";
  }
}

// The warning about windows without a usable model (empty when every window is usable).
template <class Result>
std::string unusable_warning(const Result& r) {
  std::vector<int> unusable;
  for (std::size_t w = 0; w < r.windows.size(); ++w) {
    if (!r.windows[w].verdict.usable) unusable.push_back(static_cast<int>(w) + 1);
  }
  if (unusable.empty()) return "";
  return internal::concat(
      "WARNING: ", unusable.size(), " of ", r.windows.size(),
      " windows gave no usable model (window", unusable.size() > 1 ? "s " : " ",
      window_list(unusable), "); their modes are not tracked. First reason: ",
      r.windows[static_cast<std::size_t>(unusable.front() - 1)].verdict.summary());
}

// The checks of the windows and of the output paths both paths share.
void check_windows_and_outputs(const TrackFlags& f) {
  const std::optional<double>& step = f.options.step;
  if (step && !(*step > 0.0))
    usage_error("--step is " + format_number(*step) + " s; it must be > 0");
  const double window = f.options.window;
  if (!(window > 0.0)) usage_error("--window is " + format_number(window) + " s; it must be > 0");
  const bool force = f.force;
  if (!f.table.empty()) {
    // The table may not be the data or the JSON output (the frame checks --output alone).
    const auto same = [&](const std::string& other) {
      std::error_code ignored;
      return other == f.table || std::filesystem::equivalent(other, f.table, ignored);
    };
    if (same(f.data.file)) {
      usage_error("--table '" + f.table + "' is the input file '" + f.data.file +
                  "' (data); writing it would destroy the input, so nothing was run");
    }
    if (!f.output.empty() && same(f.output)) {
      usage_error("--table and --output name the same file " + f.table);
    }
  }
  if (!f.table.empty() && !force && std::filesystem::exists(f.table)) {
    usage_error("--table " + f.table + " exists; pass --force to replace it");
  }
}

// Writes the document, the table and the figure, and prints the summary; the exit status.
template <class Result, class Data>
ExitStatus report(const TrackFlags& f, const CLI::App& app, const Result& result, const Data& data,
                  nlohmann::json document, const std::filesystem::path& package) {
  const io::Overwrite overwrite = f.force ? io::Overwrite::yes : io::Overwrite::no;
  if (!f.output.empty()) io::write_json(f.output, document, overwrite);
  if (!f.table.empty()) io::write_tracking_table(f.table, result, overwrite);

  const std::string warning = unusable_warning(result);
  if (!f.quiet) {
    if (!warning.empty()) std::cout << warning << "\n";
    print_summary(std::cout, result, data, f.data.file);
    if (f.data.preprocessing_asked(app)) {
      std::cout << "preprocessing: " << f.data.preprocessing.summary() << "\n";
    }
    if (!f.output.empty()) std::cout << "wrote " << f.output << "\n";
    if (!f.table.empty()) std::cout << "wrote " << f.table << "\n";
  } else if (!warning.empty()) {
    std::cerr << "ctid track: " << warning << "\n";
  }
  if (!f.plot.empty() && !result.tracks.empty()) {
    const TemporaryDirectory work;
    io::write_json(work.path() / "tracking.json", document);
    const std::filesystem::path figure = std::filesystem::path(f.plot) / "tracking.png";
    plot(package, {{"tracking", work.path() / "tracking.json", figure,
                    "ctid track: " + std::filesystem::path(f.data.file).filename().string()}});
    if (!f.quiet) std::cout << "wrote " << figure.string() << "\n";
  }
  return result.usable_windows == 0 ? kExitNoUsableModel : kExitOk;
}

// Several outputs (--input-columns / --output-columns): track_mimo_modes, shared poles and
// matching by mode shape as well (docs/decisions/0026-mimo-tracking.md).
ExitStatus run_mimo_track(const TrackFlags& f, const CLI::App& app) {
  ModelStructure structure = model_structure(f, app);
  // --modes K: first-degree numerators, as ctid fit gives every mode of several channels.
  if (app.count("--modes") > 0) {
    structure = ModelStructure::additive(
        std::vector<SubmodelOrder>(static_cast<std::size_t>(f.modes), SubmodelOrder{2, 1, 0}));
  }
  if (!structure.is_additive()) {
    usage_error(
        "with --input-columns / --output-columns give the modes (--modes K or --submodel N,M "
        "repeated); an unfactored model has no shared modes");
  }
  if (f.start != "auto" || !f.initial.empty()) {
    usage_error((f.initial.empty() ? "--start " + f.start : "--initial") +
                " is for one input and output; with --input-columns / --output-columns every "
                "window without a warm start starts automatically");
  }
  // Every fit flag the shared-pole windows do not read is refused, derived from the field tables.
  std::set<std::string> taken = {"--model",    "--poles", "--zeros", "--integrators",
                                 "--submodel", "--modes", "--start"};
  for (const std::string& name : shared_field_names<MimoTrackingOptions, TrackingOptions>()) {
    taken.insert(flag_of<TrackingOptions>(name));
  }
  for (const std::string& name : shared_field_names<MimoRefinedIvOptions, RefinedIvOptions>()) {
    taken.insert(flag_of<TrackingOptions>("identification.refined_iv." + name));
  }
  refuse_flags_not_taken(app, {"Structure", "Iteration"}, taken,
                         " is not available with --input-columns / --output-columns (the "
                         "shared-pole estimator is open loop, without input delays here)");
  check_windows_and_outputs(f);
  std::filesystem::path package;
  if (!f.plot.empty()) {
    package = require_plotting();
    prepare_plot_directory(f.plot, {"tracking.png"}, f.force);
  }
  MimoTrackingOptions options = f.mimo;
  assign_shared_fields(options, f.options);
  assign_shared_fields(options.refined_iv, f.options.identification.refined_iv);
  options.validate();
  const MimoData data = f.data.load_mimo(app);

  Progress progress("ctid track", f.quiet);
  const MimoTrackingResult result =
      track_mimo_modes(data, structure.orders, options, progress.callback("window"));
  progress.clear();

  nlohmann::json document = io::to_json(result);
  document["data"] = io::to_json(io::DataProvenance{.files = {f.data.file},
                                                    .samples = data.size(),
                                                    .sample_time = data.sample_time(),
                                                    .start_time = data.start_time(),
                                                    .inputs = data.input_names(),
                                                    .outputs = data.output_names()});
  document["structure"] = io::fields_to_json(structure);
  document["options"] = io::fields_to_json(options);
  return report(f, app, result, data, std::move(document), package);
}

// The length and sample time of an output-only record, as report() asks of its data.
struct OutputOnlyView {
  const OutputOnlyRecord& record;
  int size() const { return static_cast<int>(record.outputs.rows()); }
  double sample_time() const { return record.sample_time; }
  int output_count() const { return static_cast<int>(record.outputs.cols()); }
  int input_count() const { return 0; }
};

// No input (--output-only, issue 34's monitoring): track_output_only_modes, each window analysed
// by oma() and the modes matched by frequency, damping and shape (decision 0060).
ExitStatus run_output_only_track(const TrackFlags& f, const CLI::App& app) {
  for (const char* flag :
       {"--input-columns", "--input-column", "--output-column", "--model", "--poles", "--zeros",
        "--integrators", "--submodel", "--modes", "--controller", "--start", "--initial"}) {
    if (app.get_option_no_throw(flag) != nullptr && app.count(flag) > 0) {
      usage_error(std::string(flag) +
                  " is not available with --output-only (no input, no model structure: each "
                  "window is analysed as ctid oma analyses a record)");
    }
  }
  if (f.data.output_columns.empty()) {
    usage_error("--output-only needs --output-columns, the response channels");
  }
  // The fit flags oma() does not read are refused, derived from the field tables.
  std::set<std::string> taken;
  for (const std::string& name : shared_field_names<OmaTrackingOptions, TrackingOptions>()) {
    taken.insert(flag_of<TrackingOptions>(name));
  }
  for (const std::string& name : shared_field_names<OmaTrackingOptions, MimoTrackingOptions>()) {
    taken.insert(flag_of<MimoTrackingOptions>(name));
  }
  refuse_flags_not_taken(app, {"Iteration", "Several outputs"}, taken,
                         " is not available with --output-only (no input, no model structure: "
                         "each window is analysed as ctid oma analyses a record)");
  check_windows_and_outputs(f);
  std::filesystem::path package;
  if (!f.plot.empty()) {
    package = require_plotting();
    prepare_plot_directory(f.plot, {"tracking.png"}, f.force);
  }
  OmaTrackingOptions options = f.oma;
  assign_shared_fields(options, f.mimo);     // mac_weight, min_mac
  assign_shared_fields(options, f.options);  // window, step, ...: their flags are TrackingOptions'
  const OutputOnlyRecord record = read_output_only(
      f.data.file, f.data.output_columns, f.data.time_column,
      app.count("--sample-time") > 0 ? std::optional<double>(f.data.sample_time) : std::nullopt,
      f.data.preprocessing_asked(app) ? std::optional(f.data.preprocessing_options())
                                      : std::nullopt);
  for (const std::string& ref : f.reference_columns) {
    const auto at = std::find(record.names.begin(), record.names.end(), ref);
    if (at == record.names.end()) {
      usage_error("--reference-columns names '" + ref + "', which is not one of --output-columns");
    }
    options.oma.reference_channels.push_back(static_cast<int>(at - record.names.begin()));
  }
  options.validate();

  Progress progress("ctid track", f.quiet);
  const MimoTrackingResult result =
      track_output_only_modes(record.outputs, record.sample_time, record.start_time, record.names,
                              options, progress.callback("window"));
  progress.clear();

  nlohmann::json document = io::to_json(result);
  document["data"] =
      io::to_json(io::DataProvenance{.files = {f.data.file},
                                     .samples = static_cast<int>(record.outputs.rows()),
                                     .sample_time = record.sample_time,
                                     .start_time = record.start_time,
                                     .outputs = record.names,
                                     .preprocessing = record.preprocessing});
  document["options"] = io::fields_to_json(options);
  return report(f, app, result, OutputOnlyView{record}, std::move(document), package);
}

ExitStatus run_track(const TrackFlags& f, const CLI::App& app) {
  if (f.output_only) return run_output_only_track(f, app);
  refuse_flags_not_taken(app, {"Output-only"}, {}, " goes with --output-only");
  if (f.data.mimo_asked(app)) return run_mimo_track(f, app);
  refuse_flags_not_taken(app, {"Several outputs"}, {},
                         " goes with --input-columns / --output-columns");
  const ModelStructure structure = model_structure(f, app);
  check_windows_and_outputs(f);
  const bool force = f.force;
  std::filesystem::path package;
  if (!f.plot.empty()) {
    package = require_plotting();
    prepare_plot_directory(f.plot, {"tracking.png"}, force);
  }
  const TrackingOptions options = tracking_options(f);
  options.validate();
  validate_identification(structure, options.identification);
  const SampledData data = f.data.load(app, options.identification.controller.has_value());
  if (options.identification.controller &&
      !same_sample_time(options.identification.controller->sample_time(), data.sample_time())) {
    usage_error(internal::concat("the controller in ", f.controller, " has sample time ",
                                 format_number(options.identification.controller->sample_time()),
                                 " s but ", f.data.file, " is sampled every ",
                                 format_number(data.sample_time()), " s"));
  }
  // The windows are checked against the record before any fit (one line for a bad window).
  (void)window_layout(options, data.size(), data.sample_time());

  Progress progress("ctid track", f.quiet);
  const TrackingResult result = track_modes(data, structure, options, progress.callback("window"));
  progress.clear();

  nlohmann::json document = io::to_json(result);
  document["data"] = io::to_json(io::DataProvenance{.files = {f.data.file},
                                                    .samples = data.size(),
                                                    .sample_time = data.sample_time(),
                                                    .start_time = data.start_time(),
                                                    .preprocessing = f.data.preprocessing});
  document["structure"] = io::fields_to_json(structure);
  document["options"] = io::fields_to_json(options);
  return report(f, app, result, data, std::move(document), package);
}

Command add_track_command(CLI::App& parent) {
  auto flags = std::make_shared<TrackFlags>();
  TrackFlags& f = *flags;
  CLI::App* app = parent.add_subcommand(
      "track",
      "Follow the modes of one channel, or of several outputs with shared poles, through time: "
      "fit consecutive windows (each started from the previous window's model) and match their "
      "modes into tracks.");
  app->footer(
      "Windows: --window SECONDS long, starting every --step SECONDS (default: the window, "
      "adjacent windows), both rounded to whole samples; at least 2 windows must fit the "
      "record. Each window's initial state is estimated by default (--initial-conditions).\n"
      "Structure: as ctid fit (--modes K, --submodel N,M[,L] repeated, or --poles N --zeros M).\n"
      "Several outputs: --output-columns (and --input-columns) fit every window with the "
      "shared-pole estimator (--modes K gives each mode a first-degree numerator, as ctid fit) "
      "and add 1 - MAC of the mode shapes to the matching cost (--mac-weight), pairing a mode "
      "with a track only if their MAC is at least --min-mac; the table gets a mac column.\n"
      "No input: --output-only with --output-columns analyses every window as ctid oma does "
      "(its flags below, under Output-only) and matches the modes as for several outputs.\n"
      "Matching: a window's modes join the tracks by the least total cost |w - w_t|/w_t + "
      "--damping-weight |zeta - zeta_t| among the assignments with the most pairs; a mode more "
      "than --max-frequency-jump (relative) from every track starts a new one. Modes of windows "
      "without a usable model are not tracked.\n"
      "Output: -o TRACKING.json (mode_tracking_result, docs/formats.md), --table TRACKING.csv "
      "(one row per window and track), --plot DIR (tracking.png: frequency and damping against "
      "time with one standard error).\n"
      "Exit status: 0 ran and at least one window gave a usable model, 3 no window did (a "
      "WARNING line says why), 2 bad usage or input, 1 other error.");

  f.data.add_to(*app, "data", true);
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
                  "Additive: one submodel N,M[,L] (poles, zeros, integrators); repeat")
      ->take_all()
      ->allow_extra_args(false)
      ->group("Structure");
  app->add_option("--modes", f.modes, "Additive: K second-order modes (--submodel 2,0 K times)")
      ->group("Structure");
  app->add_option(flag_of<TrackingOptions>("identification.controller") + ",-c", f.controller,
                  "Discrete controller JSON (discrete_transfer_function in q): closed loop")
      ->check(CLI::ExistingFile)
      ->group("Structure");
  app->add_option(flag_of<TrackingOptions>("identification.refined_iv.start"), f.start,
                  "Start of the first window (and of windows after an unusable one): auto, "
                  "lssvf, frf, or a model/result JSON")
      ->capture_default_str()
      ->group("Iteration");
  app->add_option(flag_of<TrackingOptions>("identification.refined_iv.initial_model"), f.initial,
                  "Starting model or result JSON of the first window (same as --start FILE)")
      ->check(CLI::ExistingFile)
      ->group("Iteration");
  FieldFlagSettings settings;
  settings.group = "Iteration";
  settings.by_hand = {"identification.controller", "identification.continuous_controller",
                      "identification.refined_iv.start", "identification.refined_iv.initial_model"};
  settings.none = kNoFlag;
  add_field_flags(*app, f.options, settings);
  app->get_option("--window")->required();
  FieldFlagSettings mimo;
  mimo.group = "Several outputs";
  // Given by TrackingOptions' flags above (one --window, --max-iterations, ...).
  mimo.by_hand = shared_field_names<MimoTrackingOptions, TrackingOptions>();
  for (const std::string& name : shared_field_names<MimoRefinedIvOptions, RefinedIvOptions>()) {
    mimo.by_hand.push_back("refined_iv." + name);
  }
  // The start of several outputs' first window: --start and --initial are one channel's.
  mimo.by_hand.push_back("initial_model");
  add_field_flags(*app, f.mimo, mimo);
  app->add_flag("--output-only", f.output_only,
                "No input: analyse every window of the --output-columns as ctid oma does and "
                "match the modes by frequency, damping and shape")
      ->group("Output-only");
  app->add_option(flag_of<OmaTrackingOptions>("oma.reference_channels"), f.reference_columns,
                  "--output-only: reference channels (a subset of the outputs; default: all)")
      ->delimiter(',')
      ->group("Output-only");
  FieldFlagSettings oma;
  oma.group = "Output-only";
  oma.by_hand = shared_field_names<OmaTrackingOptions, MimoTrackingOptions>();
  oma.by_hand.push_back("oma.reference_channels");  // names of columns, above
  add_field_flags(*app, f.oma, oma);

  app->add_option("--output,-o", f.output, "Tracking JSON to write (the whole result)")
      ->group("Output");
  app->add_option("--table", f.table,
                  "CSV to write: one row per window and track (window, t_start, t_centre, t_end, "
                  "track, frequency_hz, frequency_se_hz, damping, damping_se, usable)")
      ->group("Output");
  app->add_option("--plot", f.plot,
                  "Directory for tracking.png (frequency and damping against time) drawn by "
                  "python3 -m ctid.plot")
      ->group("Output");
  app->add_flag("--force", f.force, "Replace output files that exist (never replaced otherwise)")
      ->group("Output");
  app->add_flag("--quiet,-q", f.quiet, "Print no summary")->group("Output");

  Command command;
  command.app = app;
  command.run = [flags, app] { return run_track(*flags, *app); };
  return command;
}

}  // namespace

CTID_REGISTER_COMMAND(27, add_track_command);

}  // namespace ctid::cli
