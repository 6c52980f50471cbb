// Output-error refinement, Cramér-Rao bound and delay scan for the delayed-feedback loop.
#include "ctid/delayed_feedback/refinement.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/QR>
#include <Eigen/SVD>

#include "ctid/core/error.h"
#include "delayed_feedback/internal/ceres_solve.h"
#include "delayed_feedback/internal/loop_polynomials.h"

namespace ctid {
namespace {

Eigen::VectorXd padded(const Polynomial& p, int size) {
  Eigen::VectorXd v = Eigen::VectorXd::Zero(size);
  for (int i = 0; i <= p.degree() && i < size; ++i) v(i) = p.coefficient(i);
  return v;
}

TransferFunction monic_model(const Eigen::VectorXd& rho, int offset, int order) {
  Eigen::VectorXd den(order + 1);
  den << rho.segment(offset, order), 1.0;
  return TransferFunction(Polynomial::trimmed(rho.segment(offset + order, order)), Polynomial(den));
}

// ŷ for ρ; +inf entries when the simulation overflows.
Eigen::VectorXd simulate_rho(const Eigen::VectorXd& rho, int n, int m, double delay,
                             const Eigen::VectorXd& input, double delta, Hold hold, int substeps) {
  const DelayedFeedbackLoop loop = loop_from_parameters(rho, n, m, delay);
  return simulate_delayed(to_delayed_state_space(loop), input, delta, hold,
                          DelayedSimulationOptions{substeps});
}

struct OutputErrorFunctor {
  const SampledData* data;
  int n, m;
  double delay;
  Hold hold;
  int substeps;
  bool with_delay = false;  // parameters[0] ends with Δ
  bool operator()(double const* const* parameters, double* residual) const {
    const Eigen::Map<const Eigen::VectorXd> rho(parameters[0], 2 * (n + m));
    const double d = with_delay ? parameters[0][2 * (n + m)] : delay;
    if (!(d >= 0.0)) return false;
    const Eigen::VectorXd y =
        simulate_rho(rho, n, m, d, data->input(), data->sample_time(), hold, substeps);
    if (!y.allFinite() || y.cwiseAbs().maxCoeff() > 1e12) return false;
    Eigen::Map<Eigen::VectorXd>(residual, y.size()) = data->output() - y;
    return true;
  }
};

SeparabilityReport report_from_jacobian(const Eigen::MatrixXd& jac, const Eigen::VectorXd& rho,
                                        double variance, double threshold) {
  SeparabilityReport r;
  r.parameters = rho;
  r.noise_variance = variance;
  Eigen::VectorXd scale = jac.colwise().norm().transpose();
  for (Eigen::Index i = 0; i < scale.size(); ++i)
    if (scale(i) == 0.0) scale(i) = 1.0;
  const Eigen::MatrixXd js = jac * scale.cwiseInverse().asDiagonal();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(js, Eigen::ComputeThinV);
  const Eigen::VectorXd s = svd.singularValues();
  const double smin = s(s.size() - 1);
  r.condition_number = smin > 0.0 ? s(0) / smin : std::numeric_limits<double>::infinity();
  Eigen::VectorXd inv2(s.size());
  for (Eigen::Index i = 0; i < s.size(); ++i)
    inv2(i) = s(i) > 1e-14 * s(0) ? 1.0 / (s(i) * s(i)) : std::numeric_limits<double>::infinity();
  if (!inv2.allFinite()) {
    const double inf = std::numeric_limits<double>::infinity();
    r.covariance = Eigen::MatrixXd::Constant(rho.size(), rho.size(), inf);
  } else {
    const Eigen::MatrixXd cov_s = svd.matrixV() * inv2.asDiagonal() * svd.matrixV().transpose();
    r.covariance =
        variance * scale.cwiseInverse().asDiagonal() * cov_s * scale.cwiseInverse().asDiagonal();
  }
  r.standard_deviations = r.covariance.diagonal().cwiseSqrt();
  r.relative_standard_deviations.resize(rho.size());
  for (Eigen::Index i = 0; i < rho.size(); ++i)
    r.relative_standard_deviations(i) = r.standard_deviations(i) / std::max(std::abs(rho(i)), 1e-3);
  const double worst = r.relative_standard_deviations.maxCoeff();
  r.separable = std::isfinite(worst) && worst < threshold;
  r.message = r.separable
                  ? "F and H are separable from this experiment: the largest relative standard "
                    "deviation is " +
                        std::to_string(worst)
                  : "F and H are NOT reliably separable from this experiment: the largest "
                    "relative standard deviation is " +
                        std::to_string(worst) + " (threshold " + std::to_string(threshold) +
                        "); any estimate reflects the prior or the start";
  return r;
}

Eigen::MatrixXd sensitivity(const Eigen::VectorXd& rho, int n, int m, double delay,
                            const Eigen::VectorXd& input, double delta, Hold hold, int substeps) {
  Eigen::MatrixXd jac(input.size(), rho.size());
  for (Eigen::Index i = 0; i < rho.size(); ++i) {
    const double h = 1e-6 * std::max(1.0, std::abs(rho(i)));
    Eigen::VectorXd up = rho, down = rho;
    up(i) += h;
    down(i) -= h;
    jac.col(i) = (simulate_rho(up, n, m, delay, input, delta, hold, substeps) -
                  simulate_rho(down, n, m, delay, input, delta, hold, substeps)) /
                 (2 * h);
  }
  return jac;
}

std::string short_number(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", x);
  return buffer;
}

// Structured step 1 with the 1/(s + a)^q filter at `pole`, then the bias-corrected IV
// iterations from it; InvalidArgument when no stable start exists.
StructuredIvResult iv_start(const SampledData& data, int n, int m, double delay,
                            FeedbackRegressorOptions regressors, double pole,
                            const StructuredIvOptions& iv) {
  regressors.filter = RegressorFilter::kLinearIntegralFilter;
  regressors.filter_pole = pole;
  const FeedbackRegression reg = build_feedback_regression(data, n, m, delay, regressors);
  const StructuredStep1Result st = estimate_structured_step1(reg);
  require(std::isfinite(st.cost), "structured step 1 found no start");
  return estimate_structured_step1_iv(data, st.loop, regressors, iv);
}

// Golden-section search for a minimum of f on [lo, hi] with `iterations` reductions; returns
// the better of the two final interior points and its value.
template <class Function>
std::pair<double, double> golden_section_minimum(Function&& f, double lo, double hi,
                                                 int iterations) {
  const double ratio = (std::sqrt(5.0) - 1.0) / 2.0;
  double x1 = hi - ratio * (hi - lo), x2 = lo + ratio * (hi - lo);
  double f1 = f(x1), f2 = f(x2);
  for (int it = 0; it < iterations; ++it) {
    if (f1 < f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - ratio * (hi - lo);
      f1 = f(x1);
    } else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + ratio * (hi - lo);
      f2 = f(x2);
    }
  }
  return f1 < f2 ? std::make_pair(x1, f1) : std::make_pair(x2, f2);
}

}  // namespace

Eigen::VectorXd loop_parameters(const DelayedFeedbackLoop& loop) {
  const TransferFunction f = loop.forward.normalized();
  const TransferFunction h = loop.feedback.normalized();
  const int n = f.denominator().degree();
  const int m = h.denominator().degree();
  Eigen::VectorXd rho(2 * (n + m));
  rho << padded(f.denominator(), n), padded(f.numerator(), n), padded(h.denominator(), m),
      padded(h.numerator(), m);
  return rho;
}

DelayedFeedbackLoop loop_from_parameters(const Eigen::VectorXd& rho, int n, int m, double delay) {
  require(n >= 1 && m >= 1 && rho.size() == 2 * (n + m),
          "loop_from_parameters: need n, m >= 1 and 2(n + m) = ", 2 * (n + m), " parameters, got ",
          rho.size());
  return {monic_model(rho, 0, n), monic_model(rho, 2 * n, m), delay};
}

SeparabilityReport cramer_rao_bound(const DelayedFeedbackLoop& loop, const Eigen::VectorXd& input,
                                    double sample_time, Hold hold, double noise_sd,
                                    double relative_threshold, int substeps) {
  loop.validate();
  require(std::isfinite(noise_sd) && noise_sd > 0.0,
          "cramer_rao_bound: noise_sd must be positive, got ", noise_sd);
  require(relative_threshold > 0.0, "cramer_rao_bound: relative_threshold must be positive");
  const int n = loop.forward.denominator().degree();
  const int m = loop.feedback.denominator().degree();
  const Eigen::VectorXd rho = loop_parameters(loop);
  require(input.size() > rho.size(), "cramer_rao_bound: too few samples (", input.size(), ") for ",
          rho.size(), " parameters");
  const Eigen::MatrixXd jac =
      sensitivity(rho, n, m, loop.delay, input, sample_time, hold, substeps);
  return report_from_jacobian(jac, rho, noise_sd * noise_sd, relative_threshold);
}

void OutputErrorOptions::validate() const {
  require(substeps >= 1, "OutputErrorOptions: substeps must be >= 1, got ", substeps);
  require(max_iterations >= 1, "OutputErrorOptions: max_iterations must be >= 1, got ",
          max_iterations);
  require(relative_threshold > 0.0, "OutputErrorOptions: relative_threshold must be > 0, got ",
          relative_threshold);
}

OutputErrorResult refine_output_error(const SampledData& data, const DelayedFeedbackLoop& start,
                                      const OutputErrorOptions& options) {
  options.validate();
  start.validate();
  const int n = start.forward.denominator().degree();
  const int m = start.feedback.denominator().degree();
  Eigen::VectorXd rho = loop_parameters(start);
  require(data.size() > rho.size(), "refine_output_error: too few samples (", data.size(), ") for ",
          rho.size(), " parameters");
  require((data.size() - 1) * data.sample_time() > start.delay,
          "refine_output_error: the record must be longer than the delay");
  OutputErrorResult result;
  const int np = static_cast<int>(rho.size());
  Eigen::VectorXd params(np + (options.estimate_delay ? 1 : 0));
  params.head(np) = rho;
  if (options.estimate_delay) params(np) = start.delay;
  ceres::Problem problem;
  // Forward differences: half the simulations of central ones; the minimiser is unaffected
  // (the covariance below still uses central differences).
  auto* cost = new ceres::DynamicNumericDiffCostFunction<OutputErrorFunctor, ceres::FORWARD>(
      new OutputErrorFunctor{&data, n, m, start.delay, options.hold, options.substeps,
                             options.estimate_delay});
  cost->AddParameterBlock(static_cast<int>(params.size()));
  cost->SetNumResiduals(data.size());
  problem.AddResidualBlock(cost, nullptr, params.data());
  if (options.estimate_delay) problem.SetParameterLowerBound(params.data(), np, 0.0);
  internal::LeastSquaresSettings settings;
  settings.max_iterations = options.max_iterations;
  // The cost has long curved valleys (F and H trade at low frequency); non-monotonic steps
  // cross them in far fewer iterations (measured: 200 -> ~60 at noise sd 1e-3).
  settings.nonmonotonic_steps = true;
  settings.function_tolerance = 1e-12;
  settings.parameter_tolerance = 1e-12;
  const internal::LeastSquaresOutcome outcome = internal::solve_least_squares(problem, settings);
  result.iterations = outcome.iterations;
  result.converged = outcome.converged;
  result.message = outcome.message;
  rho = params.head(np);
  const double delay = options.estimate_delay ? params(np) : start.delay;
  result.loop = loop_from_parameters(rho, n, m, delay);
  const Eigen::VectorXd y = simulate_rho(rho, n, m, delay, data.input(), data.sample_time(),
                                         options.hold, options.substeps);
  const Eigen::VectorXd e = data.output() - y;
  result.residual_rms = std::sqrt(e.squaredNorm() / static_cast<double>(e.size()));
  const double variance =
      e.squaredNorm() / static_cast<double>(std::max<Eigen::Index>(1, e.size() - rho.size()));
  if (y.allFinite()) {
    const Eigen::MatrixXd jac = sensitivity(rho, n, m, delay, data.input(), data.sample_time(),
                                            options.hold, options.substeps);
    result.quality = report_from_jacobian(jac, rho, variance, options.relative_threshold);
  }
  return result;
}

void FeedbackDelayScanOptions::validate() const {
  require(std::isfinite(min_delay) && min_delay >= 0.0,
          "FeedbackDelayScanOptions: min_delay must be >= 0, got ", min_delay);
  require(std::isfinite(max_delay) && max_delay > min_delay,
          "FeedbackDelayScanOptions: max_delay must exceed min_delay, got ", max_delay);
  require(points >= 2, "FeedbackDelayScanOptions: points must be >= 2, got ", points);
  require(substeps >= 1, "FeedbackDelayScanOptions: substeps must be >= 1, got ", substeps);
  require(refined_iterations >= 1,
          "FeedbackDelayScanOptions: refined_iterations must be >= 1, got ", refined_iterations);
  regressors.validate();
  least_squares.validate();
  iv.validate();
  for (double pole : iv_filter_poles)
    require(std::isfinite(pole) && pole > 0.0,
            "FeedbackDelayScanOptions: iv_filter_poles must be positive, got ", pole);
}

FeedbackDelayScanResult scan_feedback_delay(const SampledData& data, int n, int m,
                                            const FeedbackDelayScanOptions& options) {
  options.validate();
  require(n >= 1 && m >= 1, "scan_feedback_delay: orders must be >= 1, got n = ", n, ", m = ", m);
  auto criterion = [&](double delay) {
    try {
      const FeedbackRegression reg =
          build_feedback_regression(data, n, m, delay, options.regressors);
      if (options.criterion == DelayCriterion::kStructuredOutputError ||
          options.criterion == DelayCriterion::kRefinedOutputError) {
        const StructuredStep1Result st = estimate_structured_step1(reg);
        double rms = loop_output_rms(data, st.loop, options.hold, options.substeps);
        if (options.criterion == DelayCriterion::kRefinedOutputError) {
          OutputErrorOptions oe;
          oe.hold = options.hold;
          oe.substeps = options.substeps;
          oe.max_iterations = options.refined_iterations;
          std::vector<DelayedFeedbackLoop> starts;
          if (std::isfinite(rms)) starts.push_back(st.loop);
          StructuredIvOptions iv = options.iv;
          iv.hold = options.hold;
          iv.substeps = options.substeps;
          for (double pole : options.iv_filter_poles) {
            try {
              const StructuredIvResult r =
                  iv_start(data, n, m, delay, options.regressors, pole, iv);
              if (std::isfinite(r.output_rms)) starts.push_back(r.loop);
              rms = std::min(rms, r.output_rms);
            } catch (const InvalidArgument&) {
              // No start at this pole.
            }
          }
          for (const DelayedFeedbackLoop& start : starts) {
            const OutputErrorResult fit = refine_output_error(data, start, oe);
            if (std::isfinite(fit.residual_rms)) rms = std::min(rms, fit.residual_rms);
          }
        }
        return rms * rms;
      }
      const ClosedLoopEstimate est = estimate_closed_loop_batch(reg, options.least_squares);
      if (options.criterion == DelayCriterion::kEquationError)
        return est.residual_rms * est.residual_rms;
      const Eigen::VectorXd y = simulate_delayed(
          to_delayed_state_space(est.alpha, est.beta, est.gamma, delay), data.input(),
          data.sample_time(), options.hold, DelayedSimulationOptions{options.substeps});
      if (!y.allFinite()) return std::numeric_limits<double>::infinity();
      const double mse = (data.output() - y).squaredNorm() / static_cast<double>(y.size());
      return std::isfinite(mse) ? mse : std::numeric_limits<double>::infinity();
    } catch (const InvalidArgument&) {
      return std::numeric_limits<double>::infinity();
    }
  };
  FeedbackDelayScanResult r;
  r.delays = Eigen::VectorXd::LinSpaced(options.points, options.min_delay, options.max_delay);
  r.criterion.resize(options.points);
  Eigen::Index best = 0;
  for (int i = 0; i < options.points; ++i) {
    r.criterion(i) = criterion(r.delays(i));
    if (r.criterion(i) < r.criterion(best)) best = i;
  }
  r.delay = r.delays(best);
  r.best_criterion = r.criterion(best);
  if (options.refine && std::isfinite(r.best_criterion)) {
    const double lo = r.delays(std::max<Eigen::Index>(0, best - 1));
    const double hi = r.delays(std::min<Eigen::Index>(options.points - 1, best + 1));
    const auto [x, f] = golden_section_minimum(criterion, lo, hi, 25);
    if (f < r.best_criterion) {
      r.delay = x;
      r.best_criterion = f;
    }
  }
  return r;
}

double loop_output_rms(const SampledData& data, const DelayedFeedbackLoop& loop, Hold hold,
                       int substeps) {
  const double inf = std::numeric_limits<double>::infinity();
  try {
    const Eigen::VectorXd y =
        simulate_delayed(to_delayed_state_space(loop), data.input(), data.sample_time(), hold,
                         DelayedSimulationOptions{substeps});
    if (!y.allFinite() || y.cwiseAbs().maxCoeff() > 1e12) return inf;
    const double rms = std::sqrt((data.output() - y).squaredNorm() / static_cast<double>(y.size()));
    return std::isfinite(rms) ? rms : inf;
  } catch (const InvalidArgument&) {
    return inf;
  }
}

void FeedbackIdentificationOptions::validate() const {
  regressors.validate();
  batch.validate();
  recursive.validate();
  kronecker.validate();
  output_error.validate();
  structured.validate();
  iv.validate();
  for (double pole : iv_filter_poles)
    require(std::isfinite(pole) && pole > 0.0,
            "FeedbackIdentificationOptions: iv_filter_poles must be positive, got ", pole);
  for (double fraction : continuation_fractions)
    require(std::isfinite(fraction) && fraction > 0.0 && fraction < 1.0,
            "FeedbackIdentificationOptions: continuation_fractions must lie in (0, 1), got ",
            fraction);
  require(screening_iterations >= 1,
          "FeedbackIdentificationOptions: screening_iterations must be >= 1, got ",
          screening_iterations);
  require(extra_finalists >= 0, "FeedbackIdentificationOptions: extra_finalists must be >= 0, got ",
          extra_finalists);
  require(std::isfinite(finalist_ratio) && finalist_ratio >= 1.0,
          "FeedbackIdentificationOptions: finalist_ratio must be >= 1, got ", finalist_ratio);
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
  bool have_step1 = true;
  try {
    r.step1 = options.step1 == Step1Method::kBatch
                  ? estimate_closed_loop_batch(reg, options.batch)
                  : estimate_closed_loop_recursive(reg, options.recursive);
  } catch (const InvalidArgument& e) {
    // A singular unstructured regression: only the structured candidate remains.
    have_step1 = false;
    r.message = std::string("step 1: ") + e.what() + "; ";
  }
  const Hold hold = options.output_error.hold;
  const int substeps = options.output_error.substeps;
  r.step1_output_rms = inf;
  if (have_step1) {
    try {
      const Eigen::VectorXd y = simulate_delayed(
          to_delayed_state_space(r.step1.alpha, r.step1.beta, r.step1.gamma, delay), data.input(),
          data.sample_time(), hold, DelayedSimulationOptions{substeps});
      r.step1_output_rms =
          y.allFinite() && y.cwiseAbs().maxCoeff() < 1e12
              ? std::sqrt((data.output() - y).squaredNorm() / static_cast<double>(y.size()))
              : inf;
    } catch (const InvalidArgument&) {
      r.step1_output_rms = inf;
    }
  }
  const Polynomial& a = r.step1.alpha;
  const Polynomial& b = r.step1.beta;
  const Polynomial& g = r.step1.gamma;
  auto add = [&](std::string source, const TransferFunction& f, const TransferFunction& h) {
    if (f.denominator().degree() != n || h.denominator().degree() != m) return;
    SeparationCandidateReport c;
    c.source = std::move(source);
    c.start = DelayedFeedbackLoop{f.normalized(), h.normalized(), delay};
    try {
      c.start.validate();
    } catch (const InvalidArgument&) {
      return;
    }
    c.kronecker_cost =
        have_step1 ? kronecker_cost(a, b, g, c.start.forward, c.start.feedback) : inf;
    c.start_rms = loop_output_rms(data, c.start, hold, substeps);
    c.refined_rms = c.start_rms;
    r.candidates.push_back(std::move(c));
  };
  if (have_step1 && options.separation != SeparationMethod::kKronecker) {
    try {
      const GcdSeparationResult gcd = separate_approximate_gcd(a, b, g, n, m);
      add("gcd", gcd.forward, gcd.feedback);
    } catch (const InvalidArgument&) {
      // α̂ of low degree: no GCD candidate.
    }
  }
  if (have_step1 && options.separation != SeparationMethod::kGcd) {
    try {
      const KroneckerSeparationResult kr = separate_kronecker(a, b, g, n, m, options.kronecker);
      for (const KroneckerCandidate& c : kr.candidates)
        add("kronecker: " + c.start, c.forward, c.feedback);
    } catch (const InvalidArgument&) {
      // No usable start.
    }
  }
  if (options.structured_candidate) {
    try {
      const StructuredStep1Result st = estimate_structured_step1(reg, options.structured);
      add("structured step 1", st.loop.forward, st.loop.feedback);
    } catch (const InvalidArgument&) {
      // Degenerate structured fit: no candidate.
    }
  }
  {
    StructuredIvOptions iv = options.iv;
    iv.hold = hold;
    iv.substeps = substeps;
    for (double pole : options.iv_filter_poles) {
      try {
        const StructuredIvResult st = iv_start(data, n, m, delay, options.regressors, pole, iv);
        if (std::isfinite(st.output_rms))
          add("structured iv a = " + short_number(pole), st.loop.forward, st.loop.feedback);
      } catch (const InvalidArgument&) {
        // No stable start at this pole.
      }
    }
  }
  if (r.candidates.empty()) {
    r.message += "no separation candidate with the requested orders";
    r.output_rms = inf;
    return r;
  }
  // Every candidate gets a short output-error refinement; the best then runs to convergence.
  double best = inf;
  OutputErrorOptions screen = options.output_error;
  screen.max_iterations = std::min(options.screening_iterations, screen.max_iterations);
  for (std::size_t i = 0; i < r.candidates.size(); ++i) {
    SeparationCandidateReport& c = r.candidates[i];
    if (options.refine && std::isfinite(c.start_rms)) {
      // Continuation over the record length: the first part is dominated by the transient,
      // whose cost has fewer local minima; each stage starts where the shorter one ended.
      DelayedFeedbackLoop current = c.start;
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
      c.refinement = refine_output_error(data, current, screen);
      c.refined_rms = std::isfinite(c.refinement.residual_rms) ? c.refinement.residual_rms : inf;
    }
    if (c.refined_rms < best || r.best_candidate < 0) {
      best = c.refined_rms;
      r.best_candidate = static_cast<int>(i);
    }
  }
  if (options.refine && std::isfinite(best)) {
    // The finalists: the best screened candidate and up to extra_finalists runner-ups within
    // finalist_ratio of it, each continued to convergence; the smallest final cost wins.
    std::vector<std::size_t> finalists{static_cast<std::size_t>(r.best_candidate)};
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
      if (!c.refinement.converged &&
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
      if (r.candidates[i].refined_rms <
          r.candidates[static_cast<std::size_t>(r.best_candidate)].refined_rms)
        r.best_candidate = static_cast<int>(i);
    best = r.candidates[static_cast<std::size_t>(r.best_candidate)].refined_rms;
  }
  const SeparationCandidateReport& chosen =
      r.candidates[static_cast<std::size_t>(r.best_candidate)];
  const bool refined = options.refine && std::isfinite(chosen.start_rms);
  r.loop = refined ? chosen.refinement.loop : chosen.start;
  r.output_rms = chosen.refined_rms;
  if (refined) r.cramer_rao = chosen.refinement.quality;
  r.message += std::isfinite(best) ? "best candidate: " + chosen.source
                                   : "every candidate is unstable or overflowed";
  return r;
}

void DelayIdentificationOptions::validate() const {
  scan.validate();
  identification.validate();
  require(golden_iterations >= 0,
          "DelayIdentificationOptions: golden_iterations must be >= 0, got ", golden_iterations);
}

DelayIdentificationResult identify_delayed_feedback_with_delay_scan(
    const SampledData& data, int n, int m, const DelayIdentificationOptions& options) {
  options.validate();
  DelayIdentificationResult r;
  FeedbackDelayScanOptions scan = options.scan;
  scan.refine = false;
  r.scan = scan_feedback_delay(data, n, m, scan);
  r.identification = identify_delayed_feedback(data, n, m, r.scan.delay, options.identification);
  r.delay = r.scan.delay;
  if (r.identification.best_candidate < 0 || !std::isfinite(r.identification.output_rms)) return r;
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
    }
    return r;
  }
  if (options.golden_iterations == 0) return r;
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
  }
  return r;
}

}  // namespace ctid

namespace ctid {
namespace {

// θ(ρ) in the paper's order [β_{q-1..0} | γ_{q-2..0} | α_{q-1..0}].
struct ThetaOfRho {
  int n, m;
  template <typename T>
  void operator()(const T* p, T* theta) const {
    const int q = n + m;
    const internal::LoopPolynomials<T> poly = internal::loop_polynomials(p, n, m);
    const std::vector<T>& a = poly.alpha;
    const std::vector<T>& b = poly.beta;
    const std::vector<T>& g = poly.gamma;
    for (int i = 0; i < q; ++i) theta[i] = b[q - 1 - i];
    for (int i = 0; i + 1 < q; ++i) theta[q + i] = g[q - 2 - i];
    for (int i = 0; i < q; ++i) theta[2 * q - 1 + i] = a[q - 1 - i];
  }
};

struct StructuredResidual {
  const Eigen::MatrixXd* c;
  const Eigen::VectorXd* y;
  int n, m;
  template <typename T>
  bool operator()(T const* const* parameters, T* residual) const {
    const int p = 3 * (n + m) - 1;
    std::vector<T> theta(static_cast<size_t>(p));
    ThetaOfRho{n, m}(parameters[0], theta.data());
    for (Eigen::Index k = 0; k < c->rows(); ++k) {
      T sum = T((*y)(k));
      for (int j = 0; j < p; ++j) sum -= (*c)(k, j) * theta[static_cast<size_t>(j)];
      residual[k] = sum;
    }
    return true;
  }
};

Eigen::VectorXd theta_of(const Eigen::VectorXd& rho, int n, int m) {
  Eigen::VectorXd theta(3 * (n + m) - 1);
  ThetaOfRho{n, m}(rho.data(), theta.data());
  return theta;
}

// One alternating step: least squares in the block [offset, offset + size) of ρ, the rest fixed.
void solve_block(Eigen::VectorXd& rho, int offset, int size, int n, int m, const Eigen::MatrixXd& c,
                 const Eigen::VectorXd& y) {
  Eigen::VectorXd base = rho;
  base.segment(offset, size).setZero();
  const Eigen::VectorXd theta0 = theta_of(base, n, m);
  Eigen::MatrixXd map(theta0.size(), size);
  for (int i = 0; i < size; ++i) {
    Eigen::VectorXd unit = base;
    unit(offset + i) = 1.0;
    map.col(i) = theta_of(unit, n, m) - theta0;
  }
  const Eigen::MatrixXd a = c * map;
  const Eigen::VectorXd x = a.colPivHouseholderQr().solve(y - c * theta0);
  if (x.allFinite()) rho.segment(offset, size) = x;
}

// The θ block and target with the nuisance columns projected out; `nuisance` is the
// orthonormal basis used, so instruments can be projected the same way.
struct ProjectedSystem {
  Eigen::MatrixXd c;
  Eigen::VectorXd y;
  Eigen::MatrixXd nuisance;
};

ProjectedSystem project_nuisance(const FeedbackRegression& reg) {
  ProjectedSystem s;
  s.c = reg.regressor.leftCols(reg.theta_size);
  s.y = reg.target;
  s.nuisance.resize(reg.regressor.rows(), 0);
  if (reg.nuisance_size > 0) {
    Eigen::MatrixXd nuis = reg.regressor.rightCols(reg.nuisance_size);
    for (Eigen::Index j = 0; j < nuis.cols(); ++j)
      if (nuis.col(j).norm() > 0.0) nuis.col(j) /= nuis.col(j).norm();
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(nuis);
    s.nuisance = qr.householderQ() * Eigen::MatrixXd::Identity(nuis.rows(), nuis.cols());
    s.c -= s.nuisance * (s.nuisance.transpose() * s.c);
    s.y -= s.nuisance * (s.nuisance.transpose() * s.y);
  }
  return s;
}

// Levenberg-Marquardt on |y - c θ(ρ)|² from rho (updated in place); returns the cost.
double structured_least_squares(const Eigen::MatrixXd& c, const Eigen::VectorXd& y, int n, int m,
                                int max_iterations, Eigen::VectorXd& rho) {
  ceres::Problem problem;
  auto* cost = new ceres::DynamicAutoDiffCostFunction<StructuredResidual, 8>(
      new StructuredResidual{&c, &y, n, m});
  cost->AddParameterBlock(2 * (n + m));
  cost->SetNumResiduals(static_cast<int>(y.size()));
  problem.AddResidualBlock(cost, nullptr, rho.data());
  internal::LeastSquaresSettings settings;
  settings.max_iterations = max_iterations;
  settings.function_tolerance = 1e-14;
  settings.parameter_tolerance = 1e-14;
  return internal::solve_least_squares(problem, settings).sum_of_squares;
}

}  // namespace

void StructuredStep1Options::validate() const {
  require(!start_frequencies.empty(), "StructuredStep1Options: start_frequencies is empty");
  for (double w : start_frequencies)
    require(std::isfinite(w) && w > 0.0,
            "StructuredStep1Options: start_frequencies must be positive, got ", w);
  require(alternating_iterations >= 0 && max_iterations >= 1,
          "StructuredStep1Options: iteration counts must be >= 0 (alternating) and >= 1");
}

StructuredStep1Result estimate_structured_step1(const FeedbackRegression& reg,
                                                const StructuredStep1Options& options) {
  options.validate();
  const int n = reg.forward_order;
  const int m = reg.feedback_order;
  const ProjectedSystem sys = project_nuisance(reg);
  StructuredStep1Result best;
  best.cost = std::numeric_limits<double>::infinity();
  for (double w : options.start_frequencies) {
    Eigen::VectorXd rho = Eigen::VectorXd::Zero(2 * (n + m));
    // D_H = (s + w)^m, N_H = 0: the first F-step fits F as if there were no feedback.
    Eigen::VectorXd dh = Eigen::VectorXd::Zero(m + 1);
    for (int i = 0; i <= m; ++i)
      dh(i) = std::tgamma(m + 1.0) / (std::tgamma(i + 1.0) * std::tgamma(m - i + 1.0)) *
              std::pow(w, m - i);
    rho.segment(2 * n, m) = dh.head(m);
    for (int it = 0; it < options.alternating_iterations; ++it) {
      solve_block(rho, 0, 2 * n, n, m, sys.c, sys.y);
      solve_block(rho, 2 * n, 2 * m, n, m, sys.c, sys.y);
    }
    const double j = structured_least_squares(sys.c, sys.y, n, m, options.max_iterations, rho);
    ++best.starts;
    if (rho.allFinite() && j < best.cost) {
      best.cost = j;
      best.loop = loop_from_parameters(rho, n, m, reg.delay);
    }
  }
  return best;
}

void StructuredIvOptions::validate() const {
  require(iterations >= 1, "StructuredIvOptions: iterations must be >= 1, got ", iterations);
  require(max_iterations >= 1, "StructuredIvOptions: max_iterations must be >= 1, got ",
          max_iterations);
  require(substeps >= 1, "StructuredIvOptions: substeps must be >= 1, got ", substeps);
}

StructuredIvResult estimate_structured_step1_iv(const SampledData& data,
                                                const DelayedFeedbackLoop& start,
                                                const FeedbackRegressorOptions& regressors,
                                                const StructuredIvOptions& options) {
  options.validate();
  start.validate();
  const int n = start.forward.denominator().degree();
  const int m = start.feedback.denominator().degree();
  const double delay = start.delay;
  const FeedbackRegression reg = build_feedback_regression(data, n, m, delay, regressors);
  const ProjectedSystem sys = project_nuisance(reg);
  StructuredIvResult r;
  r.loop = DelayedFeedbackLoop{start.forward.normalized(), start.feedback.normalized(), delay};
  r.output_rms = loop_output_rms(data, r.loop, options.hold, options.substeps);
  r.output_rms_history.push_back(r.output_rms);
  if (!std::isfinite(r.output_rms)) {
    r.message = "the start is unstable or overflows";
    return r;
  }
  Eigen::VectorXd rho = loop_parameters(r.loop);
  DelayedFeedbackLoop current = r.loop;
  for (int it = 0; it < options.iterations; ++it) {
    // Instruments: the regressors rebuilt from the current model's noise-free output.
    const Eigen::VectorXd y_model =
        simulate_delayed(to_delayed_state_space(current), data.input(), data.sample_time(),
                         options.hold, DelayedSimulationOptions{options.substeps});
    if (!y_model.allFinite() || y_model.cwiseAbs().maxCoeff() > 1e12) break;
    const FeedbackRegression zreg = build_feedback_regression(
        SampledData(data.sample_time(), data.input(), y_model), n, m, delay, regressors);
    Eigen::MatrixXd z = zreg.regressor.leftCols(zreg.theta_size);
    if (sys.nuisance.cols() > 0) z -= sys.nuisance * (sys.nuisance.transpose() * z);
    for (Eigen::Index j = 0; j < z.cols(); ++j)
      if (z.col(j).norm() > 0.0) z.col(j) /= z.col(j).norm();
    // Two-stage least squares: the residual projected on the span of the instruments.
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(z);
    const Eigen::MatrixXd qz = qr.householderQ() * Eigen::MatrixXd::Identity(z.rows(), z.cols());
    const Eigen::MatrixXd c = qz.transpose() * sys.c;
    const Eigen::VectorXd y = qz.transpose() * sys.y;
    Eigen::VectorXd next = rho;
    structured_least_squares(c, y, n, m, options.max_iterations, next);
    if (options.bias_correction) {
      // The same estimator applied to the model's own output: its departure from ρ is the
      // systematic error of the regression (interpolation, filter transients), removed here.
      const ProjectedSystem model_sys = project_nuisance(zreg);
      const Eigen::MatrixXd cm = qz.transpose() * model_sys.c;
      const Eigen::VectorXd ym = qz.transpose() * model_sys.y;
      Eigen::VectorXd self = rho;
      structured_least_squares(cm, ym, n, m, options.max_iterations, self);
      next += rho - self;
    }
    ++r.iterations;
    if (!next.allFinite()) break;
    const DelayedFeedbackLoop candidate = loop_from_parameters(next, n, m, delay);
    const double rms = loop_output_rms(data, candidate, options.hold, options.substeps);
    r.output_rms_history.push_back(rms);
    if (!std::isfinite(rms)) break;
    const double change = (next - rho).norm() / std::max(1.0, rho.norm());
    rho = next;
    current = candidate;
    if (rms < r.output_rms) {
      r.output_rms = rms;
      r.loop = candidate;
    }
    if (change < options.tolerance) {
      r.converged = true;
      break;
    }
  }
  r.message = r.converged ? "instrumental-variable iterations converged"
                          : "instrumental-variable iterations stopped at the limit";
  return r;
}

}  // namespace ctid
