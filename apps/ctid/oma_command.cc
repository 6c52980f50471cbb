// ctid oma: output-only (operational) modal analysis of several response channels with no
// measured input: covariance-driven SSI over orders 2..--max-order, the stable poles clustered
// into modes, standard errors by first-order perturbation or from segments; or the peaks of the
// output spectral matrix's first singular value (fdd, efdd) (ctid::identify_output_only, the front
// door of ctid::oma: identification/output_only.h; docs/oma.md).
// Prints the modes and the verdict; -o writes an "oma_result" document. Exit 3 when no mode was
// found.
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
#include "plot_support.h"

namespace ctid::cli {
namespace {

struct OmaFlags {
  std::string file;
  std::vector<std::string> output_columns;
  std::vector<std::string> reference_columns;
  std::string time_column = "t";
  double sample_time = 0.0;
  OmaOptions options;  ///< every field a flag (field_flags.h) but reference_channels
  DataFlags prep;      ///< its preprocessing flags only (--rows, --time, --detrend, ...)
  std::string output;
  std::string plot;  // DIR for stabilisation.png
  bool force = false;
  bool quiet = false;
};

// The record: the output columns (names or ranges A:B) and the sample time from the uniform
// time column, or -T (which overrides it); `t0` the first time stamp (0 without a column).
Eigen::MatrixXd read_outputs(const OmaFlags& f, const CLI::App& app, const io::CsvTable& table,
                             std::vector<std::string>& names, double& h, double& t0) {
  t0 = table.has_column(f.time_column) && table.rows() > 0 ? table.column(f.time_column)(0) : 0.0;
  names = io::expand_columns(table, f.output_columns, "output");
  Eigen::MatrixXd y(table.rows(), static_cast<Eigen::Index>(names.size()));
  for (std::size_t j = 0; j < names.size(); ++j) {
    y.col(static_cast<Eigen::Index>(j)) = table.column(names[j]);
  }
  if (app.count("--sample-time") > 0) {
    h = f.sample_time;
    return y;
  }
  if (!table.has_column(f.time_column)) {
    usage_error(internal::concat(f.file, " has no time column '", f.time_column,
                                 "'; give --sample-time (-T) or --time-column"));
  }
  const Eigen::VectorXd& t = table.column(f.time_column);
  require(t.size() >= 2, f.file, ": fewer than 2 samples");
  h = (t(t.size() - 1) - t(0)) / static_cast<double>(t.size() - 1);
  for (Eigen::Index k = 1; k < t.size(); ++k) {
    if (std::abs(t(k) - t(k - 1) - h) > 1e-3 * std::abs(h)) {
      usage_error(internal::concat(f.file, ": time column '", f.time_column,
                                   "' is not uniform at row ", k + 1,
                                   "; give --sample-time (-T) to override it"));
    }
  }
  return y;
}

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
  std::cout << "ctid oma: " << enum_name(r.method) << " on " << f.file << ": " << r.channels.size()
            << " channels, " << r.reference_channels.size() << " references, " << r.samples
            << " samples, h = " << format_brief(r.sample_time) << " s; " << r.message << "\n";
  if (preprocessing)
    std::cout << "preprocessing: " << preprocessing_summary(*preprocessing) << "\n";
  // fdd, efdd: no orders to count
  const bool ssi = r.method == OmaMethod::ssi_cov || r.method == OmaMethod::ssi_data;
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

// --plot DIR: the stabilisation diagram over the first singular value, from the document
// (written to a temporary when -o is not given).
void draw_stabilisation(const std::filesystem::path& package, const OmaFlags& f,
                        const nlohmann::json& document) {
  const TemporaryDirectory work;
  std::filesystem::path input = f.output;
  if (input.empty()) {
    input = work.path() / "oma.json";
    io::write_json(input, document);
  }
  const std::filesystem::path figure = std::filesystem::path(f.plot) / "stabilisation.png";
  plot(package, {{"oma_stabilisation", input, figure,
                  "ctid oma on " + std::filesystem::path(f.file).filename().string()}});
  if (!f.quiet) std::cout << "wrote " << figure.string() << "\n";
}

ExitStatus run_oma(const OmaFlags& f, const CLI::App& app) {
  std::filesystem::path package;
  if (!f.plot.empty()) {
    package = require_plotting();
    prepare_plot_directory(f.plot, {"stabilisation.png"}, f.force);
  }
  OmaOptions options = f.options;
  std::vector<std::string> names;
  double h = 0.0;
  double t0 = 0.0;
  const io::CsvTable table = io::read_table(f.file);
  Eigen::MatrixXd y = read_outputs(f, app, table, names, h, t0);
  std::optional<PreprocessingRecord> preprocessing;
  if (f.prep.preprocessing_asked(app)) {
    PreprocessingOptions p = f.prep.preprocessing_options();
    p.input_scale = 1.0;
    try {
      PreprocessedOutputs done = preprocess_outputs(y, h, t0, p);
      y = std::move(done.outputs);
      h = done.record.sample_time;
      preprocessing = std::move(done.record);
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(f.file + ": " + e.what());
    }
  }
  if (!f.reference_columns.empty()) {
    for (const std::string& ref : io::expand_columns(table, f.reference_columns, "reference")) {
      const auto at = std::find(names.begin(), names.end(), ref);
      if (at == names.end()) {
        usage_error("--reference-columns names '" + ref +
                    "', which is not one of --output-columns");
      }
      options.reference_channels.push_back(static_cast<int>(at - names.begin()));
    }
  }
  const OmaResult result = identify_output_only(y, h, options, names);
  nlohmann::json document = io::to_json(result);
  document["data"] =
      io::to_json(io::DataProvenance{.files = {f.file}, .preprocessing = preprocessing});
  if (!f.output.empty()) {
    io::write_json(f.output, document, f.force ? io::Overwrite::yes : io::Overwrite::no);
  }
  if (!f.quiet) print_summary(f, result, preprocessing);
  if (!f.plot.empty()) draw_stabilisation(package, f, document);
  return result.verdict.usable ? kExitOk : kExitNoUsableModel;
}

Command add_oma_command(CLI::App& parent) {
  auto flags = std::make_shared<OmaFlags>();
  OmaFlags& f = *flags;
  CLI::App* app = parent.add_subcommand(
      "oma",
      "Output-only (operational) modal analysis: modes of several response channels with no "
      "measured input, by covariance-driven SSI (a stabilisation diagram and clustering) or "
      "by frequency-domain decomposition (fdd, efdd).");
  app->footer(
      "Prints each mode (frequency and damping with their standard errors, MPC, the "
      "number of orders supporting it) and the verdict. -o X.json writes an \"oma_result\" "
      "document (docs/oma.md) with every pole of the stabilisation diagram.\n"
      "Exit status: 0 modes found, 3 no mode found, 2 bad usage or input, 1 other error.");
  app->add_option("data", f.file, "CSV file with the output columns")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--output-columns", f.output_columns,
                  "Response channels: names or ranges A:B (file order), e.g. y1:y8")
      ->delimiter(',')
      ->required();
  app->add_option(flag_of<OmaOptions>("reference_channels"), f.reference_columns,
                  "Reference channels (a subset of the outputs; default: all)")
      ->delimiter(',');
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
                  "Directory for stabilisation.png: every pole by order and stability class, the "
                  "modes, the first singular value behind them (python3 -m ctid.plot)")
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
