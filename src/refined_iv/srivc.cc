// Public entry points of the refined IV family; the iteration lives in refined_iv.cc.
#include "ctid/refined_iv/srivc.h"

#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/clsrivc.h"
#include "ctid/refined_iv/refined_iv.h"
#include "refined_iv/internal/refined_iv_engine.h"

namespace ctid {

EstimationResult estimate_refined_iv(const RefinedIvProblem& problem,
                                     const RefinedIvOptions& options) {
  return internal::run_refined_iv(problem, options);
}

EstimationResult srivc(const SampledData& data, const SubmodelOrder& order,
                       const RefinedIvOptions& options) {
  internal::RefinedIvProblem problem;
  problem.records = {&data};
  problem.orders = {order};
  problem.unfactored = true;
  problem.name = "srivc";
  return internal::run_refined_iv(problem, options);
}

EstimationResult clsrivc(const SampledData& data, const DiscreteTransferFunction& controller,
                         const SubmodelOrder& order, const RefinedIvOptions& options) {
  internal::RefinedIvProblem problem;
  problem.records = {&data};
  problem.orders = {order};
  problem.controller = &controller;
  problem.unfactored = true;
  problem.name = "clsrivc";
  return internal::run_refined_iv(problem, options);
}

EstimationResult additive_srivc(const SampledData& data, const std::vector<SubmodelOrder>& orders,
                                const RefinedIvOptions& options) {
  internal::RefinedIvProblem problem;
  problem.records = {&data};
  problem.orders = orders;
  problem.name = "additive_srivc";
  return internal::run_refined_iv(problem, options);
}

EstimationResult additive_clsrivc(const SampledData& data,
                                  const DiscreteTransferFunction& controller,
                                  const std::vector<SubmodelOrder>& orders,
                                  const RefinedIvOptions& options) {
  internal::RefinedIvProblem problem;
  problem.records = {&data};
  problem.orders = orders;
  problem.controller = &controller;
  problem.name = "additive_clsrivc";
  return internal::run_refined_iv(problem, options);
}

}  // namespace ctid
