// ctid oma: output-only (operational) modal analysis of several response channels with no
// measured input: covariance-driven SSI over orders 2..--max-order, the stable poles clustered
// into modes, standard errors by first-order perturbation or from segments; or the peaks of the
// output spectral matrix's first singular value (fdd, efdd) (ctid::identify_output_only, the front
// door of ctid::oma: identification/output_only.h; docs/oma.md).
// Several files are setups of one structure with shared --reference-columns, merged by PoSER
// or PreGER (oma/multi_setup.h). Prints the modes and the verdict; -o writes an "oma_result"
// document. Exit 3 when no mode was found.
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
#include "ctid/core/mimo_preprocessing.h"
#include "ctid/identification/output_only.h"
#include "ctid/io/csv.h"
#include "ctid/io/fields_json.h"
#include "ctid/io/json.h"
#include "ctid/io/mimo_data_csv.h"
#include "ctid/io/npy.h"
#include "ctid/io/provenance.h"
#include "ctid/io/report_json.h"
#include "data_flags.h"
#include "field_flags.h"
#include "output_only_data.h"
#include "plot_support.h"

namespace ctid::cli {
namespace {

struct OmaFlags {
  std::vector<std::string> files;
  std::vector<std::string> output_columns;
  std::vector<std::string> reference_columns;
  std::string time_column = "t";
  double sample_time = 0.0;
  OmaOptions options;           ///< every field a flag (field_flags.h) but reference_channels
  std::string merge = "poser";  // several setups (MultiSetupOptions, by hand)
  double merge_frequency_tolerance = MultiSetupOptions{}.frequency_tolerance;
  double merge_reference_mac = MultiSetupOptions{}.reference_mac;
  DataFlags prep;  ///< its preprocessing flags only (--rows, --time, --detrend, ...)
  std::string output;
  std::string plot;            // DIR for stabilisation.png
  std::string geometry;        // sensors CSV: shapes.png on their wireframe (decision 0063)
  std::string geometry_lines;  // lines CSV of that wireframe
  bool force = false;
  bool quiet = false;
};

// "-" for a quantity the method does not estimate (fdd's damping).
std::string with_error(double value, double error, int digits) {
  if (!std::isfinite(value)) return "-";
  std::string text = format_significant(value, digits);
  if (std::isfinite(error)) text += " +- " + format_significant(error, 2);
  return text;
}

// The preprocessing line: rows kept, trends removed, decimation, scale, N and h.
std::string preprocessing_summary(const PreprocessingRecord& p) {
  std::ostringstream out;
  out << "rows " << p.first_row << ":" << p.end_row << ", "
      << (p.detrend == Detrend::linear ? "each channel's line removed"
          : p.detrend == Detrend::mean ? "each channel's mean removed"
                                       : "no detrend");
  if (p.decimate > 1) out << ", decimated by " << p.decimate;
  if (p.output_scale != 1.0) out << ", scaled by " << format_brief(p.output_scale);
  out << ", N = " << p.samples << ", h = " << format_number(p.sample_time) << " s";
  return out.str();
}

void print_summary(const OmaFlags& f, const OmaResult& r,
                   const std::optional<PreprocessingRecord>& preprocessing) {
  std::string files;
  for (const std::string& file : f.files) files += (files.empty() ? "" : ", ") + file;
  std::cout << "ctid oma: " << enum_name(r.method) << " on " << files << ": " << r.channels.size()
            << " channels, " << r.reference_channels.size() << " references, " << r.samples
            << " samples, h = " << format_brief(r.sample_time) << " s; " << r.message << "\n";
  if (preprocessing)
    std::cout << "preprocessing: " << preprocessing_summary(*preprocessing) << "\n";
  // fdd, efdd: no orders to count
  const bool ssi = r.method != OmaMethod::fdd && r.method != OmaMethod::efdd;  // orders
  if (!r.modes.empty()) {
    std::cout << "  mode  frequency [Hz]          damping ratio            MPC"
              << (ssi ? "    orders" : "") << "\n";
  }
  for (std::size_t i = 0; i < r.modes.size(); ++i) {
    const OmaMode& m = r.modes[i];
    std::ostringstream line;
    line << "  " << i + 1 << "     " << with_error(m.frequency_hz, m.frequency_hz_std, 6) << "    "
         << with_error(m.damping_ratio, m.damping_ratio_std, 3) << "    "
         << format_significant(m.mpc, 3);
    if (ssi) line << "    " << m.supporting_orders;
    std::cout << line.str() << "\n";
  }
  std::cout << (r.verdict.usable ? "verdict: usable" : r.verdict.summary()) << "\n";
  if (!f.output.empty()) std::cout << "wrote " << f.output << "\n";
}

// Several setups merged by PreGER: one global stabilisation diagram of its own.
bool global_diagram(const OmaFlags& f) {
  return f.files.size() > 1 && parse_enum_word<OmaMerge>("--merge", f.merge) == OmaMerge::preger;
}

// The figures --plot DIR may draw: stabilisation.png (with several setups one per setup, and
// PreGER's global one), and shapes.png and mac.png of the modes found.
std::vector<std::string> figure_names(const OmaFlags& f) {
  std::vector<std::string> names;
  if (f.files.size() == 1 || global_diagram(f)) names.push_back("stabilisation.png");
  for (std::size_t k = 1; f.files.size() > 1 && k <= f.files.size(); ++k) {
    names.push_back("stabilisation_setup" + std::to_string(k) + ".png");
  }
  names.push_back("shapes.png");
  names.push_back("mac.png");
  return names;
}

// One stabilisation diagram to draw: its document and the figure's title.
struct Diagram {
  nlohmann::json document;
  std::string title;
};

// --plot DIR: the stabilisation diagrams (from `diagrams`, in the order of figure_names), and
// when modes were found their shapes and auto-MAC (from `document`), each drawn from its
// document written to a temporary directory.
void draw_figures(const std::filesystem::path& package, const OmaFlags& f,
                  const nlohmann::json& document, const std::vector<Diagram>& diagrams) {
  const TemporaryDirectory work;
  const std::vector<std::string> names = figure_names(f);
  const std::filesystem::path dir(f.plot);
  std::vector<PlotJob> jobs;
  for (std::size_t k = 0; k < diagrams.size(); ++k) {
    const std::filesystem::path input = work.path() / ("oma" + std::to_string(k) + ".json");
    io::write_json(input, diagrams[k].document);
    jobs.push_back({"oma_stabilisation", input, dir / names[k], diagrams[k].title});
  }
  if (!document["modes"].empty()) {
    const std::filesystem::path input = work.path() / "modes.json";
    io::write_json(input, document);
    std::vector<std::string> geometry;
    if (!f.geometry.empty()) geometry = {"--geometry", f.geometry};
    if (!f.geometry_lines.empty()) {
      geometry.insert(geometry.end(), {"--geometry-lines", f.geometry_lines});
    }
    jobs.push_back({"oma_shapes", input, dir / "shapes.png", "mode shapes", geometry});
    jobs.push_back({"oma_mac", input, dir / "mac.png", "auto-MAC"});
  }
  plot(package, jobs);
  if (f.quiet) return;
  for (const PlotJob& job : jobs) std::cout << "wrote " << job.output.string() << "\n";
}

// One file's record, preprocessed as the flags say.
OutputOnlyRecord read_setup(const OmaFlags& f, const CLI::App& app, const std::string& file) {
  return read_output_only(
      file, f.output_columns, f.time_column,
      app.count("--sample-time") > 0 ? std::optional<double>(f.sample_time) : std::nullopt,
      f.prep.preprocessing_asked(app) ? std::optional(f.prep.preprocessing_options())
                                      : std::nullopt);
}

// Writes -o, prints, draws; the exit status from the verdict.
ExitStatus finish(const OmaFlags& f, const std::filesystem::path& package, const OmaResult& result,
                  const nlohmann::json& document,
                  const std::optional<PreprocessingRecord>& preprocessing,
                  const std::vector<Diagram>& diagrams) {
  if (!f.output.empty()) {
    io::write_json(f.output, document, f.force ? io::Overwrite::yes : io::Overwrite::no);
  }
  if (!f.quiet) print_summary(f, result, preprocessing);
  if (!f.plot.empty()) draw_figures(package, f, document, diagrams);
  return result.verdict.usable ? kExitOk : kExitNoUsableModel;
}

// "ctid oma on FILE", a diagram's title.
std::string title_of(const std::string& file) {
  return "ctid oma on " + std::filesystem::path(file).filename().string();
}

// Several files: setups of one structure merged by PoSER (decision 0059) or PreGER (decision
// 0062). The document is the merged oma_result with each setup's own under "setups".
ExitStatus run_setups(const OmaFlags& f, const CLI::App& app,
                      const std::filesystem::path& package) {
  if (f.reference_columns.empty()) {
    usage_error(
        "several files are setups of one structure: give --reference-columns, the "
        "channels every setup measures");
  }
  if (!f.output_columns.empty()) {
    usage_error(
        "--output-columns is for one file; with several setups each file's channels are "
        "its columns other than the time column");
  }
  MultiSetupOptions options;
  options.oma = f.options;
  options.reference_names = f.reference_columns;
  options.merge = parse_enum_word<OmaMerge>("--merge", f.merge);
  options.frequency_tolerance = f.merge_frequency_tolerance;
  options.reference_mac = f.merge_reference_mac;
  std::vector<OmaSetup> setups;
  std::vector<std::optional<PreprocessingRecord>> records;
  for (const std::string& file : f.files) {
    OutputOnlyRecord s = read_setup(f, app, file);
    setups.push_back({std::move(s.outputs), s.sample_time, std::move(s.names)});
    records.push_back(std::move(s.preprocessing));
  }
  const MultiSetupResult result = identify_output_only(setups, options);
  nlohmann::json document = io::to_json(result.merged);
  document["data"] = io::to_json(io::DataProvenance{.files = f.files});
  document["setups"] = nlohmann::json::array();
  for (std::size_t k = 0; k < result.setups.size(); ++k) {
    nlohmann::json one = io::to_json(result.setups[k]);
    one["data"] =
        io::to_json(io::DataProvenance{.files = {f.files[k]}, .preprocessing = records[k]});
    document["setups"].push_back(std::move(one));
  }
  std::vector<Diagram> diagrams;
  if (global_diagram(f)) {
    diagrams.push_back({io::to_json(result.merged),
                        "PreGER merge of " + std::to_string(f.files.size()) + " setups"});
  }
  for (std::size_t k = 0; k < f.files.size(); ++k) {
    diagrams.push_back({document["setups"][k], title_of(f.files[k])});
  }
  return finish(f, package, result.merged, document, records.front(), diagrams);
}

ExitStatus run_oma(const OmaFlags& f, const CLI::App& app) {
  if (!f.geometry.empty() && f.plot.empty()) {
    usage_error("--geometry draws shapes.png on the sensors' wireframe: give --plot DIR");
  }
  if (!f.geometry_lines.empty() && f.geometry.empty()) {
    usage_error("--geometry-lines needs --geometry (the sensors file)");
  }
  std::filesystem::path package;
  if (!f.plot.empty()) {
    package = require_plotting();
    prepare_plot_directory(f.plot, figure_names(f), f.force);
  }
  if (f.files.size() > 1) return run_setups(f, app, package);
  const std::string& file = f.files.front();
  OmaOptions options = f.options;
  const OutputOnlyRecord s = read_setup(f, app, file);
  if (!f.reference_columns.empty()) {
    for (const std::string& ref : io::expand_columns(s.table, f.reference_columns, "reference")) {
      const auto at = std::find(s.names.begin(), s.names.end(), ref);
      if (at == s.names.end()) {
        usage_error("--reference-columns names '" + ref +
                    "', which is not one of --output-columns");
      }
      options.reference_channels.push_back(static_cast<int>(at - s.names.begin()));
    }
  }
  const OmaResult result = identify_output_only(s.outputs, s.sample_time, options, s.names);
  nlohmann::json document = io::to_json(result);
  document["data"] =
      io::to_json(io::DataProvenance{.files = {file}, .preprocessing = s.preprocessing});
  return finish(f, package, result, document, s.preprocessing, {{document, title_of(file)}});
}

Command add_oma_command(CLI::App& parent) {
  auto flags = std::make_shared<OmaFlags>();
  OmaFlags& f = *flags;
  CLI::App* app = parent.add_subcommand(
      "oma",
      "Output-only (operational) modal analysis: modes of several response channels with no "
      "measured input, by stochastic subspace identification (ssi-cov, ssi-data) or pLSCF "
      "(plscf), each with a stabilisation diagram and clustering, or by frequency-domain "
      "decomposition (fdd, efdd).");
  app->footer(
      "Prints each mode (frequency and damping with their standard errors, MPC, the "
      "number of orders supporting it) and the verdict. -o X.json writes an \"oma_result\" "
      "document (docs/oma.md) with every pole of the stabilisation diagram.\n"
      "Exit status: 0 modes found, 3 no mode found, 2 bad usage or input, 1 other error.");
  app->add_option("data", f.files,
                  "CSV file with the output columns; several files: setups of one structure "
                  "sharing --reference-columns, merged into global modes (--merge)")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--output-columns", f.output_columns,
                  "Response channels: names or ranges A:B (file order), e.g. y1:y8; default: "
                  "every column but the time column")
      ->delimiter(',');
  app->add_option(flag_of<OmaOptions>("reference_channels"), f.reference_columns,
                  "Reference channels (a subset of the outputs; default: all)")
      ->delimiter(',');
  app->add_option("--merge", f.merge,
                  "Several setups: how their modes are merged: " + command_line_list<OmaMerge>())
      ->check([](const std::string& word) {
        try {
          parse_enum_word<OmaMerge>("--merge", word);
          return std::string();
        } catch (const CLI::ValidationError& e) {
          return std::string(e.what());
        }
      })
      ->capture_default_str();
  app->add_option("--merge-frequency-tolerance", f.merge_frequency_tolerance,
                  "Several setups: largest |df|/f between one mode's frequencies in two setups")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app->add_option("--merge-reference-mac", f.merge_reference_mac,
                  "Several setups: smallest MAC of one mode's reference entries in two setups")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app->add_option("--time-column", f.time_column, "Uniform time column")->capture_default_str();
  app->add_option("--sample-time,-T", f.sample_time, "Sample time [s] (overrides the time column)")
      ->check(CLI::PositiveNumber);
  FieldFlagSettings settings;
  settings.by_hand = {"reference_channels"};  // names of columns, above
  add_field_flags(*app, f.options, settings);
  f.prep.add_preprocessing_to(*app, false);
  app->add_option("--output,-o", f.output, "JSON file for the oma_result document")
      ->group("Output");
  app->add_option("--plot", f.plot,
                  "Directory for stabilisation.png (every pole by order and stability class, "
                  "the modes, the first singular value behind them; with several files one per "
                  "setup, stabilisation_setupK.png, and PreGER's global one) and, when modes were "
                  "found, shapes.png and mac.png (auto-MAC), drawn by python3 -m ctid.plot")
      ->group("Output");
  app->add_option("--geometry", f.geometry,
                  "With --plot: sensors CSV (channel,x,y[,z][,dx,dy[,dz]]) on whose 2-D or 3-D "
                  "wireframe shapes.png draws each mode")
      ->check(CLI::ExistingFile)
      ->group("Output");
  app->add_option("--geometry-lines", f.geometry_lines,
                  "With --geometry: lines CSV (from,to: channel names) joining the sensors' nodes")
      ->check(CLI::ExistingFile)
      ->group("Output");
  app->add_flag("--force", f.force, "Replace an output file that exists")->group("Output");
  app->add_flag("--quiet,-q", f.quiet, "Print nothing")->group("Output");
  Command command;
  command.app = app;
  command.run = [flags, app] { return run_oma(*flags, *app); };
  return command;
}

}  // namespace

CTID_REGISTER_COMMAND(45, add_oma_command);

}  // namespace ctid::cli
