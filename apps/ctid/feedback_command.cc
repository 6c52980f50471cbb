// `ctid feedback`: forward F and feedback H of a loop with a delay in the feedback path,
// W = F/(1 + F H e^{-Δs}), from a record t,u,y (u the loop input, y its output), by
// the front door identify(data, DelayedFeedbackStructure, ...) (identification/feedback_loop.h):
// identify_delayed_feedback (step 1, separation candidates, output-error refinement from each)
// or, with --delay-scan, identify_delayed_feedback_with_delay_scan. Writes the
// delayed_feedback_result document of io (feedback_result_json.h), which `ctid simulate
// --model` reads back; algorithm and conventions in docs/algorithms/feedback-delay.md.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <string>

#include "command.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/identification/feedback_loop.h"
#include "ctid/io/feedback_result_json.h"
#include "ctid/io/sampled_data_csv.h"
#include "field_flags.h"
#include "progress.h"

namespace ctid::cli {

// --step1 has been spelt batch or rls on the command line.
template <>
struct CommandLineWords<Step1Method> {
  static std::vector<std::pair<std::string, Step1Method>> words() {
    return {{"batch", Step1Method::batch}, {"rls", Step1Method::recursive}};
  }
};
namespace {

struct FeedbackFlags {
  std::string data;
  std::string output;
  bool force = false;
  bool quiet = false;
  std::string input_column = "u";
  std::string output_column = "y";
  std::string time_column = "t";
  int forward_order = 0;
  int feedback_order = 0;
  double delay = std::numeric_limits<double>::quiet_NaN();
  std::string delay_scan;
  int scan_points = 13;
  FeedbackIdentificationOptions options;  ///< every field a flag (field_flags.h) but two
};

void run_feedback(const FeedbackFlags& f) {
  if (f.forward_order < 1 || f.feedback_order < 1)
    usage_error("--forward-order and --feedback-order must be >= 1, got " +
                std::to_string(f.forward_order) + " and " + std::to_string(f.feedback_order));
  if (f.scan_points < 2 || f.scan_points > 10000)
    usage_error("--scan-points is " + std::to_string(f.scan_points) +
                "; a delay scan takes 2 to 10000 points (each is one step-1 fit)");
  const bool scan = !f.delay_scan.empty();
  if (scan == !std::isnan(f.delay)) usage_error("give one of --delay D or --delay-scan MIN:MAX");
  if (!scan && !(f.delay >= 0.0))
    usage_error("--delay must be >= 0, got " + format_number(f.delay));
  const std::filesystem::path output(f.output);

  io::CsvColumns columns;
  columns.time = f.time_column;
  columns.input = f.input_column;
  columns.output = f.output_column;
  const SampledData data = io::read_sampled_data(f.data, columns);

  const DelayedFeedbackStructure structure{f.forward_order, f.feedback_order};
  const FeedbackIdentificationOptions& options = f.options;

  io::DelayedFeedbackResult document;
  FeedbackIdentificationResult& r = document.identification;
  if (scan) {
    const auto colon = f.delay_scan.find(':');
    if (colon == std::string::npos)
      usage_error("--delay-scan must be MIN:MAX, got " + f.delay_scan);
    double lo = 0.0, hi = 0.0;
    try {
      lo = std::stod(f.delay_scan.substr(0, colon));
      hi = std::stod(f.delay_scan.substr(colon + 1));
    } catch (const std::exception&) {
      usage_error("--delay-scan must be MIN:MAX with numbers, got " + f.delay_scan);
    }
    if (!(lo >= 0.0) || !(hi > lo))
      usage_error("--delay-scan needs 0 <= MIN < MAX, got " + f.delay_scan);
    DelayIdentificationOptions d;
    d.identification = options;
    d.scan.min_delay = lo;
    d.scan.max_delay = hi;
    d.scan.points = f.scan_points;
    d.scan.regressors = options.regressors;
    d.scan.hold = options.output_error.hold;
    Progress progress("ctid feedback", f.quiet);
    const DelayIdentificationResult s =
        identify(data, structure, d, progress.callback("delay scan"));
    progress.clear();
    r = s.identification;
    document.delay_scan = s.scan;
  } else {
    r = identify(data, structure, f.delay, options);
  }

  if (!f.output.empty())
    io::write_delayed_feedback_result(output, document,
                                      f.force ? io::Overwrite::yes : io::Overwrite::no);
  if (!f.quiet) {
    // How the refinement ended is printed as `ctid fit` prints it; a run in which every
    // separation candidate failed is an outcome (no_solution), not an error.
    if (!r.verdict.usable) std::cout << "WARNING: " << r.verdict.summary() << "\n";
    std::cout << "termination: " << r.brief_report() << "\n";
    if (r.best_candidate) {
      std::cout << "F(s) = (" << r.loop.forward.numerator().to_string() << ") / ("
                << r.loop.forward.denominator().to_string() << ")\n"
                << "H(s) = (" << r.loop.feedback.numerator().to_string() << ") / ("
                << r.loop.feedback.denominator().to_string() << ")\n"
                << "delay = " << r.loop.delay << " s, output rms = " << r.output_rms << ", "
                << r.message << "\n";
    }
    if (!f.output.empty()) std::cout << "wrote " << output.string() << "\n";
  }
}

Command add_feedback_command(CLI::App& parent) {
  auto flags = std::make_shared<FeedbackFlags>();
  FeedbackFlags& f = *flags;
  CLI::App* app = parent.add_subcommand(
      "feedback",
      "Identify forward F and feedback H of a loop with a delay in the feedback path, "
      "W = F/(1 + F H e^{-Ds}), from a CSV record t,u,y.");
  app->footer(
      "Output JSON: a delayed_feedback_result document (type, version, identification: loop "
      "with F and H as transfer_function documents, step 1, candidates, Cramer-Rao, "
      "termination; delay_scan when scanned); ctid simulate --model accepts it. See "
      "docs/algorithms/feedback-delay.md. Exit status: 0 ran, 2 bad usage or input, 1 other "
      "error.");
  app->add_option("data", f.data, "CSV record with time, input and output columns")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--forward-order", f.forward_order, "Order n of F (denominator degree)")
      ->required();
  app->add_option("--feedback-order", f.feedback_order, "Order m of H (denominator degree)")
      ->required();
  auto* delay = app->add_option("--delay", f.delay, "Known feedback delay D [s]");
  auto* delay_scan =
      app->add_option("--delay-scan", f.delay_scan, "Unknown delay: scan MIN:MAX [s], then refine");
  delay->excludes(delay_scan);
  app->add_option("--scan-points", f.scan_points, "Grid points of --delay-scan")
      ->capture_default_str();
  FieldFlagSettings settings;
  // An Eigen vector and matrix: given from Python or JSON, not on the command line.
  settings.none = {"recursive.initial_theta", "recursive.initial_covariance_matrix"};
  add_field_flags(*app, f.options, settings);
  app->add_option("--input-column", f.input_column, "Input column")->capture_default_str();
  app->add_option("--output-column", f.output_column, "Output column")->capture_default_str();
  app->add_option("--time-column", f.time_column, "Time column")->capture_default_str();
  app->add_option("--output,-o", f.output, "JSON result file to write");
  app->add_flag("--force", f.force, "Replace --output if it exists (never replaced otherwise)");
  app->add_flag("--quiet,-q", f.quiet, "Print nothing on success");
  Command command;
  command.app = app;
  command.run = [flags] {
    run_feedback(*flags);
    return kExitOk;
  };
  return command;
}

}  // namespace

CTID_REGISTER_COMMAND(50, add_feedback_command);

}  // namespace ctid::cli
