// `ctid study open-loop|closed-loop`: the Monte Carlo studies of González et al., Section 6
// (ctid/study/paper_study.h), at the paper's size by default. Writes runs.csv (per-run
// estimates), mse.csv (MSE per N and parameter beside the covariance prediction), trends.csv,
// summary.json (a study_summary document, io/report_json.h) and mse.png (MSE against N, log-log, by
// `python3 -m ctid.plot mse`; plot_support.h). Existing result files are not replaced without
// --force.
// --size-index/--run-index replay one run and write only its records. --scheduler ADDRESS runs
// the cases on a Dask cluster through `python3 -m ctid.distributed study` (docs/distributed.md),
// which returns the records; the result is assembled and written here, as for a local study.
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "command.h"
#include "ctid/core/error.h"
#include "ctid/io/fields_json.h"
#include "ctid/io/file.h"
#include "ctid/io/json.h"
#include "ctid/io/report_json.h"
#include "ctid/study/monte_carlo.h"
#include "ctid/study/paper_study.h"
#include "ctid/study/study_output.h"
#include "plot_support.h"
#include "progress.h"

namespace ctid::cli {
namespace {

struct StudyFlags {
  std::string kind;
  std::string output;
  int runs = -1;
  int sizes = -1;
  int min_samples = -1;
  int max_samples = -1;
  int threads = StudyOptions{}.threads;
  std::uint64_t seed = StudyOptions{}.seed;
  int size_index = -1;
  int run_index = -1;
  int max_iterations = -1;
  double tolerance = -1.0;
  std::vector<std::string> estimators;
  std::string scheduler;
  bool no_covariance = false;
  bool no_plot = false;
  bool force = false;
  bool quiet = false;
};

StudyEstimator estimator_from_string(const std::string& name) {
  if (const auto estimator = enum_from_name<StudyEstimator>(name)) return *estimator;
  usage_error("--estimators: unknown estimator '" + name + "' (" +
              enum_names<StudyEstimator>(", ") + ")");
}

StudyOptions options_from_flags(const StudyFlags& f) {
  const StudyKind kind = f.kind == "open-loop" ? StudyKind::open_loop : StudyKind::closed_loop;
  StudyOptions options = StudyOptions::paper(kind);
  if (f.runs >= 0) options.runs = f.runs;
  if (f.sizes >= 0) options.sizes = f.sizes;
  if (f.min_samples >= 0) options.min_samples = f.min_samples;
  if (f.max_samples >= 0) options.max_samples = f.max_samples;
  if (f.max_iterations >= 0) options.max_iterations = f.max_iterations;
  if (f.tolerance > 0.0) options.tolerance = f.tolerance;
  options.threads = f.threads;
  options.seed = f.seed;
  options.compute_covariance = !f.no_covariance;
  for (const std::string& name : f.estimators) {
    options.estimators.push_back(estimator_from_string(name));
  }
  // The limits in the flags' words before the options' own check (paper_study.h).
  if (options.max_samples > kMaxStudySamples) {
    usage_error("--max-samples " + std::to_string(options.max_samples) +
                " is more than a study's runs may have (" + std::to_string(kMaxStudySamples) +
                " samples)");
  }
  const long long cases = static_cast<long long>(options.runs) * options.sizes;
  if (cases > kMaxStudyCases) {
    usage_error("--runs " + std::to_string(options.runs) + " x --sizes " +
                std::to_string(options.sizes) + " = " + std::to_string(cases) +
                " cases; a study runs at most " + std::to_string(kMaxStudyCases) +
                " (split it over --seed values or sample ranges)");
  }
  options.validate();
  return options;
}

// Writes what `fill` prints to `path` through a temporary file moved into place (io layer), so
// an interrupted study leaves no half-written table.
template <class Fill>
void write_table(const std::filesystem::path& path, Fill fill) {
  std::ostringstream text;
  fill(text);
  io::write_text_file(path, text.str(), io::Overwrite::yes);
}

// A double of a study_records document: a number, or "nan", "-nan", "inf", "-inf" (JSON has
// no non-finite numbers; the sign of a NaN is kept, so runs.csv prints what a local study does).
double record_double(const nlohmann::json& value, const std::string& where) {
  if (value.is_number()) return value.get<double>();
  if (value.is_string()) {
    const std::string& text = value.get_ref<const std::string&>();
    constexpr double nan = std::numeric_limits<double>::quiet_NaN();
    constexpr double inf = std::numeric_limits<double>::infinity();
    if (text == "nan") return nan;
    if (text == "-nan") return -nan;
    if (text == "inf") return inf;
    if (text == "-inf") return -inf;
  }
  throw ComputationError(where + " is " + value.dump() + "; expected a number");
}

// The records in the study_records document that `python3 -m ctid.distributed study` wrote:
// every field by io::fields_from_json, the two vectors by record_double.
std::vector<StudyRecord> read_study_records(const std::filesystem::path& path) {
  const nlohmann::json document = io::read_json(path);
  const std::string source = path.string();
  if (!document.is_object() || !document.contains("type") || document["type"] != "study_records" ||
      !document.contains("records") || !document["records"].is_array()) {
    throw ComputationError(source + ": not a study_records document");
  }
  std::vector<StudyRecord> records;
  records.reserve(document["records"].size());
  for (std::size_t k = 0; k < document["records"].size(); ++k) {
    const std::string where = source + ": records[" + std::to_string(k) + "]";
    nlohmann::json fields = document["records"][k];
    if (!fields.is_object()) throw ComputationError(where + " is not an object");
    StudyRecord record;
    for (auto [name, vector] : {std::pair{"estimate", &record.estimate},
                                std::pair{"standard_error", &record.standard_error}}) {
      if (!fields.contains(name)) continue;
      const nlohmann::json& array = fields[name];
      if (!array.is_array()) throw ComputationError(where + "." + name + " is not an array");
      vector->resize(static_cast<Eigen::Index>(array.size()));
      for (std::size_t i = 0; i < array.size(); ++i) {
        (*vector)[static_cast<Eigen::Index>(i)] =
            record_double(array[i], where + "." + name + "[" + std::to_string(i) + "]");
      }
      fields.erase(name);
    }
    io::fields_from_json(fields, record, where);
    records.push_back(std::move(record));
  }
  return records;
}

// The study's cases on the Dask cluster at `scheduler` (an address, or "env" for
// $DASK_SCHEDULER_ADDRESS): the options go to `python3 -m ctid.distributed study` as JSON, the
// records come back as JSON, and study_result_from_records assembles them as run_study does.
StudyResult run_study_on_dask(const StudyOptions& options, const std::filesystem::path& package,
                              const std::string& scheduler) {
  const TemporaryDirectory work;
  const std::filesystem::path options_file = work.path() / "options.json";
  const std::filesystem::path records_file = work.path() / "records.json";
  io::write_json(options_file, io::fields_to_json(options), io::Overwrite::yes);
  run_python_module(package, "ctid.distributed",
                    {"study", options_file.string(), "--scheduler", scheduler, "--out",
                     records_file.string(), "--quiet"},
                    "--scheduler " + scheduler);
  return study_result_from_records(options, read_study_records(records_file));
}

void run_study_command(const StudyFlags& f) {
  const StudyOptions options = options_from_flags(f);
  const std::filesystem::path folder(f.output);
  const bool replay = f.size_index >= 0 || f.run_index >= 0;
  const bool draw = !f.no_plot && !replay;
  const bool dask = !f.scheduler.empty();
  if (dask && replay) {
    usage_error("--scheduler runs a whole study; --size-index/--run-index replay one run here");
  }
  // Before any work: plotting and Dask must be possible, and no earlier result is replaced
  // silently.
  std::filesystem::path package;
  if (draw) package = require_plotting();
  if (dask) package = require_python_package("--scheduler");
  std::vector<std::string> files{"runs.csv"};
  if (!replay) files.insert(files.end(), {"mse.csv", "trends.csv", "summary.json"});
  if (draw) files.emplace_back("mse.png");
  prepare_plot_directory(folder, files, f.force, "--output");
  const StudySetup setup = study_setup(options.kind);

  if (replay) {
    if (f.size_index < 0 || f.run_index < 0) {
      usage_error("--size-index and --run-index replay one run: give both");
    }
    const std::vector<StudyRecord> records = run_study_case(options, f.size_index, f.run_index);
    create_output_directory(folder, "--output");
    write_table(folder / "runs.csv",
                [&](std::ostream& out) { write_records_csv(records, setup.parameter_names, out); });
    if (!f.quiet) write_records_csv(records, setup.parameter_names, std::cout);
    return;
  }

  const auto start = std::chrono::steady_clock::now();
  const int total = options.sizes * options.runs;
  StudyResult result;
  if (dask) {
    result = run_study_on_dask(options, package, f.scheduler);
  } else {
    Progress progress("ctid study", f.quiet);
    result = run_study(options, progress.callback("case"));
    progress.clear();
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  create_output_directory(folder, "--output");
  write_table(folder / "runs.csv", [&](std::ostream& out) { write_records_csv(result, out); });
  write_table(folder / "mse.csv", [&](std::ostream& out) { write_mse_csv(result, out); });
  write_table(folder / "trends.csv", [&](std::ostream& out) { write_trends_csv(result, out); });
  io::write_json(folder / "summary.json", io::to_json(study_summary(result)), io::Overwrite::yes);
  if (!f.quiet) {
    std::cout << "ctid study " << to_string(options.kind) << ": " << total << " cases x "
              << options.active_estimators().size() << " estimators in " << seconds << " s ";
    if (dask) {
      std::cout << "on the Dask cluster at " << f.scheduler << "\n";
    } else {
      std::cout << "on " << resolve_thread_count(options.threads) << " threads\n";
    }
    write_trends_csv(result, std::cout);
  }
  if (draw) {
    const std::string title =
        "Section " + std::string(options.kind == StudyKind::open_loop ? "6.1" : "6.2") + " " +
        to_string(options.kind) + ", " + std::to_string(options.runs) + " runs per N";
    plot(package, {{"mse", folder / "mse.csv", folder / "mse.png", title}});
    if (!f.quiet) std::cout << "wrote " << (folder / "mse.png").string() << "\n";
  }
}

Command add_study_command(CLI::App& parent) {
  auto flags = std::make_shared<StudyFlags>();
  StudyFlags& f = *flags;
  CLI::App* app = parent.add_subcommand(
      "study",
      "Monte Carlo study of González et al. Section 6: open-loop (6.1, SRIVC 8 poles/6 zeros "
      "against the additive estimator, DC gains) or closed-loop (6.2, direct SRIVC, CLSRIVC "
      "and the additive closed-loop estimator, all six parameters). Paper size by default.");
  app->footer(
      "Writes DIR/runs.csv (per-run estimates and standard errors), DIR/mse.csv (MSE per N and "
      "parameter with the covariance prediction), DIR/trends.csv (log-log slopes, MSE ratios), "
      "DIR/summary.json (a study_summary document: MSE table and trends) and DIR/mse.png. Run r at "
      "size j is a pure function of (--seed, j, r): the output does "
      "not depend on --threads or --scheduler, and --size-index j --run-index r replays that run "
      "alone. --scheduler ADDRESS runs the cases on a Dask cluster (docs/distributed.md).\n"
      "Docs: docs/study.md. Exit status: 0 ran, 2 bad usage or input, 1 other error.");
  app->add_option("kind", f.kind, "open-loop (Section 6.1) or closed-loop (Section 6.2)")
      ->required()
      ->check(CLI::IsMember({"open-loop", "closed-loop"}));
  app->add_option("--output,-o", f.output, "Folder to write the results into")->required();
  app->add_option("--runs,-r", f.runs, "Monte Carlo runs per sample size (paper: 300)")
      ->check(CLI::Range(1, 1000000000));
  app->add_option("--sizes,-k", f.sizes,
                  "Number of log-spaced sample sizes (paper: 30 open loop, 50 closed loop)")
      ->check(CLI::Range(1, 1000000000));
  app->add_option("--min-samples", f.min_samples,
                  "Smallest N (paper: 2000 open loop, 500 closed loop)")
      ->check(CLI::Range(1, 1000000000));
  app->add_option("--max-samples", f.max_samples,
                  "Largest N (paper: 100000 open loop, 123036 closed loop)")
      ->check(CLI::Range(1, 1000000000));
  app->add_option("--threads,-j", f.threads, "Worker threads (0: every core)")
      ->capture_default_str()
      ->check(non_negative_number());
  app->add_option("--seed", f.seed, "Study seed")->check(seed_validator())->capture_default_str();
  app->add_option("--size-index", f.size_index, "Replay one run: the sample-size index j")
      ->check(non_negative_number());
  app->add_option("--run-index", f.run_index, "Replay one run: the run index r")
      ->check(non_negative_number());
  app->add_option("--max-iterations", f.max_iterations, "Estimator iterations (paper: 100)")
      ->check(CLI::Range(1, 1000000000));
  app->add_option("--tolerance", f.tolerance,
                  "Relative parameter change that stops the iteration (paper: 1e-10 open loop, "
                  "1e-7 closed loop)")
      ->check(CLI::PositiveNumber);
  app->add_option("--estimators", f.estimators,
                  "Subset of estimators (srivc, clsrivc, additive_srivc, additive_clsrivc)");
  app->add_option("--scheduler", f.scheduler,
                  "Run the cases on the Dask cluster of this scheduler (tcp://host:8786; env: "
                  "$DASK_SCHEDULER_ADDRESS) through python3 -m ctid.distributed; same outputs, "
                  "identical to a local study (docs/distributed.md)")
      ->check([](const std::string& value) {
        return value.empty() ? std::string("an address is needed") : std::string();
      });
  app->add_flag("--no-covariance", f.no_covariance,
                "Skip the estimators' covariance (no standard errors or predicted MSE; faster)");
  app->add_flag("--no-plot", f.no_plot, "Do not draw mse.png");
  app->add_flag("--force", f.force, "Replace result files that exist in the folder");
  app->add_flag("--quiet,-q", f.quiet, "Print nothing on success");

  Command command;
  command.app = app;
  command.run = [flags] {
    run_study_command(*flags);
    return kExitOk;
  };
  return command;
}

}  // namespace

CTID_REGISTER_COMMAND(60, add_study_command);

}  // namespace ctid::cli
