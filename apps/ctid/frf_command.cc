// `ctid frf`: the nonparametric frequency response of a record, by Welch's H1 estimate with
// coherence (non-periodic data) or averaged over the periods of a periodic excitation
// (--period N), written as CSV, with the resonance peaks listed (for choosing orders and
// initial modes). The numerics are ctid::welch_frf, ctid::periodic_frf and
// ctid::resonance_peaks (frequency/frf.h); figures by `python3 -m ctid.plot` (plot_support.h).
#include <algorithm>
#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "command.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/frequency/frf.h"
#include "ctid/frequency/mimo_frf.h"
#include "ctid/io/csv.h"
#include "ctid/io/fields_json.h"
#include "ctid/io/json.h"
#include "ctid/io/mimo_frf_file.h"
#include "ctid/io/model_json.h"
#include "ctid/io/provenance.h"
#include "ctid/io/report_json.h"
#include "ctid/io/result_json.h"
#include "ctid/io/uff58.h"
#include "data_flags.h"
#include "plot_support.h"

namespace ctid::cli {
namespace {

struct FrfFlags {
  DataFlags data;
  int period = 0;
  int transient_periods = PeriodicFrfOptions{}.transient_periods;
  int experiments = 0;     // 0: one per input (several inputs only)
  int segment_length = 0;  // 0: default_segment_length(N)
  double overlap = WelchOptions{}.overlap;
  double min_prominence_db = PeakOptions{}.min_prominence_db;
  int max_peaks = 10;  // a noisy FRF has many small local maxima; list the main ones
  double line_threshold = PeakOptions{}.line_threshold;
  double min_coherence = PeakOptions{}.min_coherence;
  std::string output;
  std::string plot;
  std::string model;
  bool force = false;
  bool quiet = false;

  // The estimators' and the peak picker's options as the flags give them (validated).
  PeriodicFrfOptions periodic_options() const {
    PeriodicFrfOptions options;
    options.period_length = period;
    options.transient_periods = transient_periods;
    options.line_threshold = line_threshold;
    options.validate();
    return options;
  }
  WelchOptions welch_options(int samples) const {
    WelchOptions options;
    options.segment_length = segment_length > 0 ? segment_length : default_segment_length(samples);
    options.overlap = overlap;
    options.validate();
    return options;
  }
  PeakOptions peak_options() const {
    PeakOptions options;
    options.min_prominence_db = min_prominence_db;
    options.max_peaks = max_peaks;
    options.line_threshold = line_threshold;
    options.min_coherence = min_coherence;
    options.validate();
    return options;
  }
};

// One line of the peak list; `response` names the FRF (G for SISO, H for the matrix's norm).
void print_peak(std::ostream& out, const ResonancePeak& p, const char* response) {
  out << "  w = " << format_brief(p.frequency) << " rad/s ("
      << format_brief(p.frequency / (2.0 * std::numbers::pi)) << " Hz), |" << response
      << "| = " << format_significant(20.0 * std::log10(p.magnitude), 4) << " dB, prominence "
      << format_significant(p.prominence_db, 3) << " dB, damping ~ "
      << format_significant(p.damping_ratio, 3) << ", coherence "
      << format_significant(p.coherence, 3) << "\n";
}

io::CsvTable frf_table(const Frf& frf) {
  const Eigen::Index n = frf.frequencies.size();
  Eigen::VectorXd hz(n), db(n), deg(n), re(n), im(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const std::complex<double> g = frf.response(k);
    hz(k) = frf.frequencies(k) / (2.0 * std::numbers::pi);
    db(k) = 20.0 * std::log10(std::abs(g));
    deg(k) = std::arg(g) * 180.0 / std::numbers::pi;
    re(k) = g.real();
    im(k) = g.imag();
  }
  io::CsvTable table;
  table.add_column("frequency", frf.frequencies);
  table.add_column("frequency_hz", hz);
  table.add_column("magnitude_db", db);
  table.add_column("phase_deg", deg);
  table.add_column("real", re);
  table.add_column("imag", im);
  table.add_column("variance", frf.variance);
  if (frf.coherence.size() == n) table.add_column("coherence", frf.coherence);
  if (frf.input_level.size() == n) table.add_column("input_level", frf.input_level);
  return table;
}

// frf.png (the FRF with its coherence) and, with --model, bode.png (the model over the FRF),
// drawn by `python3 -m ctid.plot` from files in a temporary folder.
void draw_frf(const FrfFlags& f, const std::filesystem::path& package, const Frf& frf,
              const io::CsvTable& table, const std::optional<io::FittedModel>& fitted) {
  const TemporaryDirectory work;
  const std::string title = "ctid frf: " + std::filesystem::path(f.data.file).filename().string();
  const std::filesystem::path dir(f.plot);
  io::write_csv(work.path() / "frf.csv", table);
  std::vector<PlotJob> jobs{{"frf", work.path() / "frf.csv", dir / "frf.png", title}};
  if (fitted) {
    nlohmann::json input = {{"model", io::to_json(fitted->model)}, {"frf", frf_json(frf)}};
    input["frequency_range"] = {frf.frequencies(0), frf.frequencies(frf.frequencies.size() - 1)};
    io::write_json(work.path() / "bode.json", input);
    jobs.push_back({"bode", work.path() / "bode.json", dir / "bode.png", title});
  }
  plot(package, jobs);
}

// Every number ctid frf writes is finite (docs/cli.md): an FRF with an infinite or NaN entry
// is refused, naming the column and the line, instead of written. Values whose squares
// overflow or vanish in double precision (|u| ~ 1e200) cause it.
void require_finite(const io::CsvTable& table, const std::string& file) {
  const Eigen::VectorXd& hz = table.column("frequency_hz");
  for (std::size_t c = 0; c < table.names.size(); ++c) {
    const Eigen::VectorXd& v = table.columns[c];
    for (Eigen::Index k = 0; k < v.size(); ++k) {
      if (std::isfinite(v(k))) continue;
      usage_error(internal::concat(
          file, ": the FRF's ", table.names[c], " is ", v(k), " at ", hz(k),
          " Hz; the input or output values are too large or too small for the spectra "
          "(their squares must stay within double precision); rescale them with "
          "--scale-input / --scale-output"));
    }
  }
}

// An output that is zero at every sample (no response to estimate: its FRF is 0, -inf dB,
// with no coherence) and a constant input are refused before the spectra are computed (the
// records themselves refuse magnitudes the spectra could not square: core/internal/
// signal_range.h).
void require_spectral_column(const Eigen::VectorXd& x, const std::string& file,
                             const std::string& column, bool is_output) {
  if (x.size() == 0) return;
  if (!is_output && (x.array() == x(0)).all()) {
    usage_error(internal::concat(file, ": input column '", column, "' is ", x(0),
                                 " at every sample; an FRF needs an input that varies (check "
                                 "--input-column)"));
  }
  if (is_output && (x.array() == 0.0).all()) {
    usage_error(file + ": output column '" + column +
                "' is zero at every sample; there is no response to estimate (check "
                "--output-column)");
  }
}

double median(Eigen::VectorXd v) {
  std::vector<double> x;
  for (double e : v) {
    if (std::isfinite(e)) x.push_back(e);
  }
  if (x.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(x.begin(), x.end());
  const std::size_t m = x.size() / 2;
  return x.size() % 2 == 1 ? x[m] : 0.5 * (x[m - 1] + x[m]);
}

// -o: the CSV table, for a .json name the FRF's document with the method, the data it came
// from (samples, h, hold, preprocessing) and the peaks (and, if given, what they are peaks of)
// added to `document`, and for a universal-file name (.uff, .unv, .uf) the FRF matrix `mimo`
// as dataset 58 records (checked_output_name refuses that name without one).
void write_output(const FrfFlags& f, const io::CsvTable& table, nlohmann::json& document,
                  bool periodic, int samples, double sample_time, Hold input_hold,
                  const std::vector<ResonancePeak>& peaks, const char* peaks_of = nullptr,
                  const MimoFrf* mimo = nullptr) {
  if (f.output.empty()) return;
  const io::Overwrite overwrite = f.force ? io::Overwrite::yes : io::Overwrite::no;
  if (mimo != nullptr && io::is_universal_file_path(f.output)) {
    io::write_uff58(f.output, *mimo, overwrite);
    return;
  }
  if (std::filesystem::path(f.output).extension() != ".json") {
    io::write_csv(f.output, table, overwrite);
    return;
  }
  document["method"] = periodic ? "periodic" : "welch";
  document["data"] = io::to_json(io::DataProvenance{.files = {f.data.file},
                                                    .samples = samples,
                                                    .sample_time = sample_time,
                                                    .input_hold = input_hold,
                                                    .preprocessing = f.data.preprocessing});
  if (peaks_of != nullptr) document["peaks_of"] = peaks_of;
  nlohmann::json listed = nlohmann::json::array();
  for (const ResonancePeak& p : peaks) listed.push_back(io::fields_to_json(p));
  document["peaks"] = std::move(listed);
  io::write_json(f.output, document, overwrite);
}

void run_mimo_frf(const FrfFlags& f, const CLI::App& app, bool periodic) {
  if (!f.model.empty()) {
    usage_error("--model is not available with --input-columns / --output-columns yet");
  }
  std::filesystem::path package;
  if (!f.plot.empty()) {
    package = require_plotting();
    prepare_plot_directory(f.plot, {"frf_matrix.png"}, f.force);
  }
  const MimoData data = f.data.load_mimo(app);
  for (Eigen::Index k = 0; k < data.inputs().cols(); ++k) {
    require_spectral_column(data.inputs().col(k), f.data.file,
                            data.input_names()[static_cast<std::size_t>(k)], false);
  }
  for (Eigen::Index j = 0; j < data.outputs().cols(); ++j) {
    require_spectral_column(data.outputs().col(j), f.data.file,
                            data.output_names()[static_cast<std::size_t>(j)], true);
  }
  MimoFrf frf;
  if (periodic) {
    const int experiments = f.experiments > 0 ? f.experiments : data.input_count();
    frf = periodic_frf(data, f.periodic_options(), experiments);
  } else {
    frf = welch_frf(data, f.welch_options(data.size()));
  }
  const PeakOptions peak_options = f.peak_options();
  const std::size_t all_lines = frf.lines.size();
  frf = excited_lines(frf, f.line_threshold);
  require(frf.frequencies.size() > 0,
          "ctid frf: no line where every input reaches "
          "--line-threshold ",
          f.line_threshold, " of its largest line; lower it or check the input columns");
  const Frf summary = summed_power_frf(frf);
  const std::vector<ResonancePeak> peaks = resonance_peaks(summary, peak_options);
  int correlated = 0;
  for (int l = 0; l < frf.input_condition.size(); ++l) correlated += frf.inputs_correlated(l);

  const io::CsvTable table = io::mimo_frf_table(frf);
  require_finite(table, f.data.file);
  nlohmann::json document = io::to_json(frf);
  write_output(
      f, table, document, periodic, data.size(), data.sample_time(), data.input_hold(), peaks,
      "sqrt(sum |H_ji|^2) over all channels, with the power-weighted multiple coherence", &frf);
  if (!f.plot.empty()) {
    // frf_matrix.png: every input of the first four outputs, with their multiple coherence.
    const TemporaryDirectory work;
    io::write_json(work.path() / "frf.json", document);
    plot(package,
         {{"frf_matrix", work.path() / "frf.json", std::filesystem::path(f.plot) / "frf_matrix.png",
           "ctid frf: " + std::filesystem::path(f.data.file).filename().string()}});
  }
  if (f.quiet) return;
  const auto names = [](const std::vector<std::string>& v) {
    std::string text;
    for (const std::string& name : v) text += (text.empty() ? "" : ", ") + name;
    return text;
  };
  std::cout << "ctid frf: " << (periodic ? "periodic" : "Welch H1") << " on " << f.data.file << ": "
            << frf.input_count() << " input" << (frf.input_count() == 1 ? "" : "s") << " ("
            << names(frf.input_names) << ") x " << frf.output_count() << " output"
            << (frf.output_count() == 1 ? "" : "s") << ", " << frf.frequencies.size() << " lines, "
            << frf.averages << (periodic ? " periods" : " segments") << " of " << frf.block_length
            << " samples\n";
  if (f.data.preprocessing_asked(app)) {
    std::cout << "preprocessing: " << f.data.preprocessing.summary() << "\n";
  }
  const Eigen::Index last = frf.frequencies.size() - 1;
  std::cout << "excited band: " << format_brief(frf.frequencies(0) / (2.0 * std::numbers::pi))
            << " to " << format_brief(frf.frequencies(last) / (2.0 * std::numbers::pi)) << " Hz, "
            << frf.lines.size() << " of " << all_lines
            << " lines where every input is above --line-threshold "
            << format_number(f.line_threshold) << " of its largest line\n";
  if (frf.input_count() > 1) {
    std::cout << "inputs correlated (condition of the normalised S_uu > "
              << format_number(kCorrelatedInputCondition) << ") at " << correlated << " of "
              << frf.lines.size() << " lines; largest condition "
              << format_significant(frf.input_condition.maxCoeff(), 3) << "\n";
  }
  std::cout << "multiple coherence with all inputs, median over the excited band:\n";
  for (int j = 0; j < frf.output_count(); ++j) {
    std::cout << "  " << frf.output_names[static_cast<std::size_t>(j)] << " "
              << format_significant(median(frf.coherence.col(j)), 3) << "\n";
  }
  std::cout << peaks.size() << " resonance peak" << (peaks.size() == 1 ? "" : "s")
            << " of sqrt(sum |H_ji|^2) over the " << frf.input_count() * frf.output_count()
            << " channels (prominence >= " << format_number(f.min_prominence_db)
            << " dB, power-weighted coherence >= " << format_number(f.min_coherence) << "):\n";
  for (const ResonancePeak& p : peaks) print_peak(std::cout, p, "H");
  if (!f.output.empty()) std::cout << "wrote " << f.output << "\n";
}

void run_frf(const FrfFlags& f, const CLI::App& app) {
  const bool periodic = app.count("--period") > 0;
  if (periodic && (app.count("--segment-length") > 0 || app.count("--overlap") > 0)) {
    usage_error(
        "--segment-length and --overlap are Welch flags; they have no effect with --period");
  }
  if (app.count("--segment-length") > 0 && f.segment_length < 1) {
    usage_error("--segment-length is " + std::to_string(f.segment_length) +
                "; give a positive number of samples, or leave the flag out for the default");
  }
  if (!periodic && app.count("--transient-periods") > 0) {
    usage_error("--transient-periods needs --period");
  }
  if (!f.model.empty() && f.plot.empty())
    usage_error("--model needs --plot (it is drawn over the FRF)");
  if (f.data.mimo_asked(app)) {
    if (app.count("--experiments") > 0 && !periodic) usage_error("--experiments needs --period");
    run_mimo_frf(f, app, periodic);
    return;
  }
  if (app.count("--experiments") > 0) {
    usage_error("--experiments needs several inputs (--input-columns)");
  }
  if (io::is_universal_file_path(f.output)) {
    usage_error("-o " + f.output +
                ": a universal file (dataset 58) holds an FRF matrix; give --input-columns / "
                "--output-columns, or write .csv or .json");
  }
  std::filesystem::path package;
  // --model is read before any work: a bad model file used to be found only after the FRF
  // was computed, printed and written with -o, which then stayed behind.
  std::optional<io::FittedModel> fitted;
  if (!f.plot.empty()) {
    package = require_plotting();
    if (!f.model.empty()) fitted = io::read_fitted_model(f.model);
    std::vector<std::string> figures{"frf.png"};
    if (!f.model.empty()) figures.emplace_back("bode.png");
    prepare_plot_directory(f.plot, figures, f.force);
  }
  // The data checks' warnings (e.g. about a constant input's mean) are queued until the
  // refusals below are behind: a refused record gets its one line only.
  const SampledData data = f.data.load(app, false);
  require_spectral_column(data.input(), f.data.file, f.data.input_column, false);
  require_spectral_column(data.output(), f.data.file, f.data.output_column, true);
  flush_diagnostics();

  Frf frf;
  if (periodic) {
    frf = periodic_frf(data, f.periodic_options());
  } else {
    frf = welch_frf(data, f.welch_options(data.size()));
  }
  const PeakOptions peak_options = f.peak_options();
  const std::size_t all_lines = frf.lines.size();
  frf = excited_lines(frf, f.line_threshold);
  require(frf.frequencies.size() > 0, "ctid frf: no line of the input reaches --line-threshold ",
          f.line_threshold, " of its largest line; lower it or check the input column");
  const std::vector<ResonancePeak> peaks = resonance_peaks(frf, peak_options);

  const io::CsvTable table = frf_table(frf);
  require_finite(table, f.data.file);
  nlohmann::json document = io::to_json(frf);
  write_output(f, table, document, periodic, data.size(), data.sample_time(), data.input_hold(),
               peaks);
  if (!f.quiet) {
    std::cout << "ctid frf: " << (periodic ? "periodic" : "Welch H1") << " on " << f.data.file
              << ": " << frf.frequencies.size() << " lines, " << frf.averages
              << (periodic ? " periods" : " segments") << " of " << frf.block_length
              << " samples\n";
    if (f.data.preprocessing_asked(app)) {
      std::cout << "preprocessing: " << f.data.preprocessing.summary() << "\n";
    }
    const Eigen::Index last = frf.frequencies.size() - 1;
    std::cout << "excited band: " << format_brief(frf.frequencies(0) / (2.0 * std::numbers::pi))
              << " to " << format_brief(frf.frequencies(last) / (2.0 * std::numbers::pi)) << " Hz, "
              << frf.lines.size() << " of " << all_lines << " lines above --line-threshold "
              << format_number(f.line_threshold) << " of the largest input line\n";
    std::cout << peaks.size() << " resonance peak" << (peaks.size() == 1 ? "" : "s")
              << " (prominence >= " << format_number(f.min_prominence_db)
              << " dB, coherence >= " << format_number(f.min_coherence) << "):\n";
    for (const ResonancePeak& p : peaks) print_peak(std::cout, p, "G");
    if (!f.output.empty()) std::cout << "wrote " << f.output << "\n";
  }
  if (!f.plot.empty()) draw_frf(f, package, frf, table, fitted);
}

Command add_frf_command(CLI::App& parent) {
  auto flags = std::make_shared<FrfFlags>();
  FrfFlags& f = *flags;
  CLI::App* app = parent.add_subcommand(
      "frf",
      "Nonparametric frequency response of a record (Welch H1 with coherence, or averaged "
      "over periods) as CSV, with its resonance peaks.");
  app->footer(
      "CSV columns: frequency (rad/s), frequency_hz, magnitude_db, phase_deg, real, imag, "
      "variance (of the complex estimate), coherence (squared, 0-1) and input_level (the input's "
      "amplitude at the line over its largest line's); only lines above --line-threshold.\n"
      "-o X.json writes a typed \"frf\" document instead (docs/formats.md), with the peaks.\n"
      "With --input-columns / --output-columns (names or ranges A:B, e.g. y1:y28) the FRF "
      "matrix H = S_yu S_uu^-1 (Welch) or Y U^-1 over experiments (--period): CSV columns "
      "frequency, frequency_hz, input_condition, input_level_<input>, coherence_<output> (the "
      "multiple coherence with all inputs) and <output>/<input>_real, _imag, _variance; -o "
      "X.json a \"mimo_frf\" document; --plot DIR draws frf_matrix.png. Peaks are those of "
      "sqrt(sum |H_ji|^2) over all channels.\n"
      "Exit status: 0 ran, 2 bad usage or input, 1 other error.");
  f.data.add_to(*app, "data", false);
  f.data.add_mimo_columns(*app);
  app->add_option("--period", f.period,
                  "Samples per period of a periodic excitation: average the FRF over periods")
      ->group("Periodic");
  app->add_option("--experiments", f.experiments,
                  "Several inputs: the record holds this many experiments of equal length one "
                  "after another (default: one per input), e.g. Hadamard-phased multisines")
      ->group("Periodic");
  app->add_option("--transient-periods", f.transient_periods,
                  "Periods dropped at the start (transient)")
      ->capture_default_str()
      ->group("Periodic");
  app->add_option("--segment-length", f.segment_length,
                  "Welch: samples per segment (not given: largest power of 2 <= N/8, 8..4096)")
      ->group("Welch");
  app->add_option("--overlap", f.overlap, "Welch: fraction shared by consecutive segments")
      ->capture_default_str()
      ->group("Welch");
  app->add_option("--min-prominence-db", f.min_prominence_db,
                  "Peaks: height above the surrounding minima, dB")
      ->capture_default_str()
      ->group("Peaks");
  app->add_option("--max-peaks", f.max_peaks, "Peaks: keep at most this many (0: all)")
      ->capture_default_str()
      ->group("Peaks");
  app->add_option("--line-threshold", f.line_threshold,
                  "Keep lines where the input's amplitude exceeds this fraction of its largest "
                  "line (gaps and out-of-band leakage are not peaks)")
      ->capture_default_str()
      ->group("Peaks");
  app->add_option("--min-coherence", f.min_coherence,
                  "Peaks: smallest squared coherence at the peak (0-1)")
      ->capture_default_str()
      ->group("Peaks");
  app->add_option("--output,-o", f.output,
                  "CSV file to write (.json: an frf document; .uff/.unv with several channels: "
                  "universal file dataset 58, which fit-frf reads)")
      ->group("Output");
  app->add_option("--plot", f.plot, "Directory for frf.png (and bode.png of --model over the FRF)")
      ->group("Output");
  app->add_option("--model", f.model, "Model or result JSON drawn over the FRF in bode.png")
      ->check(CLI::ExistingFile)
      ->group("Output");
  app->add_flag("--force", f.force, "Replace output files that exist")->group("Output");
  app->add_flag("--quiet,-q", f.quiet, "Print nothing")->group("Output");

  Command command;
  command.app = app;
  command.run = [flags, app] {
    run_frf(*flags, *app);
    return kExitOk;
  };
  return command;
}

}  // namespace

CTID_REGISTER_COMMAND(40, add_frf_command);

}  // namespace ctid::cli
