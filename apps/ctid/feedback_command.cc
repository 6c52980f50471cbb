// `ctid feedback`: forward F and feedback H of a loop with a delay in the feedback path,
// W = F/(1 + F H e^{-Δs}), from a record t,u,y (u the loop input, y its output), by
// ctid::identify_delayed_feedback (step 1, separation candidates, output-error refinement
// from each) or, with --delay-scan, identify_delayed_feedback_with_delay_scan. Writes JSON
// with ascending coefficients; algorithm and conventions in docs/algorithms/feedback-delay.md.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <string>

#include "command.h"
#include "ctid/core/error.h"
#include "ctid/delayed_feedback/identification.h"
#include "ctid/io/json.h"
#include "ctid/io/sampled_data_csv.h"

namespace ctid::cli {
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
  std::string step1 = "batch";
  std::string separation = "both";
  std::string hold = "foh";
  double filter_pole = 1.0;
};

nlohmann::json coefficients(const Polynomial& p) {
  nlohmann::json a = nlohmann::json::array();
  for (int i = 0; i <= p.degree(); ++i) a.push_back(p.coefficient(i));
  return a;
}

nlohmann::json model(const TransferFunction& tf) {
  return {{"numerator", coefficients(tf.numerator())},
          {"denominator", coefficients(tf.denominator())}};
}

nlohmann::json finite_or_null(double x) { return std::isfinite(x) ? nlohmann::json(x) : nullptr; }

nlohmann::json vector(const Eigen::VectorXd& v) {
  nlohmann::json a = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(finite_or_null(v(i)));
  return a;
}

void run_feedback(const FeedbackFlags& f) {
  if (f.forward_order < 1 || f.feedback_order < 1)
    usage_error("--forward-order and --feedback-order must be >= 1, got " +
                std::to_string(f.forward_order) + " and " + std::to_string(f.feedback_order));
  const bool scan = !f.delay_scan.empty();
  if (scan == !std::isnan(f.delay)) usage_error("give one of --delay D or --delay-scan MIN:MAX");
  if (!scan && !(f.delay >= 0.0))
    usage_error("--delay must be >= 0, got " + std::to_string(f.delay));
  const std::filesystem::path output(f.output);
  if (!f.output.empty() && !f.force && std::filesystem::exists(output))
    usage_error(output.string() + ": file exists; pass --force to replace it");

  io::CsvColumns columns;
  columns.time = f.time_column;
  columns.input = f.input_column;
  columns.output = f.output_column;
  const SampledData data = io::read_sampled_data(f.data, columns);

  FeedbackIdentificationOptions options;
  options.regressors.filter_pole = f.filter_pole;
  options.step1 = f.step1 == "rls" ? Step1Method::kRecursive : Step1Method::kBatch;
  options.separation = f.separation == "gcd"         ? SeparationMethod::kGcd
                       : f.separation == "kronecker" ? SeparationMethod::kKronecker
                                                     : SeparationMethod::kBoth;
  options.output_error.hold = f.hold == "zoh" ? Hold::zero_order_hold : Hold::first_order_hold;

  FeedbackIdentificationResult r;
  nlohmann::json scan_json = nullptr;
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
    const DelayIdentificationResult s =
        identify_delayed_feedback_with_delay_scan(data, f.forward_order, f.feedback_order, d);
    r = s.identification;
    scan_json = {{"delays", vector(s.scan.delays)},
                 {"criterion", vector(s.scan.criterion)},
                 {"grid_delay", s.scan.delay}};
  } else {
    r = identify_delayed_feedback(data, f.forward_order, f.feedback_order, f.delay, options);
  }
  if (!r.best_candidate) throw std::runtime_error("no usable separation candidate: " + r.message);

  nlohmann::json candidates = nlohmann::json::array();
  for (const SeparationCandidateReport& c : r.candidates)
    candidates.push_back({{"source", c.source},
                          {"kronecker_cost", finite_or_null(c.kronecker_cost)},
                          {"start_rms", finite_or_null(c.start_rms)},
                          {"refined_rms", finite_or_null(c.refined_rms)}});
  const nlohmann::json result = {
      {"kind", "delayed_feedback"},
      {"coefficients", "ascending powers of s"},
      {"forward", model(r.loop.forward)},
      {"feedback", model(r.loop.feedback)},
      {"delay", r.loop.delay},
      {"closed_loop",
       {{"alpha", coefficients(r.loop.alpha())},
        {"beta", coefficients(r.loop.beta())},
        {"gamma", coefficients(r.loop.gamma())}}},
      {"diagnostics",
       {{"output_rms", finite_or_null(r.output_rms)},
        {"message", r.message},
        {"step1",
         {{"alpha", coefficients(r.step1.alpha)},
          {"beta", coefficients(r.step1.beta)},
          {"gamma", coefficients(r.step1.gamma)},
          {"residual_rms", r.step1.residual_rms},
          {"condition_number", r.step1.condition_number},
          {"output_rms", finite_or_null(r.step1_output_rms)}}},
        {"candidates", candidates},
        {"best_candidate", *r.best_candidate},
        {"cramer_rao",
         {{"parameters", vector(r.cramer_rao.parameters)},
          {"standard_deviations", vector(r.cramer_rao.standard_deviations)},
          {"separable", r.cramer_rao.separable},
          {"message", r.cramer_rao.message}}},
        {"delay_scan", scan_json}}}};
  if (!f.output.empty())
    io::write_json(output, result, f.force ? io::Overwrite::yes : io::Overwrite::no);
  if (!f.quiet) {
    std::cout << "F(s) = (" << r.loop.forward.numerator().to_string() << ") / ("
              << r.loop.forward.denominator().to_string() << ")\n"
              << "H(s) = (" << r.loop.feedback.numerator().to_string() << ") / ("
              << r.loop.feedback.denominator().to_string() << ")\n"
              << "delay = " << r.loop.delay << " s, output rms = " << r.output_rms << ", "
              << r.message << "\n";
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
      "Output JSON: forward/feedback numerator and denominator (ascending powers of s, monic "
      "denominators), delay, closed_loop alpha/beta/gamma, diagnostics (step 1, candidates, "
      "Cramer-Rao). See docs/algorithms/feedback-delay.md. Exit status: 0 ran, 2 bad usage or "
      "input, 1 other error.");
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
  app->add_option("--step1", f.step1, "Step 1 solver")
      ->check(CLI::IsMember({"batch", "rls"}))
      ->capture_default_str();
  app->add_option("--separation", f.separation, "Separation candidates")
      ->check(CLI::IsMember({"kronecker", "gcd", "both"}))
      ->capture_default_str();
  app->add_option("--hold", f.hold, "Input between samples in the output-error model")
      ->check(CLI::IsMember({"zoh", "foh"}))
      ->capture_default_str();
  app->add_option("--filter-pole", f.filter_pole, "Pole a > 0 of the step-1 filter 1/(s+a)^q")
      ->capture_default_str();
  app->add_option("--input-column", f.input_column, "Input column")->capture_default_str();
  app->add_option("--output-column", f.output_column, "Output column")->capture_default_str();
  app->add_option("--time-column", f.time_column, "Time column")->capture_default_str();
  app->add_option("--output,-o", f.output, "JSON result file to write");
  app->add_flag("--force", f.force, "Replace --output if it exists (never replaced otherwise)");
  app->add_flag("--quiet,-q", f.quiet, "Print nothing on success");
  Command command;
  command.app = app;
  command.run = [flags] { run_feedback(*flags); };
  return command;
}

}  // namespace

CTID_REGISTER_COMMAND(50, add_feedback_command);

}  // namespace ctid::cli
