// CLSRIVC with a stabilised prefilter for plants that may be unstable (decision 0038).
#include "ctid/refined_iv/unstable_clsrivc.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <optional>
#include <string>
#include <utility>

#include <Eigen/Dense>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/estimation/validation.h"
#include "ctid/estimation/verdict.h"
#include "ctid/filtering/filter_bank.h"
#include "ctid/refined_iv/initialization.h"
#include "ctid/refined_iv/srivc.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/simulate.h"
#include "refined_iv/internal/refined_iv_engine.h"
#include "refined_iv/internal/unstable_loop.h"

namespace ctid {
namespace {

// Starts iterated from, at most (the best by their closed-loop fit from r).
constexpr int kUnstableStarts = 3;

// A with its right-half-plane roots reflected, kept anti-monic: the engine's reflection,
// applied here to the prefilter only.
Polynomial unstable_loop_prefilter(const Polynomial& a) {
  bool reflected = false;
  return internal::reflect_unstable_roots(a, reflected);
}

// What the closed-loop recursion of the model gives from r: the controller output u_r, the
// model output x and p^k/A_f x, k = 0..n (columns).
struct UnstableLoopPass {
  Eigen::VectorXd input;
  Eigen::VectorXd output;
  Eigen::MatrixXd filtered_output;
};

// The ZOH model B/(p^l A) with the bank 1/A_f cascaded after it, in closed loop with the
// controller, driven by r; std::nullopt when the loop is ill-posed or not stable.
std::optional<UnstableLoopPass> unstable_loop_pass(const Polynomial& a, const Eigen::VectorXd& b,
                                                   int integrators, const Polynomial& af,
                                                   const DiscreteTransferFunction& controller,
                                                   const Eigen::VectorXd& r, double h) {
  // A degenerate model (A lost its leading coefficient) has no finite realisation.
  const std::optional<FilterRealization> first_bank =
      finite_derivative_filters(Polynomial::monomial(integrators) * a);
  const std::optional<FilterRealization> second_bank = finite_derivative_filters(af);
  if (!first_bank || !second_bank) return std::nullopt;
  const FilterRealization& first = *first_bank;
  const FilterRealization& second = *second_bank;
  Eigen::VectorXd w = Eigen::VectorXd::Zero(first.outputs());
  w.head(b.size()) = b;
  const int s1 = first.order();
  const int s2 = second.order();
  const int n2 = second.outputs();
  const Eigen::RowVectorXd cy = w.transpose() * first.c;
  const double dy = w.dot(first.d);
  Eigen::MatrixXd am = Eigen::MatrixXd::Zero(s1 + s2, s1 + s2);
  am.topLeftCorner(s1, s1) = first.a;
  am.bottomLeftCorner(s2, s1) = second.b * cy;
  am.bottomRightCorner(s2, s2) = second.a;
  Eigen::MatrixXd bm(s1 + s2, 1);
  bm.topRows(s1) = first.b;
  bm.bottomRows(s2) = second.b * dy;
  Eigen::MatrixXd cf = Eigen::MatrixXd::Zero(n2, s1 + s2);
  cf.leftCols(s1) = second.d * cy;
  cf.rightCols(s2) = second.c;
  const Eigen::VectorXd df = second.d * dy;
  if (!am.allFinite() || !bm.allFinite()) return std::nullopt;  // b not finite, or overflow
  const ZohDiscretization z = discretize_zoh(am, bm, h);
  const StateSpace c = controller.to_state_space();
  const int ng = s1 + s2;
  const int nc = c.order();
  const int n = ng + nc;
  const double loop = 1.0 + c.d * dy;
  if (!(std::abs(loop) > 1e-12)) return std::nullopt;
  // X = [x_g; x_c]; y_k = yx X + yr r_k, u_k = ku X + kr r_k.
  Eigen::RowVectorXd cg = Eigen::RowVectorXd::Zero(n);
  cg.head(s1) = cy;
  Eigen::RowVectorXd cc = Eigen::RowVectorXd::Zero(n);
  cc.tail(nc) = c.c;
  const Eigen::RowVectorXd ku = (cc - c.d * cg) / loop;
  const double kr = c.d / loop;
  const Eigen::RowVectorXd yx = cg + dy * ku;
  const double yr = dy * kr;
  Eigen::MatrixXd acl = Eigen::MatrixXd::Zero(n, n);
  acl.topLeftCorner(ng, ng) = z.phi;
  acl.topRows(ng) += z.gamma * ku;
  Eigen::VectorXd bcl = Eigen::VectorXd::Zero(n);
  bcl.head(ng) = z.gamma.col(0) * kr;
  acl.bottomRows(nc) += -c.b * yx;
  acl.bottomRightCorner(nc, nc) += c.a;
  bcl.tail(nc) += c.b * (1.0 - yr);
  if (!acl.allFinite()) return std::nullopt;
  if (acl.eigenvalues().cwiseAbs().maxCoeff() >= 1.0 - 1e-9) return std::nullopt;
  const Eigen::Index samples = r.size();
  UnstableLoopPass pass;
  pass.input.resize(samples);
  pass.output.resize(samples);
  pass.filtered_output.resize(samples, n2);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd next(n);
  for (Eigen::Index k = 0; k < samples; ++k) {
    const double u = ku.dot(x) + kr * r(k);
    pass.input(k) = u;
    pass.output(k) = yx.dot(x) + yr * r(k);
    pass.filtered_output.row(k) = (cf * x.head(ng) + df * u).transpose();
    next.noalias() = acl * x;
    next += bcl * r(k);
    x.swap(next);
  }
  if (!pass.filtered_output.allFinite() || !pass.input.allFinite()) return std::nullopt;
  return pass;
}

struct UnstableLoopStep {
  Eigen::VectorXd theta;
  double reciprocal_condition = 0.0;
};

// One step of the iteration at theta = [a_1..a_n, b_0..b_m] from its closed-loop pass.
std::optional<UnstableLoopStep> unstable_loop_step(const SampledData& data, const SubmodelOrder& o,
                                                   const UnstableLoopPass& pass,
                                                   const Polynomial& af, bool stale) {
  const double h = data.sample_time();
  const Eigen::Index samples = data.size();
  const int p = o.n + o.m + 1;
  const FilterRealization input_bank = derivative_filters(Polynomial::monomial(o.integrators) * af);
  const SampledFilter input_filter(input_bank, h, Hold::zero_order_hold);
  const Eigen::MatrixXd fu = input_filter.apply(data.input());
  const Eigen::MatrixXd fur = input_filter.apply(pass.input);
  const SampledFilter output_filter(derivative_filters(af), h, Hold::first_order_hold);
  // A stale pass (an earlier iterate's, the current one's loop being unstable) gives u_r and a
  // noise-free x still, but not p^k/A_f x for this A_f: x is filtered like y then.
  const Eigen::MatrixXd fx =
      stale ? output_filter.apply(pass.output) : Eigen::MatrixXd(pass.filtered_output);
  const Eigen::MatrixXd fy =
      stale ? output_filter.apply(data.output())
            : Eigen::MatrixXd(fx + output_filter.apply(data.output() - pass.output));
  Eigen::MatrixXd z(samples, p);
  Eigen::MatrixXd phi(samples, p);
  z.leftCols(o.n) = -fx.middleCols(1, o.n);
  phi.leftCols(o.n) = -fy.middleCols(1, o.n);
  z.rightCols(o.m + 1) = fur.leftCols(o.m + 1);
  phi.rightCols(o.m + 1) = fu.leftCols(o.m + 1);
  const Eigen::VectorXd upsilon = fy.col(0);
  const Eigen::VectorXd sz = z.colwise().norm().transpose();
  const Eigen::VectorXd sp = phi.colwise().norm().transpose();
  if (!sz.allFinite() || !sp.allFinite() || !(sz.minCoeff() > 0.0) || !(sp.minCoeff() > 0.0)) {
    return std::nullopt;
  }
  const Eigen::MatrixXd m =
      sz.cwiseInverse().asDiagonal() * (z.transpose() * phi) * sp.cwiseInverse().asDiagonal();
  const Eigen::VectorXd rhs = sz.cwiseInverse().asDiagonal() * (z.transpose() * upsilon);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(m);
  const Eigen::VectorXd& sv = svd.singularValues();
  UnstableLoopStep step;
  step.reciprocal_condition = sv(sv.size() - 1) / sv(0);
  if (!(step.reciprocal_condition > 1e-14)) return std::nullopt;
  step.theta = sp.cwiseInverse().asDiagonal() * Eigen::VectorXd(m.fullPivLu().solve(rhs));
  if (!step.theta.allFinite()) return std::nullopt;
  return step;
}

Polynomial unstable_loop_denominator(const SubmodelOrder& o, const Eigen::VectorXd& theta) {
  Eigen::VectorXd a(o.n + 1);
  a(0) = 1.0;
  a.tail(o.n) = theta.head(o.n);
  return Polynomial(a);
}

std::optional<UnstableLoopPass> unstable_loop_pass_at(const SubmodelOrder& o,
                                                      const Eigen::VectorXd& theta,
                                                      const DiscreteTransferFunction& controller,
                                                      const SampledData& data) {
  const Polynomial a = unstable_loop_denominator(o, theta);
  bool reflected = false;
  // A degenerate model (A lost its leading coefficient) has no prefilter.
  const std::optional<Polynomial> af = internal::reflect_unstable_roots_if_finite(a, reflected);
  if (!af) return std::nullopt;
  return unstable_loop_pass(a, theta.tail(o.m + 1), o.integrators, *af, controller,
                            data.reference(), data.sample_time());
}

double unstable_loop_fit(const SampledData& data, const UnstableLoopPass& pass) {
  return fit_percent(data.output(), pass.output);
}

EstimationResult unstable_clsrivc_from(const SampledData& data,
                                       const DiscreteTransferFunction& controller,
                                       const SubmodelOrder& o, const RefinedIvOptions& options,
                                       const AdditiveModel& start) {
  const std::string name = "unstable_clsrivc";
  require(start.size() == 1 && start[0].n() == o.n && start[0].integrators == o.integrators &&
              start[0].m() <= o.m,
          name, ": the initial model is not one submodel with n = ", o.n,
          ", integrators = ", o.integrators, " and m <= ", o.m);
  const int p = o.n + o.m + 1;
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(p);
  for (int k = 1; k <= o.n; ++k) theta(k - 1) = start[0].a[k];
  for (int k = 0; k <= start[0].m(); ++k) theta(o.n + k) = start[0].b[k];
  require(theta.allFinite(), name, ": the initial model has a non-finite parameter");

  EstimationResult result{start, start.to_transfer_function()};
  result.termination = Termination::iteration_limit;
  std::optional<UnstableLoopPass> pass = unstable_loop_pass_at(o, theta, controller, data);
  if (pass) result.start_closed_loop_fit_percent = unstable_loop_fit(data, *pass);
  result.start_fit_percent = result.start_closed_loop_fit_percent;
  int iteration = 1;
  bool stale = false;  // pass is an earlier iterate's
  if (!pass) {
    result.termination = Termination::closed_loop_unstable;
    result.message = name +
                     ": the controller does not stabilise the initial model, so the instrument "
                     "cannot be formed; give a model the controller stabilises";
  }
  while (pass && iteration <= options.max_iterations) {
    const Polynomial af = unstable_loop_prefilter(unstable_loop_denominator(o, theta));
    if (af.coefficients() != unstable_loop_denominator(o, theta).coefficients()) {
      ++result.unstable_reflections;
    }
    const std::optional<UnstableLoopStep> step = unstable_loop_step(data, o, *pass, af, stale);
    if (!step) {
      result.termination = Termination::singular_equations;
      result.message = name +
                       ": the instrument-regressor matrix is numerically singular or "
                       "non-finite at iteration " +
                       std::to_string(iteration);
      break;
    }
    result.reciprocal_condition = step->reciprocal_condition;
    // A step to a model the controller does not stabilise is halved toward the iterate.
    Eigen::VectorXd next = step->theta;
    std::optional<UnstableLoopPass> next_pass = unstable_loop_pass_at(o, next, controller, data);
    int halvings = 0;
    while (!next_pass && halvings < options.max_step_halvings) {
      next = 0.5 * (theta + next);
      ++halvings;
      ++result.step_halvings;
      next_pass = unstable_loop_pass_at(o, next, controller, data);
    }
    if (!next_pass) {
      // As the engine does: the full step is taken and this pass reused until an iterate's
      // loop is stable again.
      next = step->theta;
      ++result.sensitivity_fallbacks;
    }
    stale = !next_pass;
    const double change = (next - theta).norm() / std::max(next.norm(), 1e-300);
    result.relative_change = change;
    result.iterations = iteration;
    theta = next;
    if (next_pass) pass = std::move(next_pass);
    if (options.record_history) result.history.push_back({iteration, theta, change, 0.0});
    if (change < options.tolerance && !stale) {
      result.termination = Termination::converged;
      result.message = name + ": converged after " + std::to_string(iteration) +
                       " iterations (relative parameter change " + format_significant(change, 3) +
                       " < tolerance " + format_significant(options.tolerance, 3) + ")";
      break;
    }
    ++iteration;
  }
  if (result.termination == Termination::iteration_limit) {
    result.message = name + ": stopped at the iteration limit (" +
                     std::to_string(options.max_iterations) + ") with relative parameter change " +
                     format_significant(result.relative_change, 3);
  }
  result.parameters = theta;
  result.model = AdditiveModel::from_parameters({o}, theta, 0.0);
  result.transfer_function = result.model.to_transfer_function();
  result.additive_view = AdditiveModel::split_transfer_function(result.transfer_function);
  const bool loop_stable = pass.has_value() && !stale;
  if (loop_stable) {
    result.closed_loop_fit_percent = unstable_loop_fit(data, *pass);
    const Eigen::VectorXd residual = data.output() - pass->output;
    result.mean_squared_error = residual.squaredNorm() / static_cast<double>(data.size());
    result.noise_variance = residual.squaredNorm() / std::max<double>(data.size() - p, 1.0);
  }
  result.fit_percent = result.closed_loop_fit_percent;

  result.verdict = internal::unstable_loop_verdict(result, loop_stable);
  return result;
}

}  // namespace

namespace internal {

Verdict unstable_loop_verdict(const EstimationResult& result, bool loop_stable) {
  Verdict verdict;
  check_finite(verdict, result.parameters.allFinite(), "a parameter");
  if (!loop_stable) {
    verdict.fail(
        "the known controller does not stabilise the fitted model, so the model cannot "
        "describe the loop that was recorded",
        {verdict_advice::better_start, verdict_advice::lower_order});
  } else {
    check_fit(verdict, result.closed_loop_fit_percent, std::numeric_limits<double>::quiet_NaN());
    check_closed_loop_fit(verdict, result.closed_loop_fit_percent,
                          result.start_closed_loop_fit_percent);
  }
  const Eigen::VectorXcd poles =
      result.model[0].a.degree() >= 1 ? result.model[0].a.roots() : Eigen::VectorXcd(0);
  const Eigen::VectorXcd zeros = result.transfer_function.numerator().degree() >= 1
                                     ? result.transfer_function.zeros()
                                     : Eigen::VectorXcd(0);
  if (poles.allFinite() && zeros.allFinite()) check_cancellation(verdict, poles, zeros);
  std::vector<std::string> names;
  Eigen::VectorXd values(static_cast<Eigen::Index>(result.modes.size()));
  Eigen::VectorXd errors(values.size());
  for (size_t k = 0; k < result.modes.size(); ++k) {
    names.push_back("the natural frequency of mode " + std::to_string(k + 1));
    values(static_cast<Eigen::Index>(k)) = result.modes[k].value.natural_frequency;
    errors(static_cast<Eigen::Index>(k)) = result.modes[k].standard_error.natural_frequency;
  }
  check_standard_errors(verdict, names, values, errors);
  check_conditioning(verdict, result.reciprocal_condition, result.fit_percent);
  return verdict;
}

EstimationResult best_loop_fit(const std::vector<AdditiveModel>& starts,
                               const std::function<EstimationResult(const AdditiveModel&)>& fit) {
  std::optional<EstimationResult> best;
  for (const AdditiveModel& start : starts) {
    EstimationResult r = fit(start);
    auto score = [](const EstimationResult& e) {
      return std::isnan(e.closed_loop_fit_percent) ? -HUGE_VAL : e.closed_loop_fit_percent;
    };
    if (!best || (r.verdict.usable && !best->verdict.usable) ||
        (r.verdict.usable == best->verdict.usable && score(r) > score(*best))) {
      best = std::move(r);
    }
  }
  best->message += "; of " + std::to_string(starts.size()) +
                   " fits from different starts, the usable one with the best closed-loop fit "
                   "from r was kept";
  return std::move(*best);
}

AdditiveModel loop_start_submodel(const TransferFunction& g) {
  const Eigen::VectorXd d = g.denominator().coefficients();
  int l = 0;
  while (l < d.size() && d(l) == 0.0) ++l;
  const double scale = d(l);
  const Eigen::VectorXd a = d.tail(d.size() - l) / scale;
  return AdditiveModel({Submodel{Polynomial(a), g.numerator() * (1.0 / scale), l}});
}

std::optional<AdditiveModel> explained_input_start(const SampledData& data,
                                                   const SubmodelOrder& order, int loop_order) {
  try {
    RefinedIvOptions quick;
    quick.compute_covariance = false;
    const EstimationResult sensitivity =
        srivc(SampledData(data.sample_time(), data.reference(), data.input()),
              SubmodelOrder{loop_order, loop_order, 0}, quick);
    if (!sensitivity.parameters.allFinite()) return std::nullopt;
    const Eigen::VectorXd explained =
        simulate(sensitivity.transfer_function, data.reference(), data.sample_time());
    if (!explained.allFinite()) return std::nullopt;
    return loop_start_submodel(initial_transfer_function(
        SampledData(data.sample_time(), explained, data.output()), order, {}));
  } catch (const InvalidArgument&) {
    return std::nullopt;  // too short or too poorly excited for the first stage
  }
}

std::vector<AdditiveModel> stabilised_starts(const std::vector<AdditiveModel>& bases,
                                             const SubmodelOrder& order, const LoopFit& fit,
                                             int keep) {
  struct Scored {
    double fit;
    AdditiveModel model;
  };
  std::vector<Scored> scored;
  for (const AdditiveModel& base : bases) {
    const Submodel& s = base[0];
    const Eigen::VectorXcd roots = s.a.roots();
    std::vector<Eigen::Index> factors;  // real roots and the upper member of each pair
    for (Eigen::Index j = 0; j < roots.size(); ++j) {
      if (roots(j).imag() >= 0.0) factors.push_back(j);
    }
    if (factors.size() > 12) factors.resize(12);  // 4096 combinations at most
    for (unsigned mask = 0; mask < (1u << factors.size()); ++mask) {
      Eigen::VectorXcd moved = roots;
      for (size_t f = 0; f < factors.size(); ++f) {
        if (!(mask & (1u << f))) continue;
        const std::complex<double> z = roots(factors[f]);
        for (Eigen::Index j = 0; j < moved.size(); ++j) {
          if (std::abs(roots(j) - z) == 0.0 || std::abs(roots(j) - std::conj(z)) == 0.0) {
            moved(j) = std::complex<double>(-roots(j).real(), roots(j).imag());
          }
        }
      }
      const Polynomial a = mask == 0 ? s.a : Polynomial::from_roots(moved).anti_monic();
      if (a.degree() != order.n || s.b.degree() > order.m) continue;
      // The gain as it is, else the nearest power of two the controller stabilises.
      for (double gain : {1.0, 0.5, 2.0, 0.25, 4.0, 0.125, 8.0}) {
        Eigen::VectorXd theta = Eigen::VectorXd::Zero(order.n + order.m + 1);
        for (int k = 1; k <= order.n; ++k) theta(k - 1) = a[k];
        for (int k = 0; k <= s.b.degree(); ++k) theta(order.n + k) = gain * s.b[k];
        if (!theta.allFinite()) break;
        const std::optional<double> score = fit(theta);
        if (!score) continue;
        scored.push_back({*score, AdditiveModel({Submodel{a, gain * s.b, s.integrators}})});
        break;
      }
    }
  }
  std::stable_sort(scored.begin(), scored.end(),
                   [](const Scored& x, const Scored& y) { return x.fit > y.fit; });
  std::vector<AdditiveModel> starts;
  for (Scored& c : scored) {
    if (static_cast<int>(starts.size()) >= keep) break;
    starts.push_back(std::move(c.model));
  }
  return starts;
}

}  // namespace internal

std::vector<AdditiveModel> unstable_clsrivc_starts(const SampledData& data,
                                                   const DiscreteTransferFunction& controller,
                                                   const SubmodelOrder& order) {
  // The open-loop start (SRIVC on u -> y, which reflects every unstable root it meets), the
  // two-stage one (the open-loop start on the input's part r explains) and the closed-loop
  // one (made stable and one the controller stabilises, decision 0011).
  std::vector<AdditiveModel> bases;
  InitializationOptions init;
  bases.push_back(internal::loop_start_submodel(initial_transfer_function(data, order, init)));
  const int loop_order = order.n + order.integrators + controller.denominator().degree();
  if (std::optional<AdditiveModel> explained =
          internal::explained_input_start(data, order, loop_order)) {
    bases.push_back(std::move(*explained));
  }
  init.controller = controller;
  bases.push_back(internal::loop_start_submodel(initial_transfer_function(data, order, init)));
  // The reflected start of an unstable plant becomes the plant again when its roots move back.
  const internal::LoopFit fit = [&](const Eigen::VectorXd& theta) -> std::optional<double> {
    const std::optional<UnstableLoopPass> pass =
        unstable_loop_pass_at(order, theta, controller, data);
    if (!pass) return std::nullopt;
    return unstable_loop_fit(data, *pass);
  };
  std::vector<AdditiveModel> starts =
      internal::stabilised_starts(bases, order, fit, kUnstableStarts);
  if (starts.empty()) starts.push_back(bases.back());  // none stabilised: fails, named
  return starts;
}

std::optional<std::string> unstable_clsrivc_refusal(const SampledData& data,
                                                    const DiscreteTransferFunction& controller,
                                                    const SubmodelOrder& order,
                                                    const RefinedIvOptions& options) {
  options.validate();
  const std::string name = "unstable_clsrivc";
  using internal::concat;
  if (options.noise_model) {
    return concat(name,
                  ": noise_model is set; the fit with a stabilised prefilter has no noise model "
                  "(use the closed-loop estimator, CLRIVC)");
  }
  if (!data.has_reference()) {
    return concat(name, ": closed-loop estimation needs a measured reference r");
  }
  if (std::abs(controller.sample_time() - data.sample_time()) > 1e-9 * data.sample_time()) {
    return concat(name, ": the controller's sample time ", controller.sample_time(),
                  " differs from the data's ", data.sample_time());
  }
  if (order.n < 1 || order.m < 0 || order.integrators < 0 ||
      order.m > order.n + order.integrators) {
    return concat(name, ": the order needs n >= 1 and 0 <= m <= n + integrators (n = ", order.n,
                  ", m = ", order.m, ", integrators = ", order.integrators, ")");
  }
  if (options.input_delay_samples != 0 || options.input_delay_fraction != 0.0) {
    return concat(name, ": an input delay is not supported");
  }
  if (data.size() < 3 * (order.n + order.m + 1) + 20) {
    return concat(name, ": ", data.size(), " samples are too few");
  }
  return std::nullopt;
}

EstimationResult unstable_clsrivc(const SampledData& data,
                                  const DiscreteTransferFunction& controller,
                                  const SubmodelOrder& order, const RefinedIvOptions& options) {
  if (std::optional<std::string> refusal =
          unstable_clsrivc_refusal(data, controller, order, options)) {
    throw InvalidArgument(*refusal);
  }
  if (options.initial_model) {
    return unstable_clsrivc_from(data, controller, order, options, *options.initial_model);
  }
  return internal::best_loop_fit(
      unstable_clsrivc_starts(data, controller, order), [&](const AdditiveModel& start) {
        return unstable_clsrivc_from(data, controller, order, options, start);
      });
}

}  // namespace ctid
