// Python bindings of the delayed-feedback module (De Iuliis et al.): step-1 regressors and
// least squares, separation of F and H, output-error and IV refinement, Cramér-Rao report,
// delay scan, the identification pipeline and the Section 4 validation protocol.
#include "common.h"
#include "ctid/delayed_feedback/least_squares.h"
#include "ctid/delayed_feedback/identification.h"
#include "ctid/delayed_feedback/regressors.h"
#include "ctid/delayed_feedback/separation.h"
#include "ctid/delayed_feedback/validation.h"

namespace ctid::python {

namespace {

void bind_feedback(py::module_& m) {
  py::enum_<RegressorFilter>(m, "RegressorFilter", "Filter of the step-1 regressors.")
      .value("integrator_chain", RegressorFilter::kIntegratorChain, "1/s^q (the paper).")
      .value("linear_integral_filter", RegressorFilter::kLinearIntegralFilter, "1/(s+a)^q.");
  OptionsClass<FeedbackRegressorOptions>(m, "FeedbackRegressorOptions",
                                         "Options of build_feedback_regression.")
      .field("filter", &FeedbackRegressorOptions::filter, "RegressorFilter.")
      .field("filter_pole", &FeedbackRegressorOptions::filter_pole, "a of 1/(s+a)^q.")
      .field("initial_condition_terms", &FeedbackRegressorOptions::initial_condition_terms,
             "Append nuisance columns for initial conditions.")
      .field("first_equation", &FeedbackRegressorOptions::first_equation,
             "First equation k; -1: ceil(Delta/delta).")
      .finish();
  py::class_<FeedbackRegression>(m, "FeedbackRegression", "target = regressor [theta; nuisance].")
      .def_readonly("regressor", &FeedbackRegression::regressor, "C.")
      .def_readonly("target", &FeedbackRegression::target, "y.")
      .def_readonly("sample_index", &FeedbackRegression::sample_index, "k of each row.")
      .def_readonly("forward_order", &FeedbackRegression::forward_order, "n.")
      .def_readonly("feedback_order", &FeedbackRegression::feedback_order, "m.")
      .def_readonly("theta_size", &FeedbackRegression::theta_size, "3(n+m) - 1.")
      .def_readonly("nuisance_size", &FeedbackRegression::nuisance_size, "Nuisance columns.")
      .def_readonly("delay", &FeedbackRegression::delay, "Delta [s].")
      .def_readonly("sample_time", &FeedbackRegression::sample_time, "delta [s].");
  m.def(
      "build_feedback_regression",
      [](const SampledData& data, int forward_order, int feedback_order, double delay,
         const std::optional<FeedbackRegressorOptions>& options, const py::kwargs& kwargs) {
        return build_feedback_regression(
            data, forward_order, feedback_order, delay,
            options_from<FeedbackRegressorOptions>("build_feedback_regression", options, kwargs));
      },
      py::arg("data"), py::arg("forward_order"), py::arg("feedback_order"), py::arg("delay"),
      py::arg("options") = py::none(), "Step-1 regression of the delayed-feedback loop.");

  py::class_<ClosedLoopEstimate>(m, "ClosedLoopEstimate", "alpha, beta, gamma and diagnostics.")
      .def_readonly("alpha", &ClosedLoopEstimate::alpha, "alpha.")
      .def_readonly("beta", &ClosedLoopEstimate::beta, "beta (monic).")
      .def_readonly("gamma", &ClosedLoopEstimate::gamma, "gamma.")
      .def_readonly("theta", &ClosedLoopEstimate::theta, "The paper's theta.")
      .def_readonly("nuisance", &ClosedLoopEstimate::nuisance, "Nuisance coefficients.")
      .def_readonly("residual_rms", &ClosedLoopEstimate::residual_rms, "Residual rms.")
      .def_readonly("condition_number", &ClosedLoopEstimate::condition_number, "cond(C).")
      .def_readonly("ridge", &ClosedLoopEstimate::ridge, "Ridge weight used.")
      .def_readonly("equations", &ClosedLoopEstimate::equations, "Rows used.")
      .def_readonly("theta_history", &ClosedLoopEstimate::theta_history, "RLS trajectory.");
  m.def("closed_loop_polynomials", &closed_loop_polynomials, py::arg("theta"), py::arg("q"),
        "Split theta into alpha, beta, gamma.");
  m.def("closed_loop_theta", &closed_loop_theta, py::arg("alpha"), py::arg("beta"),
        py::arg("gamma"), "theta of known polynomials.");
  py::enum_<LeastSquaresSolver>(m, "LeastSquaresSolver", "Batch solver.")
      .value("qr", LeastSquaresSolver::kQr, "Column-pivoted QR.")
      .value("svd", LeastSquaresSolver::kSvd, "SVD.");
  py::enum_<Regularisation>(m, "Regularisation", "Ridge choice.")
      .value("none", Regularisation::kNone, "Plain least squares.")
      .value("fixed", Regularisation::kFixed, "Fixed ridge weight.")
      .value("gcv", Regularisation::kGcv, "Weight by generalised cross-validation.");
  OptionsClass<BatchLeastSquaresOptions>(m, "BatchLeastSquaresOptions",
                                         "Options of estimate_closed_loop_batch.")
      .field("solver", &BatchLeastSquaresOptions::solver, "LeastSquaresSolver.")
      .field("regularisation", &BatchLeastSquaresOptions::regularisation, "Regularisation.")
      .field("ridge", &BatchLeastSquaresOptions::ridge, "Fixed relative ridge weight.")
      .field("gcv_min", &BatchLeastSquaresOptions::gcv_min, "GCV grid lower end.")
      .field("gcv_max", &BatchLeastSquaresOptions::gcv_max, "GCV grid upper end.")
      .field("gcv_points", &BatchLeastSquaresOptions::gcv_points, "GCV grid size.")
      .field("rank_tolerance", &BatchLeastSquaresOptions::rank_tolerance, "Rank threshold.")
      .finish();
  m.def(
      "estimate_closed_loop_batch",
      [](const FeedbackRegression& regression,
         const std::optional<BatchLeastSquaresOptions>& options, const py::kwargs& kwargs) {
        return estimate_closed_loop_batch(
            regression,
            options_from<BatchLeastSquaresOptions>("estimate_closed_loop_batch", options, kwargs));
      },
      py::arg("regression"), py::arg("options") = py::none(), "Batch least squares of step 1.");
  OptionsClass<RecursiveLeastSquaresOptions>(m, "RecursiveLeastSquaresOptions",
                                             "Options of estimate_closed_loop_recursive.")
      .field("forgetting", &RecursiveLeastSquaresOptions::forgetting, "lambda in (0, 1].")
      .field("initial_theta", &RecursiveLeastSquaresOptions::initial_theta, "theta(0) or None.")
      .field("initial_covariance", &RecursiveLeastSquaresOptions::initial_covariance,
             "P(0) = value * I.")
      .field("initial_covariance_matrix", &RecursiveLeastSquaresOptions::initial_covariance_matrix,
             "P(0) in full or None.")
      .field("keep_history", &RecursiveLeastSquaresOptions::keep_history, "Keep theta(k).")
      .finish();
  m.def(
      "estimate_closed_loop_recursive",
      [](const FeedbackRegression& regression,
         const std::optional<RecursiveLeastSquaresOptions>& options, const py::kwargs& kwargs) {
        return estimate_closed_loop_recursive(
            regression, options_from<RecursiveLeastSquaresOptions>("estimate_closed_loop_recursive",
                                                                   options, kwargs));
      },
      py::arg("regression"), py::arg("options") = py::none(), "Recursive least squares (13).");
  py::class_<RecursiveLeastSquares>(m, "RecursiveLeastSquares", "RLS of eq. (13).")
      .def(py::init<Eigen::VectorXd, Eigen::MatrixXd, double>(), py::arg("theta0"), py::arg("p0"),
           py::arg("forgetting"), "From theta(0), P(0) and lambda.")
      .def("update", &RecursiveLeastSquares::update, py::arg("c"), py::arg("y"), "One update.")
      .def_property_readonly("theta", &RecursiveLeastSquares::theta, "Current theta.")
      .def_property_readonly("covariance", &RecursiveLeastSquares::covariance, "Current P.");
  py::class_<SeparationCandidateReport>(m, "SeparationCandidateReport",
                                        "One separation candidate of identify_delayed_feedback.")
      .def_readonly("source", &SeparationCandidateReport::source,
                    "'gcd', 'kronecker: <start>' or 'structured step 1'.")
      .def_readonly("start", &SeparationCandidateReport::start, "DelayedFeedbackLoop start.")
      .def_readonly("kronecker_cost", &SeparationCandidateReport::kronecker_cost, "J of the start.")
      .def_readonly("start_rms", &SeparationCandidateReport::start_rms,
                    "Output-error rms of the start (inf: unstable).")
      .def_readonly("refined_rms", &SeparationCandidateReport::refined_rms,
                    "Output-error rms after refinement.");
  py::class_<FeedbackIdentificationResult>(m, "FeedbackIdentificationResult",
                                           "F, H and diagnostics of identify_delayed_feedback.")
      .def_readonly("loop", &FeedbackIdentificationResult::loop,
                    "DelayedFeedbackLoop (F, H, delay).")
      .def_readonly("step1", &FeedbackIdentificationResult::step1, "ClosedLoopEstimate (W).")
      .def_readonly("step1_output_rms", &FeedbackIdentificationResult::step1_output_rms,
                    "Output-error rms of the step-1 W (inf: unstable).")
      .def_readonly("candidates", &FeedbackIdentificationResult::candidates,
                    "SeparationCandidateReport list.")
      .def_readonly("best_candidate", &FeedbackIdentificationResult::best_candidate,
                    "Index of the chosen candidate (None: none).")
      .def_readonly("output_rms", &FeedbackIdentificationResult::output_rms,
                    "Output-error rms of the returned loop.")
      .def_readonly("message", &FeedbackIdentificationResult::message, "Summary.")
      .def_property_readonly(
          "cramer_rao_standard_deviations",
          [](const FeedbackIdentificationResult& r) { return r.cramer_rao.standard_deviations; },
          "Cramer-Rao standard deviations of [a_F | b_F | a_H | b_H] at the estimate.");
  const FeedbackIdentificationOptions default_identification;
  m.def(
      "identify_delayed_feedback",
      [](const SampledData& data, int forward_order, int feedback_order, double delay, Hold hold,
         double filter_pole, const std::vector<double>& iv_filter_poles) {
        FeedbackIdentificationOptions options;
        options.output_error.hold = hold;
        options.regressors.filter_pole = filter_pole;
        options.iv_filter_poles = iv_filter_poles;
        options.validate();
        py::gil_scoped_release release;
        return identify_delayed_feedback(data, forward_order, feedback_order, delay, options);
      },
      py::arg("data"), py::arg("forward_order"), py::arg("feedback_order"), py::arg("delay"),
      py::arg("hold") = Hold::first_order_hold, py::arg("filter_pole") = 1.0,
      py::arg("iv_filter_poles") = default_identification.iv_filter_poles,
      "F and H of a loop with a delayed feedback: step 1, separation candidates (GCD, min J, "
      "structured step 1, a bias-corrected IV start per pole in iv_filter_poles), output-error "
      "refinement from each; the smallest output error wins.");

  OptionsClass<StructuredIvOptions>(m, "StructuredIvOptions",
                                    "Options of estimate_structured_step1_iv.")
      .field("iterations", &StructuredIvOptions::iterations, "IV iterations.")
      .field("max_iterations", &StructuredIvOptions::max_iterations,
             "Levenberg-Marquardt steps per iteration.")
      .field("tolerance", &StructuredIvOptions::tolerance, "|d rho| / max(1, |rho|) to stop.")
      .field("hold", &StructuredIvOptions::hold, "Hold of the simulated instruments.")
      .field("bias_correction", &StructuredIvOptions::bias_correction,
             "Subtract the estimator's error on the model's own simulated output.")
      .field("substeps", &StructuredIvOptions::substeps, "RK4 steps per sample.")
      .finish();
  py::class_<StructuredIvResult>(m, "StructuredIvResult", "Outcome of the structured IV.")
      .def_readonly("loop", &StructuredIvResult::loop, "DelayedFeedbackLoop.")
      .def_readonly("output_rms", &StructuredIvResult::output_rms, "Output-error rms.")
      .def_readonly("output_rms_history", &StructuredIvResult::output_rms_history,
                    "Start, then each iterate (inf: unstable).")
      .def_readonly("iterations", &StructuredIvResult::iterations, "Iterations run.")
      .def_readonly("termination", &StructuredIvResult::termination, "Why it stopped.")
      .def("converged", &StructuredIvResult::converged, "termination == converged.")
      .def_readonly("message", &StructuredIvResult::message, "Summary.");
  m.def(
      "estimate_structured_step1_iv",
      [](const SampledData& data, const DelayedFeedbackLoop& start,
         const FeedbackRegressorOptions& regressors,
         const std::optional<StructuredIvOptions>& options, const py::kwargs& kwargs) {
        const auto o =
            options_from<StructuredIvOptions>("estimate_structured_step1_iv", options, kwargs);
        py::gil_scoped_release release;
        return estimate_structured_step1_iv(data, start, regressors, o);
      },
      py::arg("data"), py::arg("start"), py::arg("regressors"), py::arg("options") = py::none(),
      "Bias-corrected instrumental variables in F and H's 2(n+m) unknowns, from a start loop: "
      "instruments from the loop's simulated output; the best iterate by output error.");
}

// Step 2 (separation), refinement, quality and validation of the delayed-feedback methods
// (De Iuliis et al., eqs. 19-24, and docs/algorithms/feedback-delay.md).
void bind_feedback_separation(py::module_& m) {
  py::class_<KroneckerCandidate>(m, "KroneckerCandidate", "One refined start of min J.")
      .def_readonly("start", &KroneckerCandidate::start, "'gcd' or 'roots split k'.")
      .def_readonly("forward", &KroneckerCandidate::forward, "F of this start.")
      .def_readonly("feedback", &KroneckerCandidate::feedback, "H of this start.")
      .def_readonly("cost", &KroneckerCandidate::cost, "J after Levenberg-Marquardt.");
  py::class_<KroneckerSeparationResult>(m, "KroneckerSeparationResult",
                                        "F and H from min J (eqs. 19-21).")
      .def_readonly("forward", &KroneckerSeparationResult::forward, "F(s).")
      .def_readonly("feedback", &KroneckerSeparationResult::feedback, "H(s).")
      .def_readonly("cost", &KroneckerSeparationResult::cost, "J at the returned F, H.")
      .def_readonly("starts", &KroneckerSeparationResult::starts, "Starts refined.")
      .def_readonly("best_start", &KroneckerSeparationResult::best_start, "Winning start.")
      .def_readonly("termination", &KroneckerSeparationResult::termination, "Why it stopped.")
      .def("converged", &KroneckerSeparationResult::converged, "termination == converged.")
      .def_readonly("message", &KroneckerSeparationResult::message, "Summary.")
      .def_readonly("candidates", &KroneckerSeparationResult::candidates,
                    "Every refined start (KroneckerCandidate list).");
  m.def(
      "separate_kronecker",
      [](const Polynomial& alpha, const Polynomial& beta, const Polynomial& gamma,
         int forward_order, int feedback_order, bool multi_start, int max_iterations) {
        KroneckerSeparationOptions options;
        options.multi_start = multi_start;
        options.max_iterations = max_iterations;
        py::gil_scoped_release release;
        return separate_kronecker(alpha, beta, gamma, forward_order, feedback_order, options);
      },
      py::arg("alpha"), py::arg("beta"), py::arg("gamma"), py::arg("forward_order"),
      py::arg("feedback_order"), py::kw_only(), py::arg("multi_start") = true,
      py::arg("max_iterations") = 200,
      "Separate F and H from alpha, beta, gamma (ascending) by min J with Levenberg-Marquardt "
      "from the GCD estimate and every split of the roots of beta.");
  py::class_<GcdSeparationResult>(m, "GcdSeparationResult",
                                  "F and H from the approximate GCD (eqs. 22-24).")
      .def_readonly("forward", &GcdSeparationResult::forward, "F(s).")
      .def_readonly("feedback", &GcdSeparationResult::feedback, "H(s).")
      .def_readonly("forward_singular_values", &GcdSeparationResult::forward_singular_values,
                    "Singular values of the observability matrix of alpha/beta.")
      .def_readonly("feedback_singular_values", &GcdSeparationResult::feedback_singular_values,
                    "Singular values of the observability matrix of gamma/alpha.")
      .def_readonly("forward_gap", &GcdSeparationResult::forward_gap, "sigma_n / sigma_{n+1}.")
      .def_readonly("feedback_gap", &GcdSeparationResult::feedback_gap, "sigma_m / sigma_{m+1}.")
      .def_readonly("cancelled_forward", &GcdSeparationResult::cancelled_forward,
                    "The cancelled part of alpha/beta (approximate D_H).")
      .def_readonly("cancelled_feedback", &GcdSeparationResult::cancelled_feedback,
                    "The cancelled part of gamma/alpha (approximate monic N_F).");
  m.def("separate_approximate_gcd", &separate_approximate_gcd, py::arg("alpha"), py::arg("beta"),
        py::arg("gamma"), py::arg("forward_order"), py::arg("feedback_order"),
        "Separate F and H by Kalman observability decomposition and SVD (approximate GCD).");
  m.def("kronecker_cost", &kronecker_cost, py::arg("alpha"), py::arg("beta"), py::arg("gamma"),
        py::arg("forward"), py::arg("feedback"), "J of eqs. (19)-(21) at F and H.");

  py::class_<SeparabilityReport>(m, "SeparabilityReport",
                                 "Covariance of [a_F | b_F | a_H | b_H]: are F, H separable?")
      .def_readonly("parameters", &SeparabilityReport::parameters, "rho.")
      .def_readonly("covariance", &SeparabilityReport::covariance, "sigma^2 (J'J)^-1.")
      .def_readonly("standard_deviations", &SeparabilityReport::standard_deviations,
                    "Square roots of the covariance diagonal.")
      .def_readonly("relative_standard_deviations",
                    &SeparabilityReport::relative_standard_deviations, "sd / max(|rho_i|, 1e-3).")
      .def_readonly("noise_variance", &SeparabilityReport::noise_variance, "sigma^2.")
      .def_readonly("condition_number", &SeparabilityReport::condition_number,
                    "Of the column-scaled sensitivity matrix.")
      .def_readonly("separable", &SeparabilityReport::separable,
                    "Every relative sd below the threshold.")
      .def_readonly("message", &SeparabilityReport::message, "Verdict in one sentence.");
  m.def("cramer_rao_bound", &cramer_rao_bound, py::arg("loop"), py::arg("input"),
        py::arg("sample_time"), py::arg("hold"), py::arg("noise_sd"),
        py::arg("relative_threshold") = 0.1, py::arg("substeps") = 4,
        "Cramer-Rao bound of rho for this loop, input and white output noise.");

  py::class_<OutputErrorResult>(m, "OutputErrorResult", "Output-error refinement of F and H.")
      .def_readonly("loop", &OutputErrorResult::loop, "DelayedFeedbackLoop (F, H, delay).")
      .def_readonly("residual_rms", &OutputErrorResult::residual_rms, "rms of y - y_hat.")
      .def_readonly("iterations", &OutputErrorResult::iterations, "Iterations.")
      .def_readonly("termination", &OutputErrorResult::termination, "Why it stopped.")
      .def("converged", &OutputErrorResult::converged, "termination == converged.")
      .def_readonly("message", &OutputErrorResult::message, "Summary.")
      .def_readonly("quality", &OutputErrorResult::quality, "SeparabilityReport at the estimate.");
  m.def(
      "refine_output_error",
      [](const SampledData& data, const DelayedFeedbackLoop& start, Hold hold, int substeps,
         int max_iterations, bool estimate_delay) {
        OutputErrorOptions options;
        options.hold = hold;
        options.substeps = substeps;
        options.max_iterations = max_iterations;
        options.estimate_delay = estimate_delay;
        py::gil_scoped_release release;
        return refine_output_error(data, start, options);
      },
      py::arg("data"), py::arg("start"), py::kw_only(), py::arg("hold") = Hold::zero_order_hold,
      py::arg("substeps") = 4, py::arg("max_iterations") = 200, py::arg("estimate_delay") = false,
      "Minimise the output error over F and H (and the delay) from a start.");

  py::class_<ResponseComparison>(m, "ResponseComparison",
                                 "Responses of a true and an estimated model to white noise.")
      .def_readonly("mse", &ResponseComparison::mse, "MSE of this realisation (inf: overflow).")
      .def_readonly("expected_mse", &ResponseComparison::expected_mse,
                    "Expected MSE over realisations.")
      .def_readonly("estimate_stable", &ResponseComparison::estimate_stable, "Estimate stable.")
      .def_readonly("truth", &ResponseComparison::truth, "True response.")
      .def_readonly("estimate", &ResponseComparison::estimate, "Estimated response.");
  m.def(
      "compare_white_noise_response",
      [](const TransferFunction& truth, const TransferFunction& estimate, double sample_time,
         double duration, std::uint64_t seed) {
        WhiteNoiseValidationOptions options;
        options.sample_time = sample_time;
        options.duration = duration;
        options.seed = seed;
        return compare_white_noise_response(truth, estimate, options);
      },
      py::arg("truth"), py::arg("estimate"), py::kw_only(), py::arg("sample_time") = 0.005,
      py::arg("duration") = 5.0, py::arg("seed") = 1,
      "The paper's validation: both models driven by unit-variance white noise held at "
      "sample_time for duration seconds.");
  m.def("expected_white_noise_mse", &expected_white_noise_mse, py::arg("truth"),
        py::arg("estimate"), py::arg("sample_time"), py::arg("samples"),
        "Exact expected MSE of the white-noise validation.");

  py::class_<FeedbackDelayScanResult>(m, "FeedbackDelayScanResult", "A scan over the delay.")
      .def_readonly("delays", &FeedbackDelayScanResult::delays, "Delays tried [s].")
      .def_readonly("criterion", &FeedbackDelayScanResult::criterion, "Criterion per delay.")
      .def_readonly("delay", &FeedbackDelayScanResult::delay, "The minimiser [s].")
      .def_readonly("best_criterion", &FeedbackDelayScanResult::best_criterion, "Its value.");
  py::class_<DelayIdentificationResult>(m, "DelayIdentificationResult",
                                        "F, H and the delay when the delay is unknown.")
      .def_readonly("scan", &DelayIdentificationResult::scan, "FeedbackDelayScanResult.")
      .def_readonly("identification", &DelayIdentificationResult::identification,
                    "FeedbackIdentificationResult at the returned delay.")
      .def_readonly("delay", &DelayIdentificationResult::delay, "Estimated delay [s].")
      .def_readonly("evaluations", &DelayIdentificationResult::evaluations, "Identifications run.");
  m.def(
      "identify_delayed_feedback_with_delay_scan",
      [](const SampledData& data, int forward_order, int feedback_order, double min_delay,
         double max_delay, int points, Hold hold) {
        DelayIdentificationOptions options;
        options.scan.min_delay = min_delay;
        options.scan.max_delay = max_delay;
        options.scan.points = points;
        options.scan.hold = hold;
        options.identification.output_error.hold = hold;
        py::gil_scoped_release release;
        return identify_delayed_feedback_with_delay_scan(data, forward_order, feedback_order,
                                                         options);
      },
      py::arg("data"), py::arg("forward_order"), py::arg("feedback_order"), py::kw_only(),
      py::arg("min_delay"), py::arg("max_delay"), py::arg("points") = 41,
      py::arg("hold") = Hold::first_order_hold,
      "identify_delayed_feedback with the delay unknown: a scan of the refined output error "
      "over [min_delay, max_delay], then a joint refinement of F, H and the delay.");
}

}  // namespace

void bind_delayed_feedback(py::module_& m) {
  bind_feedback(m);
  bind_feedback_separation(m);
}

}  // namespace ctid::python
