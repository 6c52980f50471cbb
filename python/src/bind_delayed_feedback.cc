// Python bindings of the delayed-feedback module (De Iuliis et al.): step-1 regressors and
// least squares, separation of F and H, output-error and IV refinement, Cramér-Rao report,
// delay scan, the identification pipeline and the Section 4 validation protocol. Every options
// and result class, and every enumeration, is derived from its C++ field list (fields.h):
// nothing is named twice. Functions take `options=` or the options' fields as keywords.
#include "common.h"
#include "ctid/delayed_feedback/cramer_rao.h"
#include "ctid/delayed_feedback/feedback_delay_scan.h"
#include "ctid/delayed_feedback/identification.h"
#include "ctid/delayed_feedback/least_squares.h"
#include "ctid/delayed_feedback/loop_parameters.h"
#include "ctid/delayed_feedback/output_error.h"
#include "ctid/delayed_feedback/regressors.h"
#include "ctid/delayed_feedback/separation.h"
#include "ctid/delayed_feedback/structured_iv.h"
#include "ctid/delayed_feedback/structured_step1.h"
#include "ctid/delayed_feedback/validation.h"
#include "fields.h"

namespace ctid::python {

namespace {

/// Adds converged() and brief_report() to a result deriving from Outcome.
template <class Class>
Class& with_outcome(Class& cls) {
  using S = typename Class::type;
  cls.def(
      "converged", [](const S& r) { return r.converged(); }, "termination == converged.");
  cls.def(
      "brief_report", [](const S& r) { return r.brief_report(); },
      "One line: termination, iterations and, unless converged, why.");
  return cls;
}

void bind_feedback_types(py::module_& m) {
  bind_enum<RegressorFilter>(m, "RegressorFilter", "Filter of the step-1 regressors.");
  bind_enum<LeastSquaresSolver>(m, "LeastSquaresSolver", "Batch solver of step 1.");
  bind_enum<Regularisation>(m, "Regularisation", "Ridge choice of step 1.");
  bind_enum<DelayCriterion>(m, "DelayCriterion", "What the delay scan scores.");
  bind_enum<Step1Method>(m, "Step1Method", "Step-1 solver of identify_delayed_feedback.");
  bind_enum<SeparationMethod>(m, "SeparationMethod", "Separation candidates from step 1.");

  bind_options<FeedbackRegressorOptions>(m, "Options of build_feedback_regression.");
  bind_options<BatchLeastSquaresOptions>(m, "Options of estimate_closed_loop_batch.");
  bind_options<RecursiveLeastSquaresOptions>(m, "Options of estimate_closed_loop_recursive.");
  bind_options<KroneckerSeparationOptions>(m, "Options of separate_kronecker.");
  bind_options<StructuredStep1Options>(m, "Options of estimate_structured_step1.");
  bind_options<StructuredIvOptions>(m, "Options of estimate_structured_step1_iv.");
  bind_options<OutputErrorOptions>(m, "Options of refine_output_error.");
  bind_options<FeedbackDelayScanOptions>(m, "Options of scan_feedback_delay.");
  bind_options<FeedbackIdentificationOptions>(m, "Options of identify_delayed_feedback.");
  bind_options<DelayIdentificationOptions>(m,
                                           "Options of identify_delayed_feedback_with_delay_scan.");
  bind_options<WhiteNoiseValidationOptions>(m, "Options of compare_white_noise_response.");

  bind_result<FeedbackRegression>(m, "target = regressor [theta; nuisance].");
  auto closed_loop = bind_result<ClosedLoopEstimate>(m, "alpha, beta, gamma and diagnostics.");
  with_outcome(closed_loop);
  bind_result<SeparabilityReport>(m, "Covariance of [a_F | b_F | a_H | b_H]: are F, H separable?");
  bind_result<KroneckerCandidate>(m, "One refined start of min J.");
  auto kronecker = bind_result<KroneckerSeparationResult>(m, "F and H from min J (eqs. 19-21).");
  with_outcome(kronecker);
  bind_result<GcdSeparationResult>(m, "F and H from the approximate GCD (eqs. 22-24).");
  auto structured = bind_result<StructuredStep1Result>(m, "Outcome of the structured step 1.");
  with_outcome(structured);
  auto iv = bind_result<StructuredIvResult>(m, "Outcome of the structured IV.");
  with_outcome(iv);
  auto oe = bind_result<OutputErrorResult>(m, "Output-error refinement of F and H.");
  with_outcome(oe);
  auto scan = bind_result<FeedbackDelayScanResult>(m, "A scan over the delay.");
  with_outcome(scan);
  bind_result<SeparationCandidateReport>(m, "One separation candidate.");
  auto identification = bind_result<FeedbackIdentificationResult>(
      m, "F, H and diagnostics of identify_delayed_feedback.");
  with_outcome(identification);
  identification.def_property_readonly(
      "cramer_rao_standard_deviations",
      [](const FeedbackIdentificationResult& r) { return r.cramer_rao.standard_deviations; },
      "Cramer-Rao standard deviations of [a_F | b_F | a_H | b_H] at the estimate.");
  auto delay =
      bind_result<DelayIdentificationResult>(m, "F, H and the delay when the delay is unknown.");
  with_outcome(delay);
  bind_result<ResponseComparison>(m, "Responses of a true and an estimated model to white noise.");
}

void bind_feedback_functions(py::module_& m) {
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
  m.def("closed_loop_polynomials", &closed_loop_polynomials, py::arg("theta"), py::arg("q"),
        "Split theta into alpha, beta, gamma.");
  m.def("closed_loop_theta", &closed_loop_theta, py::arg("alpha"), py::arg("beta"),
        py::arg("gamma"), "theta of known polynomials.");
  m.def(
      "estimate_closed_loop_batch",
      [](const FeedbackRegression& regression,
         const std::optional<BatchLeastSquaresOptions>& options, const py::kwargs& kwargs) {
        return estimate_closed_loop_batch(
            regression,
            options_from<BatchLeastSquaresOptions>("estimate_closed_loop_batch", options, kwargs));
      },
      py::arg("regression"), py::arg("options") = py::none(),
      "Batch least squares of step 1; a singular regressor ends in "
      "Termination.singular_equations (no exception).");
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

  m.def(
      "separate_kronecker",
      [](const Polynomial& alpha, const Polynomial& beta, const Polynomial& gamma,
         int forward_order, int feedback_order,
         const std::optional<KroneckerSeparationOptions>& options, const py::kwargs& kwargs) {
        const auto o =
            options_from<KroneckerSeparationOptions>("separate_kronecker", options, kwargs);
        py::gil_scoped_release release;
        return separate_kronecker(alpha, beta, gamma, forward_order, feedback_order, o);
      },
      py::arg("alpha"), py::arg("beta"), py::arg("gamma"), py::arg("forward_order"),
      py::arg("feedback_order"), py::arg("options") = py::none(),
      "Separate F and H from alpha, beta, gamma (ascending) by min J with Levenberg-Marquardt "
      "from the GCD estimate and every split of the roots of beta.");
  m.def("separate_approximate_gcd", &separate_approximate_gcd, py::arg("alpha"), py::arg("beta"),
        py::arg("gamma"), py::arg("forward_order"), py::arg("feedback_order"),
        "Separate F and H by Kalman observability decomposition and SVD (approximate GCD).");
  m.def("kronecker_cost", &kronecker_cost, py::arg("alpha"), py::arg("beta"), py::arg("gamma"),
        py::arg("forward"), py::arg("feedback"), "J of eqs. (19)-(21) at F and H.");

  m.def("loop_parameters", &loop_parameters, py::arg("loop"),
        "rho = [a_F | b_F | a_H | b_H] of a loop (monic denominators).");
  m.def("loop_from_parameters", &loop_from_parameters, py::arg("rho"), py::arg("forward_order"),
        py::arg("feedback_order"), py::arg("delay"), "The loop of rho.");
  m.def("loop_output_rms", &loop_output_rms, py::arg("data"), py::arg("loop"), py::arg("hold"),
        py::arg("substeps") = 4, "Output-error rms of a loop on the data (inf: not simulable).");
  m.def("validate_loop", &validate_loop, py::arg("loop"), py::arg("data"), py::arg("hold"),
        py::arg("substeps") = 4, py::arg("max_lag") = 20,
        "ValidationReport of a loop simulated from rest with the measured input.");
  m.def("cramer_rao_bound", &cramer_rao_bound, py::arg("loop"), py::arg("input"),
        py::arg("sample_time"), py::arg("hold"), py::arg("noise_sd"),
        py::arg("relative_threshold") = 0.1, py::arg("substeps") = 4,
        "Cramer-Rao bound of rho for this loop, input and white output noise.");
  m.def(
      "estimate_structured_step1",
      [](const FeedbackRegression& regression, const std::optional<StructuredStep1Options>& options,
         const py::kwargs& kwargs) {
        const auto o =
            options_from<StructuredStep1Options>("estimate_structured_step1", options, kwargs);
        py::gil_scoped_release release;
        return estimate_structured_step1(regression, o);
      },
      py::arg("regression"), py::arg("options") = py::none(),
      "The step-1 equation error minimised over F and H's 2(n+m) unknowns.");
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
  m.def(
      "refine_output_error",
      [](const SampledData& data, const DelayedFeedbackLoop& start,
         const std::optional<OutputErrorOptions>& options, const py::kwargs& kwargs) {
        const auto o = options_from<OutputErrorOptions>("refine_output_error", options, kwargs);
        py::gil_scoped_release release;
        return refine_output_error(data, start, o);
      },
      py::arg("data"), py::arg("start"), py::arg("options") = py::none(),
      "Minimise the output error over F and H (and the delay) from a start.");
  m.def(
      "scan_feedback_delay",
      [](const SampledData& data, int forward_order, int feedback_order,
         const std::optional<FeedbackDelayScanOptions>& options, const py::kwargs& kwargs) {
        const auto o =
            options_from<FeedbackDelayScanOptions>("scan_feedback_delay", options, kwargs);
        py::gil_scoped_release release;
        return scan_feedback_delay(data, forward_order, feedback_order, o);
      },
      py::arg("data"), py::arg("forward_order"), py::arg("feedback_order"),
      py::arg("options") = py::none(), "Score each delay of a grid by a step-1 criterion.");
  m.def(
      "identify_delayed_feedback",
      [](const SampledData& data, int forward_order, int feedback_order, double delay,
         const std::optional<FeedbackIdentificationOptions>& options, const py::kwargs& kwargs) {
        const auto o = options_from<FeedbackIdentificationOptions>("identify_delayed_feedback",
                                                                   options, kwargs);
        o.validate();
        py::gil_scoped_release release;
        return identify_delayed_feedback(data, forward_order, feedback_order, delay, o);
      },
      py::arg("data"), py::arg("forward_order"), py::arg("feedback_order"), py::arg("delay"),
      py::arg("options") = py::none(),
      "F and H of a loop with a delayed feedback: step 1, separation candidates (GCD, min J, "
      "structured step 1, a bias-corrected IV start per pole in iv_filter_poles), output-error "
      "refinement from each; the smallest output error wins. Options: options= a "
      "FeedbackIdentificationOptions, or its fields as keywords. A fit that fails is a result "
      "with its termination, never an exception.");
  m.def(
      "identify_delayed_feedback_with_delay_scan",
      [](const SampledData& data, int forward_order, int feedback_order,
         const std::optional<DelayIdentificationOptions>& options, const py::kwargs& kwargs) {
        const auto o = options_from<DelayIdentificationOptions>(
            "identify_delayed_feedback_with_delay_scan", options, kwargs);
        o.validate();
        py::gil_scoped_release release;
        return identify_delayed_feedback_with_delay_scan(data, forward_order, feedback_order, o);
      },
      py::arg("data"), py::arg("forward_order"), py::arg("feedback_order"),
      py::arg("options") = py::none(),
      "identify_delayed_feedback with the delay unknown: a scan of the refined output error "
      "over [scan.min_delay, scan.max_delay], then a joint refinement of F, H and the delay. "
      "Options: options= a DelayIdentificationOptions, or its fields as keywords.");

  m.def(
      "compare_white_noise_response",
      [](const TransferFunction& truth, const TransferFunction& estimate,
         const std::optional<WhiteNoiseValidationOptions>& options, const py::kwargs& kwargs) {
        return compare_white_noise_response(truth, estimate,
                                            options_from<WhiteNoiseValidationOptions>(
                                                "compare_white_noise_response", options, kwargs));
      },
      py::arg("truth"), py::arg("estimate"), py::arg("options") = py::none(),
      "The paper's validation: both models driven by unit-variance white noise held at "
      "sample_time for duration seconds.");
  m.def("expected_white_noise_mse", &expected_white_noise_mse, py::arg("truth"),
        py::arg("estimate"), py::arg("sample_time"), py::arg("samples"),
        "Exact expected MSE of the white-noise validation.");
}

}  // namespace

void bind_delayed_feedback(py::module_& m) {
  bind_feedback_types(m);
  bind_feedback_functions(m);
}

}  // namespace ctid::python
