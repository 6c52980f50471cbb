// `ctid structure`: fits a range of structures (K modes, or unfactored n poles) with the
// library's scan_structures (identification/structure_scan.h), prints a table of how each fit ended
// and scores (estimation and held-out validation fit, YIC, RT2, AIC, BIC, usable), recommends
// one by the stated rule, and writes the scan with its stabilisation diagram as JSON. With
// --input-columns / --output-columns it scans mode counts of the shared-pole fit instead
// (scan_mimo_modes, identification/mimo_structure_scan.h, decision 0064).
#include <cmath>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "command.h"
#include "ctid/core/error.h"
#include "ctid/core/fields.h"
#include "ctid/core/format.h"
#include "ctid/identification/mimo_structure_scan.h"
#include "ctid/identification/structure_scan.h"
#include "ctid/identification/two_stage.h"
#include "ctid/io/json.h"
#include "ctid/io/model_json.h"
#include "ctid/io/provenance.h"
#include "ctid/io/report_json.h"
#include "data_flags.h"
#include "field_flags.h"
#include "plot_support.h"
#include "progress.h"

namespace ctid::cli {
namespace {

struct StructureFlags {
  DataFlags data;
  std::string modes;        // A:B
  std::string poles;        // A:B
  std::string zeros;        // M or A:B; empty: poles - 1
  std::string integrators;  // L or A:B; empty: 0
  // Every field a flag (field_flags.h) but the controller and delay_scan, read from a file and
  // as A:B below, and those no scan takes from the command line (kNoScanFlag).
  StructureScanOptions options;
  MimoRefinedIvOptions mimo;  ///< several channels: the fields not shared with refined_iv
  std::string controller;
  bool two_stage = false;             // closed loop, unknown controller (decision 0071)
  TwoStageOptions two_stage_options;  // with --two-stage
  std::string delay_scan;             // A:B samples
  std::string output;
  std::string plot;
  bool force = false;
  bool quiet = false;
};

// Fields of StructureScanOptions with no flag: one start model does not suit structures of
// other orders, and a continuous delay and per-record delays are not scanned (decision 0051);
// the polish and the constraints named by coefficient are ctid fit's (0057).
const std::vector<std::string> kNoScanFlag = {"identification.refined_iv.initial_model",
                                              "identification.delay_range",
                                              "identification.refined_iv.record_delay_samples",
                                              "identification.polish",
                                              "identification.polish_options",
                                              "identification.constraints"};

// "A:B" (or "A") as an inclusive range of counts >= `least`.
std::pair<int, int> parse_range(const std::string& text, const std::string& flag, int least = 1) {
  const auto colon = text.find(':');
  const std::string low = text.substr(0, colon);
  const std::string high = colon == std::string::npos ? low : text.substr(colon + 1);
  const auto parse = [&](const std::string& part) {
    const std::optional<int> value = parse_number<int>(part);
    if (!value || *value < least) {
      usage_error(flag + " '" + text + "': expected MIN:MAX, integers >= " + std::to_string(least) +
                  ", e.g. " + std::to_string(least) + ":6");
    }
    return *value;
  };
  const int a = parse(low);
  const int b = parse(high);
  if (b < a) usage_error(flag + " '" + text + "': MAX is below MIN");
  if (b - a > 31) usage_error(flag + " '" + text + "': at most 32 structures per scan");
  return {a, b};
}

std::string describe(const ModelStructure& s) {
  std::ostringstream out;
  if (!s.is_additive()) {
    const SubmodelOrder& o = s.orders[0];
    out << "n=" << o.n << " m=" << o.m;
    if (o.integrators > 0) out << " l=" << o.integrators;
    return out.str();
  }
  out << s.orders.size() << (s.orders.size() == 1 ? " mode" : " modes");
  return out.str();
}

std::string fixed(double x, int decimals) {
  if (!std::isfinite(x)) return "-";
  return format_fixed(x, decimals);
}

void print_table(std::ostream& out, const StructureScanResult& r, const std::string& file) {
  out << "ctid structure: " << r.fits.size() << " structures on " << file << " ("
      << r.estimation_samples << " samples fitted, " << r.validation_samples << " held out)\n";
  out << "   structure    params  est.fit %  val.fit %      YIC     RT2          AIC          BIC"
         "  usable  termination\n";
  for (std::size_t i = 0; i < r.fits.size(); ++i) {
    const StructureFit& f = r.fits[i];
    out << (static_cast<int>(i) == r.recommended ? " * " : "   ") << std::left << std::setw(12)
        << describe(f.structure) << std::right << std::setw(7) << f.parameters << std::setw(11)
        << fixed(f.estimation_fit, 2) << std::setw(11) << fixed(f.validation_fit, 2) << std::setw(9)
        << fixed(f.yic, 2) << std::setw(8) << fixed(f.rt2, 4) << std::setw(13) << fixed(f.aic, 1)
        << std::setw(13) << fixed(f.bic, 1) << std::setw(8) << (f.usable ? "yes" : "no") << "  "
        << f.message << "\n";
  }
  if (r.recommended >= 0) {
    out << "recommended: " << describe(r.fits[static_cast<std::size_t>(r.recommended)].structure)
        << " (" << r.rule << ")\n";
  } else {
    out << "WARNING: " << r.rule << "; try other orders, a longer record or --start\n";
  }
}

// --plot DIR checked before any work; the plotting package (empty without --plot).
std::filesystem::path prepare_plot(const StructureFlags& f) {
  if (f.plot.empty()) return {};
  std::filesystem::path package = require_plotting();
  prepare_plot_directory(f.plot, {"stabilisation.png"}, f.force);
  return package;
}

// Writes -o (the scan's `document` with its data), prints the table (`print`), draws --plot;
// exit 3 when no fit is recommended.
ExitStatus finish_scan(const StructureFlags& f, const std::filesystem::path& package,
                       nlohmann::json document, int samples, double sample_time, int recommended,
                       const std::function<void(std::ostream&)>& print) {
  document["data"] = io::to_json(
      io::DataProvenance{.files = {f.data.file}, .samples = samples, .sample_time = sample_time});
  if (!f.output.empty()) {
    io::write_json(f.output, document, f.force ? io::Overwrite::yes : io::Overwrite::no);
  }
  if (!f.quiet) {
    print(std::cout);
    if (!f.output.empty()) std::cout << "wrote " << f.output << "\n";
  }
  if (!f.plot.empty()) {
    const TemporaryDirectory work;
    io::write_json(work.path() / "scan.json", document);
    plot(package, {{"stabilisation", work.path() / "scan.json",
                    std::filesystem::path(f.plot) / "stabilisation.png",
                    "ctid structure: " + std::filesystem::path(f.data.file).filename().string()}});
  }
  return recommended < 0 ? kExitNoUsableModel : kExitOk;
}

std::string mean_of(const Eigen::VectorXd& v, int decimals) {
  return v.size() == 0 ? "-" : fixed(v.mean(), decimals);
}

void print_mimo_table(std::ostream& out, const MimoStructureScanResult& r, const MimoData& data,
                      const std::string& file) {
  out << "ctid structure: " << r.fits.size() << " mode counts on " << file << " ("
      << data.input_count() << " inputs, " << data.output_count() << " outputs; "
      << r.estimation_samples << " samples fitted, " << r.validation_samples << " held out)\n";
  out << "   modes  est.fit %  val.fit %  val.error  usable  termination\n";
  out << "          (means over the outputs)\n";
  for (std::size_t i = 0; i < r.fits.size(); ++i) {
    const MimoStructureFit& f = r.fits[i];
    out << (static_cast<int>(i) == r.recommended ? " * " : "   ") << std::left << std::setw(5)
        << f.modes << std::right << std::setw(11) << mean_of(f.estimation_fit, 2) << std::setw(11)
        << mean_of(f.validation_fit, 2) << std::setw(11) << fixed(f.validation_error, 5)
        << std::setw(8) << (f.usable ? "yes" : "no") << "  " << f.message << "\n";
  }
  if (r.recommended >= 0) {
    out << "recommended: " << r.fits[static_cast<std::size_t>(r.recommended)].modes << " modes ("
        << r.rule << ")\n";
  } else {
    out << "WARNING: " << r.rule << "; try other counts or a longer record\n";
  }
}

// With several channels, every "Choice and fits" flag of the one-channel scan that the
// shared-pole scan does not use (all but the scan's own four and the estimator fields the two
// estimators share, assign_shared_fields) is refused rather than ignored.
void refuse_single_channel_fit_flags(const CLI::App& app) {
  std::set<std::string> used;
  for (const char* field :
       {"validation_fraction", "error_tolerance", "frequency_tolerance", "damping_tolerance"}) {
    used.insert(flag_of<StructureScanOptions>(field));
  }
  for (const std::string& name : shared_field_names<MimoRefinedIvOptions, RefinedIvOptions>()) {
    used.insert(flag_of<StructureScanOptions>("identification.refined_iv." + name));
  }
  refuse_flags_not_taken(app, {"Choice and fits"}, used,
                         " is for one input and output; with --input-columns / --output-columns "
                         "the shared-pole fit takes the flags of 'Several inputs and outputs'");
}

// Several inputs and outputs: mode counts of the shared-pole fit (decision 0064).
ExitStatus run_mimo_structure(const StructureFlags& f, const CLI::App& app) {
  if (f.modes.empty()) usage_error("with --input-columns / --output-columns give --modes MIN:MAX");
  for (const char* flag : {"--poles", "--zeros", "--integrators", "--controller", "--two-stage",
                           "--delay-scan-samples"}) {
    if (app.count(flag) > 0) {
      usage_error(std::string(flag) +
                  " is for one input and output; with --input-columns / --output-columns the "
                  "scan is over --modes");
    }
  }
  refuse_single_channel_fit_flags(app);
  const auto [low, high] = parse_range(f.modes, "--modes");
  std::vector<int> counts;
  for (int k = low; k <= high; ++k) counts.push_back(k);
  MimoStructureScanOptions options;
  assign_shared_fields(options, f.options);  // the scan's own four, by the field tables
  options.identification.refined_iv = f.mimo;
  assign_shared_fields(options.identification.refined_iv, f.options.identification.refined_iv);
  options.validate();
  const std::filesystem::path package = prepare_plot(f);
  const MimoData data = f.data.load_mimo(app);
  Progress progress("ctid structure", f.quiet);
  const MimoStructureScanResult result =
      scan_mimo_modes(data, counts, options, progress.callback("mode counts"));
  progress.clear();
  return finish_scan(f, package, io::to_json(result), data.size(), data.sample_time(),
                     result.recommended,
                     [&](std::ostream& out) { print_mimo_table(out, result, data, f.data.file); });
}

ExitStatus run_structure(const StructureFlags& f, const CLI::App& app) {
  if (f.data.mimo_asked(app)) return run_mimo_structure(f, app);
  refuse_flags_not_taken(app, {"Several inputs and outputs"}, {},
                         " goes with --input-columns / --output-columns");
  const bool modes = !f.modes.empty();
  const bool poles = !f.poles.empty();
  if (modes == poles) usage_error("give one range: --modes MIN:MAX or --poles MIN:MAX");
  if (modes && (!f.zeros.empty() || !f.integrators.empty())) {
    usage_error("--zeros and --integrators go with --poles");
  }
  if (!f.delay_scan.empty() && app.count("--input-delay-samples") > 0) {
    usage_error("give --input-delay-samples or --delay-scan-samples, not both");
  }
  std::vector<ModelStructure> candidates;
  const auto [l_low, l_high] =
      f.integrators.empty() ? std::pair{0, 0} : parse_range(f.integrators, "--integrators", 0);
  if (l_high > io::kMaxIntegrators) {
    usage_error(internal::concat("--integrators goes up to ", l_high,
                                 "; a model document holds at most ", io::kMaxIntegrators,
                                 ", so ctid could not read such a model back"));
  }
  // A pure integrator (0 poles besides the origin) is a candidate when integrators are scanned.
  const auto [low, high] =
      parse_range(modes ? f.modes : f.poles, modes ? "--modes" : "--poles", l_high > 0 ? 0 : 1);
  // Zeros given once for every structure (parsed here, once); none: n + l - 1 for each.
  const std::pair<int, int> zeros =
      f.zeros.empty() ? std::pair{-1, -1} : parse_range(f.zeros, "--zeros", 0);
  for (int k = low; k <= high; ++k) {
    if (modes) {
      candidates.push_back(ModelStructure::modes(k));
      continue;
    }
    for (int l = l_low; l <= l_high; ++l) {
      if (k + l == 0) continue;
      // Every zero count of --zeros that keeps the model proper.
      const int m_low = f.zeros.empty() ? k + l - 1 : zeros.first;
      const int m_high = f.zeros.empty() ? k + l - 1 : zeros.second;
      if (m_low > k + l) {
        usage_error("--zeros " + f.zeros + " exceeds the " + std::to_string(k + l) +
                    " poles of a structure in --poles " + f.poles + " (an improper model)");
      }
      for (int m = m_low; m <= std::min(m_high, k + l); ++m) {
        candidates.push_back(ModelStructure::unfactored(k, m, l));
      }
    }
  }
  if (candidates.size() > 64) {
    usage_error("the flags ask for " + std::to_string(candidates.size()) +
                " structures; at most 64 per scan");
  }
  const std::filesystem::path package = prepare_plot(f);
  StructureScanOptions options = f.options;
  if (!f.controller.empty()) {
    read_controller(f.controller, options.identification.controller,
                    options.identification.continuous_controller);
  }
  if (f.two_stage) options.identification.two_stage = f.two_stage_options;
  if (!f.delay_scan.empty()) {
    const auto [d_low, d_high] = parse_range(f.delay_scan, "--delay-scan-samples", 0);
    options.identification.delay_scan_samples = DelayRange{d_low, d_high};
  }
  options.validate();
  const SampledData data = f.data.load(app, !f.controller.empty() || f.two_stage);
  Progress progress("ctid structure", f.quiet);
  const StructureScanResult result =
      scan_structures(data, candidates, options, progress.callback("structure"));
  progress.clear();
  return finish_scan(f, package, io::to_json(result), data.size(), data.sample_time(),
                     result.recommended,
                     [&](std::ostream& out) { print_table(out, result, f.data.file); });
}

Command add_structure_command(CLI::App& parent) {
  auto flags = std::make_shared<StructureFlags>();
  StructureFlags& f = *flags;
  CLI::App* app = parent.add_subcommand(
      "structure",
      "Fit a range of structures and recommend one: estimation and held-out validation fit, "
      "YIC, RT2, AIC, BIC, and a stabilisation diagram of the poles.");
  app->footer(
      "The last --validation-fraction of the record is held out: every estimate is simulated "
      "over the whole record (from rest, or from its fitted initial state; with --controller, "
      "from rest through the loop from r; with --two-stage, from the input stage 1 simulates "
      "from r) and scored there. Recommended: the fewest parameters "
      "among usable fits whose held-out mean squared error is within --error-tolerance "
      "(relative; default 2 sqrt(2 / held-out samples)) of the best.\n"
      "-o SCAN.json writes every fit, the recommendation and the stabilisation diagram.\n"
      "Exit status: 0 ran, 3 ran but no structure gave a usable model, 2 bad usage or input, 1 "
      "other error.");
  f.data.add_to(*app, "data", true);
  f.data.add_mimo_columns(*app);
  app->add_option("--modes", f.modes,
                  "Additive: numbers of second-order modes, MIN:MAX (with --input-columns / "
                  "--output-columns: modes shared by every channel, 2 poles and 1 zero each)")
      ->group("Structures");
  app->add_option("--poles", f.poles, "Unfactored: numbers of poles n, MIN:MAX")
      ->group("Structures");
  app->add_option("--zeros", f.zeros,
                  "Unfactored: zeros m, M or MIN:MAX (each with every --poles; default n + l - 1; "
                  "m = n + l adds a direct term)")
      ->group("Structures");
  app->add_option("--integrators", f.integrators,
                  "Unfactored: poles at the origin l, L or MIN:MAX (default 0; with l >= 1 "
                  "--poles may start at 0, a pure integrator)")
      ->group("Structures");
  app->add_option(flag_of<StructureScanOptions>("identification.controller") + ",-c", f.controller,
                  "Controller JSON, a discrete_transfer_function (digital) or a "
                  "transfer_function (analog): closed loop (the data need the reference)")
      ->check(CLI::ExistingFile)
      ->group("Structures");
  add_two_stage_flags(*app, f.two_stage, f.two_stage_options,
                      flag_of<StructureScanOptions>("identification.two_stage"),
                      "StructureScanOptions.identification.two_stage", "Structures",
                      "Closed loop with an unknown controller: every structure's plant fitted "
                      "from the input simulated by a model of r -> u, and scored from it (needs "
                      "the reference column; decisions 0043, 0071)");
  app->add_option(flag_of<StructureScanOptions>("identification.delay_scan_samples"), f.delay_scan,
                  "Scan the input delay MIN:MAX (samples) in every structure; each keeps its best")
      ->group("Structures");
  FieldFlagSettings settings;
  settings.group = "Choice and fits";
  settings.by_hand = {"identification.controller", "identification.continuous_controller",
                      "identification.two_stage", "identification.delay_scan_samples"};
  settings.none = kNoScanFlag;
  add_field_flags(*app, f.options, settings);
  FieldFlagSettings mimo;
  mimo.group = "Several inputs and outputs";
  // Given by the identification.refined_iv flags above (one --max-iterations, ...).
  mimo.by_hand = shared_field_names<MimoRefinedIvOptions, RefinedIvOptions>();
  add_field_flags(*app, f.mimo, mimo);
  app->add_option("--output,-o", f.output, "Scan JSON to write")->group("Output");
  app->add_option("--plot", f.plot, "Directory for stabilisation.png (the stabilisation diagram)")
      ->group("Output");
  app->add_flag("--force", f.force, "Replace an output file that exists")->group("Output");
  app->add_flag("--quiet,-q", f.quiet, "Print nothing")->group("Output");

  Command command;
  command.app = app;
  command.run = [flags, app] { return run_structure(*flags, *app); };
  return command;
}

}  // namespace

CTID_REGISTER_COMMAND(25, add_structure_command);

}  // namespace ctid::cli
