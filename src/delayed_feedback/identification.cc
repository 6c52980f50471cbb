// The delayed-feedback identification pipeline, with the delay known or scanned.
#include "ctid/delayed_feedback/identification.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/delayed_feedback/loop_parameters.h"
#include "delayed_feedback/internal/golden_section.h"
#include "delayed_feedback/internal/structured_system.h"

namespace ctid {

using internal::golden_section_minimum;
using internal::iv_start;
namespace {

constexpr double kNoStart = std::numeric_limits<double>::quiet_NaN();

// "%g" of the C locale whatever LC_NUMERIC says (issue 33).
std::string short_number(double x) { return format_brief(x); }

// The checks of estimation/verdict.h that apply to a delayed-feedback loop (decision 0007):
// a loop was found, its output error is finite (a stable, simulable loop) and its
// output-error fit 100 (1 - rms(e) / rms(y - mean y)) is not negative.
Verdict feedback_verdict(const FeedbackIdentificationResult& r, const SampledData& data) {
  Verdict verdict;
  if (r.termination == Termination::no_solution) {
    verdict.fail("no candidate gave a stable loop (" + r.message + ")",
                 {verdict_advice::lower_order, verdict_advice::more_data});
    return verdict;
  }
  if (!std::isfinite(r.output_rms)) {
    verdict.fail("the loop's output error is not finite (unstable or overflowed)",
                 {verdict_advice::lower_order, verdict_advice::better_start});
    return verdict;
  }
  const Eigen::VectorXd& y = data.output();
  const double spread = std::sqrt((y.array() - y.mean()).square().mean());
  if (!(spread > 0.0)) {
    verdict.fail("the output is constant, so the record says nothing about the loop",
                 {verdict_advice::more_data});
    return verdict;
  }
  check_fit(verdict, 100.0 * (1.0 - r.output_rms / spread), kNoStart);
  return verdict;
}

// A candidate's screening refinement: output error from `start` continued over growing
// parts of the record (the first part is dominated by the transient, whose cost has fewer
// local minima; each stage starts where the shorter one ended), then over the whole record.
OutputErrorResult continued_refinement(const SampledData& data, const DelayedFeedbackLoop& start,
                                       int n, int m, double delay,
                                       const FeedbackIdentificationOptions& options,
                                       const OutputErrorOptions& screen) {
  DelayedFeedbackLoop current = start;
  for (double fraction : options.continuation_fractions) {
    const auto samples = static_cast<Eigen::Index>(std::lround(fraction * data.size()));
    if (samples <= 2 * (n + m) + 1 || samples >= data.size() ||
        static_cast<double>(samples - 1) * data.sample_time() <= delay)
      continue;
    const SampledData part(data.sample_time(), data.input().head(samples),
                           data.output().head(samples));
    const OutputErrorResult stage = refine_output_error(part, current, screen);
    if (std::isfinite(stage.residual_rms)) current = stage.loop;
  }
  return refine_output_error(data, current, screen);
}

// The finalists: the best screened candidate (r.best_candidate, of cost `best`) and up to
// extra_finalists runner-ups within finalist_ratio of it, each continued to convergence; the
// smallest final cost wins. Returns it.
double refine_finalists(FeedbackIdentificationResult& r, const SampledData& data,
                        const FeedbackIdentificationOptions& options, double best) {
  std::vector<std::size_t> finalists{*r.best_candidate};
  {
    std::vector<std::size_t> others;
    for (std::size_t i = 0; i < r.candidates.size(); ++i)
      if (i != finalists[0] && r.candidates[i].refined_rms <= options.finalist_ratio * best)
        others.push_back(i);
    std::sort(others.begin(), others.end(), [&](std::size_t x, std::size_t y) {
      return r.candidates[x].refined_rms < r.candidates[y].refined_rms;
    });
    for (std::size_t k = 0;
         k < others.size() && k < static_cast<std::size_t>(options.extra_finalists); ++k)
      finalists.push_back(others[k]);
  }
  for (std::size_t i : finalists) {
    SeparationCandidateReport& c = r.candidates[i];
    if (!c.refinement.converged() &&
        options.output_error.max_iterations > options.screening_iterations) {
      OutputErrorOptions rest = options.output_error;
      rest.max_iterations = options.output_error.max_iterations - options.screening_iterations;
      OutputErrorResult more = refine_output_error(data, c.refinement.loop, rest);
      if (std::isfinite(more.residual_rms) && more.residual_rms <= c.refined_rms) {
        more.iterations += c.refinement.iterations;
        c.refinement = std::move(more);
        c.refined_rms = c.refinement.residual_rms;
      }
    }
  }
  for (std::size_t i : finalists)
    if (r.candidates[i].refined_rms < r.candidates[*r.best_candidate].refined_rms)
      r.best_candidate = i;
  return r.candidates[*r.best_candidate].refined_rms;
}

}  // namespace

void FeedbackIdentificationOptions::check_relations(const std::string& path) const {
  iv.check_agrees(path + ".iv", output_error.hold, output_error.substeps);
}

FeedbackIdentificationResult identify_delayed_feedback(
    const SampledData& data, int n, int m, double delay,
    const FeedbackIdentificationOptions& options) {
  require(n >= 1 && m >= 1, "identify_delayed_feedback: orders must be >= 1, got n = ", n,
          ", m = ", m);
  require(std::isfinite(delay) && delay >= 0.0,
          "identify_delayed_feedback: delay must be >= 0, got ", delay);
  options.validate();
  const double inf = std::numeric_limits<double>::infinity();
  const FeedbackRegression reg = build_feedback_regression(data, n, m, delay, options.regressors);
  FeedbackIdentificationResult r;
  r.step1 = options.step1 == Step1Method::batch
                ? estimate_closed_loop_batch(reg, options.batch)
                : estimate_closed_loop_recursive(reg, options.recursive);
  // A singular unstructured regression: only the structured candidates remain.
  const bool have_step1 = r.step1.converged();
  if (!have_step1) r.message = "step 1: " + r.step1.message + "; ";
  const Hold hold = options.output_error.hold;
  const int substeps = options.output_error.substeps;
  r.step1_output_rms = inf;
  if (have_step1) {
    const Eigen::VectorXd y = simulate_delayed(
        to_delayed_state_space(r.step1.alpha, r.step1.beta, r.step1.gamma, delay), data.input(),
        data.sample_time(), hold, DelayedSimulationOptions{substeps});
    r.step1_output_rms =
        y.allFinite() && y.cwiseAbs().maxCoeff() < 1e12
            ? std::sqrt((data.output() - y).squaredNorm() / static_cast<double>(y.size()))
            : inf;
  }
  const Polynomial& a = r.step1.alpha;
  const Polynomial& b = r.step1.beta;
  const Polynomial& g = r.step1.gamma;
  auto add = [&](std::string source, const TransferFunction& f, const TransferFunction& h) {
    if (f.denominator().degree() != n || h.denominator().degree() != m) return;
    SeparationCandidateReport c;
    c.source = std::move(source);
    c.start = DelayedFeedbackLoop{f.normalized(), h.normalized(), delay};
    if (!loop_is_simulable(c.start)) return;
    c.kronecker_cost =
        have_step1 ? kronecker_cost(a, b, g, c.start.forward, c.start.feedback) : inf;
    c.start_rms = loop_output_rms(data, c.start, hold, substeps);
    c.refined_rms = c.start_rms;
    r.candidates.push_back(std::move(c));
  };
  // α̂ of low degree: no GCD candidate.
  if (have_step1 && options.separation != SeparationMethod::kronecker && a.degree() == n + m - 1) {
    const GcdSeparationResult gcd = separate_approximate_gcd(a, b, g, n, m);
    add("gcd", gcd.forward, gcd.feedback);
  }
  if (have_step1 && options.separation != SeparationMethod::gcd) {
    // No usable start (no_solution): no candidates.
    const KroneckerSeparationResult kr = separate_kronecker(a, b, g, n, m, options.kronecker);
    for (const KroneckerCandidate& c : kr.candidates)
      add("kronecker: " + c.start, c.forward, c.feedback);
  }
  if (options.structured_candidate) {
    // A degenerate structured fit (no_solution) gives no simulable candidate.
    const StructuredStep1Result st = estimate_structured_step1(reg, options.structured);
    if (st.termination != Termination::no_solution)
      add("structured step 1", st.loop.forward, st.loop.feedback);
  }
  {
    StructuredIvOptions iv = options.iv;
    iv.hold = hold;
    iv.substeps = substeps;
    for (double pole : options.iv_filter_poles) {
      // No stable start at this pole: output_rms is +inf.
      const StructuredIvResult st = iv_start(data, n, m, delay, options.regressors, pole, iv);
      if (std::isfinite(st.output_rms))
        add("structured iv a = " + short_number(pole), st.loop.forward, st.loop.feedback);
    }
  }
  if (r.candidates.empty()) {
    r.message += "no separation candidate with the requested orders";
    r.output_rms = inf;
    r.termination = Termination::no_solution;
    r.verdict = feedback_verdict(r, data);
    return r;
  }
  // Every candidate gets a short output-error refinement; the best then runs to convergence.
  double best = inf;
  OutputErrorOptions screen = options.output_error;
  screen.max_iterations = std::min(options.screening_iterations, screen.max_iterations);
  for (std::size_t i = 0; i < r.candidates.size(); ++i) {
    SeparationCandidateReport& c = r.candidates[i];
    if (options.refine && std::isfinite(c.start_rms)) {
      c.refinement = continued_refinement(data, c.start, n, m, delay, options, screen);
      c.refined_rms = std::isfinite(c.refinement.residual_rms) ? c.refinement.residual_rms : inf;
    }
    if (c.refined_rms < best || !r.best_candidate) {
      best = c.refined_rms;
      r.best_candidate = i;
    }
  }
  if (options.refine && std::isfinite(best)) best = refine_finalists(r, data, options, best);
  const SeparationCandidateReport& chosen = r.candidates[*r.best_candidate];
  const bool refined = options.refine && std::isfinite(chosen.start_rms);
  r.loop = refined ? chosen.refinement.loop : chosen.start;
  r.output_rms = chosen.refined_rms;
  if (refined) r.cramer_rao = chosen.refinement.quality;
  r.message += std::isfinite(best) ? "best candidate: " + chosen.source
                                   : "every candidate is unstable or overflowed";
  if (!std::isfinite(best)) {
    r.termination = Termination::no_solution;
  } else if (refined) {
    r.termination = chosen.refinement.termination;
    r.iterations = chosen.refinement.iterations;
  } else {
    r.termination = Termination::converged;  // the selection by step-1 output error is done
  }
  r.verdict = feedback_verdict(r, data);
  return r;
}

void DelayIdentificationOptions::check_relations(const std::string& path) const {
  const OutputErrorOptions& oe = identification.output_error;
  if (scan.hold != oe.hold)
    throw InvalidArgument(internal::concat(path, ".scan.hold is ", enum_name(scan.hold),
                                           "; it must equal identification.output_error.hold (",
                                           enum_name(oe.hold), ")"));
  require(scan.substeps == oe.substeps, path, ".scan.substeps is ", scan.substeps,
          "; it must equal identification.output_error.substeps (", oe.substeps, ")");
}

DelayIdentificationResult identify_delayed_feedback_with_delay_scan(
    const SampledData& data, int n, int m, const DelayIdentificationOptions& options,
    const std::function<void(int, int)>& progress) {
  options.validate();
  DelayIdentificationResult r;
  FeedbackDelayScanOptions scan = options.scan;
  scan.refine = false;
  r.scan = scan_feedback_delay(data, n, m, scan, progress);
  r.delay = r.scan.delay;
  // The outcome is the identification's at the returned Δ.
  const auto finish = [&r, &data]() -> DelayIdentificationResult& {
    r.identification.verdict = feedback_verdict(r.identification, data);
    static_cast<Outcome&>(r) = static_cast<const Outcome&>(r.identification);
    return r;
  };
  r.identification = identify_delayed_feedback(data, n, m, r.scan.delay, options.identification);
  if (!r.identification.best_candidate || !std::isfinite(r.identification.output_rms))
    return finish();
  if (options.joint_delay) {
    OutputErrorOptions joint = options.identification.output_error;
    joint.estimate_delay = true;
    ++r.evaluations;
    const OutputErrorResult fit = refine_output_error(data, r.identification.loop, joint);
    if (std::isfinite(fit.residual_rms) && fit.residual_rms <= r.identification.output_rms) {
      r.delay = fit.loop.delay;
      r.identification.loop = fit.loop;
      r.identification.output_rms = fit.residual_rms;
      r.identification.cramer_rao = fit.quality;
      r.identification.message += "; delay refined jointly with F and H";
      r.identification.termination = fit.termination;
    }
    return finish();
  }
  if (options.golden_iterations == 0) return finish();
  const double step = (scan.max_delay - scan.min_delay) / (scan.points - 1);
  DelayedFeedbackLoop warm = r.identification.loop;
  OutputErrorResult best_fit;
  double best_cost = r.identification.output_rms;
  double best_delay = r.scan.delay;
  auto cost = [&](double d) {
    ++r.evaluations;
    DelayedFeedbackLoop start = warm;
    start.delay = d;
    const OutputErrorResult fit =
        refine_output_error(data, start, options.identification.output_error);
    const double c = std::isfinite(fit.residual_rms) ? fit.residual_rms
                                                     : std::numeric_limits<double>::infinity();
    if (c < best_cost) {
      best_cost = c;
      best_delay = d;
      best_fit = fit;
      warm = fit.loop;
    }
    return c;
  };
  // The cost keeps the best fit it has seen; the search only drives it.
  golden_section_minimum(cost, std::max(scan.min_delay, r.scan.delay - step),
                         std::min(scan.max_delay, r.scan.delay + step), options.golden_iterations);
  if (best_delay != r.scan.delay) {
    r.delay = best_delay;
    r.identification.loop = best_fit.loop;
    r.identification.output_rms = best_cost;
    r.identification.cramer_rao = best_fit.quality;
    r.identification.message += "; delay refined by golden section";
    r.identification.termination = best_fit.termination;
  }
  return finish();
}

}  // namespace ctid
