// The additive closed-loop estimator from the data alone (decision 0028): the refined IV
// iteration run from several starts, the usable estimate with the best output-error fit kept.
// Split from refined_iv.cc, whose driver runs one estimate from one start; with it, the
// conversions of a start model into beta (parameters_for_orders, unfactored_parameters).
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ctid/core/error.h"
#include "refined_iv/internal/refined_iv_engine.h"

namespace ctid::internal {

namespace {

// The additive closed-loop estimator from the data alone (decision 0028). CLSRIVC can have
// several stationary points on one closed-loop record, and the output error y - G u it is
// started by leans toward -1/C_d, so one start is not enough: the additive iteration runs from
// the additive start of each start method and from the split of the unfactored CLSRIVC fit of
// each. Of the usable estimates (the verdict holds each to the loop the controller keeps
// stable and to its closed-loop fit from r), the one kept has the best output-error fit
// y - G u: with the noise fed back through the loop it tells the stationary points apart where
// the closed-loop fit from r, in which r explains little of y, cannot (measured in decision
// 0028).
EstimationResult closed_loop_additive_from_data(const RefinedIvProblem& problem,
                                                const RefinedIvOptions& options) {
  std::vector<StartMethod> methods;
  if (options.start == StartMethod::automatic) {
    methods = {StartMethod::lssvf, StartMethod::frf};
  } else {
    methods = {options.start};
  }
  std::vector<EstimationResult> candidates;
  for (StartMethod method : methods) {
    RefinedIvOptions own = options;
    own.start = method;
    ScreenedStart start;  // screened once for both fits from this method
    // A method that forms no start (e.g. too few resonance peaks for the FRF start) gives no
    // candidate: the other candidates remain.
    if (std::optional<EstimationResult> r = run_refined_iv_if_started(problem, own, &start)) {
      candidates.push_back(std::move(*r));
    }
    RefinedIvProblem unfactored = problem;
    unfactored.orders = {unfactored_order(problem.orders)};
    unfactored.unfactored = true;
    RefinedIvOptions quick = own;
    quick.compute_covariance = false;
    quick.record_history = false;
    std::optional<AdditiveModel> whole;  // one submodel, grouped by the engine
    std::optional<EstimationResult> g = run_refined_iv_if_started(unfactored, quick, &start);
    if (g && g->parameters.allFinite() && g->iterations > 0) whole = std::move(g->model);
    if (!whole) continue;
    RefinedIvOptions split = options;
    split.initial_model = std::move(whole);
    // None when the unfactored fit's poles cannot be grouped into the submodels.
    if (std::optional<EstimationResult> r = run_refined_iv_if_started(problem, split)) {
      candidates.push_back(std::move(*r));
    }
  }
  // No candidate at all: the plain run, which names what went wrong.
  if (candidates.empty()) return run_refined_iv_from_start(problem, options);
  // Usable first, by their output-error fit; if none is, the best closed-loop fit from r
  // (NaN, a loop the controller does not hold, last). Ties keep the earlier candidate.
  auto better = [](const EstimationResult& a, const EstimationResult& b) {
    if (a.verdict.usable != b.verdict.usable) return a.verdict.usable;
    auto score = [usable = a.verdict.usable](const EstimationResult& r) {
      const double f = usable ? r.fit_percent : r.closed_loop_fit_percent;
      return std::isnan(f) ? -HUGE_VAL : f;
    };
    return score(a) > score(b);
  };
  size_t best = 0;
  for (size_t k = 1; k < candidates.size(); ++k) {
    if (better(candidates[k], candidates[best])) best = k;
  }
  EstimationResult result = std::move(candidates[best]);
  result.message += "; of " + std::to_string(candidates.size()) +
                    " fits from different starts, the usable one with the best output-error fit "
                    "was kept (with none usable, the best closed-loop fit from r)";
  return result;
}

}  // namespace

EstimationResult run_refined_iv(const RefinedIvProblem& problem, const RefinedIvOptions& options) {
  if (problem.controller != nullptr && !problem.unfactored && problem.orders.size() > 1 &&
      !options.initial_model) {
    options.validate();
    return closed_loop_additive_from_data(problem, options);
  }
  return run_refined_iv_from_start(problem, options);
}

Eigen::VectorXd parameters_for_orders(const AdditiveModel& model,
                                      const std::vector<SubmodelOrder>& orders) {
  require(model.size() == static_cast<int>(orders.size()), "initial model has ", model.size(),
          " submodels; the structure asks for ", orders.size());
  const srivc_engine::Layout layout(orders);
  Eigen::VectorXd beta = Eigen::VectorXd::Zero(layout.parameters);
  for (int i = 0; i < model.size(); ++i) {
    const Submodel& s = model[i];
    const SubmodelOrder& o = orders[static_cast<size_t>(i)];
    require(s.n() == o.n && s.integrators == o.integrators && s.m() <= o.m, "initial submodel ",
            i + 1, " has n = ", s.n(), ", m = ", s.m(), ", integrators = ", s.integrators,
            "; the structure asks for n = ", o.n, ", m <= ", o.m,
            ", integrators = ", o.integrators);
    const int off = layout.offset[static_cast<size_t>(i)];
    for (int k = 1; k <= o.n; ++k) beta(off + k - 1) = s.a[k];
    for (int k = 0; k <= s.m(); ++k) beta(off + o.n + k) = s.b[k];
  }
  return beta;
}

Eigen::VectorXd unfactored_parameters(const TransferFunction& g, const SubmodelOrder& order) {
  const Polynomial& den = g.denominator();
  int l = 0;
  while (l <= den.degree() && den[l] == 0.0) ++l;
  require(
      l == order.integrators && den.degree() - l == order.n && g.numerator().degree() <= order.m,
      "initial transfer function has ", den.degree() - l, " non-zero poles, ", l,
      " poles at the origin and numerator degree ", g.numerator().degree(),
      "; the structure asks for n = ", order.n, ", integrators = ", order.integrators,
      ", m <= ", order.m);
  const double scale = den[l];
  Eigen::VectorXd beta = Eigen::VectorXd::Zero(order.n + order.m + 1);
  for (int k = 1; k <= order.n; ++k) beta(k - 1) = den[l + k] / scale;
  for (int k = 0; k <= g.numerator().degree(); ++k) beta(order.n + k) = g.numerator()[k] / scale;
  return beta;
}

}  // namespace ctid::internal
