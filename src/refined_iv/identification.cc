// The refined IV front door: chooses the estimator, runs the delay scan and the relocation.
#include "ctid/refined_iv/identification.h"

#include <utility>

#include "ctid/core/error.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/clsrivc.h"
#include "ctid/refined_iv/srivc.h"

namespace ctid {

ModelStructure ModelStructure::unfactored(int poles, int zeros, int integrators) {
  return {ModelKind::unfactored, {SubmodelOrder{poles, zeros, integrators}}};
}

ModelStructure ModelStructure::additive(std::vector<SubmodelOrder> orders) {
  return {ModelKind::additive, std::move(orders)};
}

ModelStructure ModelStructure::modes(int count) {
  require(count >= 1, "ModelStructure::modes: count is ", count, "; it must be >= 1");
  return {ModelKind::additive,
          std::vector<SubmodelOrder>(static_cast<std::size_t>(count), SubmodelOrder{2, 0, 0})};
}

void ModelStructure::check_relations(const std::string& path) const {
  if (kind == ModelKind::unfactored) {
    require(orders.size() == 1, path, ".orders has ", orders.size(),
            " entries; an unfactored structure has exactly one");
  } else {
    require(!orders.empty(), path, ".orders is empty; an additive structure has at least one");
  }
}

void DelayRange::check_relations(const std::string& path) const {
  require(max >= min, path, ".max is ", max, "; it must be >= min (", min, ")");
}

void IdentificationOptions::check_relations(const std::string& path) const {
  require(!delay_scan || refined_iv.input_delay == 0, path, ".refined_iv.input_delay is ",
          refined_iv.input_delay, " and ", path,
          ".delay_scan is set; give a known delay or a scan, not both");
}

RefinedIvEstimator choose_estimator(const ModelStructure& structure, bool closed_loop) {
  if (structure.is_additive()) {
    return closed_loop ? RefinedIvEstimator::additive_clsrivc : RefinedIvEstimator::additive_srivc;
  }
  return closed_loop ? RefinedIvEstimator::clsrivc : RefinedIvEstimator::srivc;
}

void validate_identification(const ModelStructure& structure,
                             const IdentificationOptions& options) {
  structure.validate();
  options.validate();
  if (options.relocate_modes) {
    require(structure.is_additive(),
            "IdentificationOptions.relocate_modes is true but the structure is unfactored; mode "
            "relocation moves submodels of an additive model");
    require(!options.controller,
            "IdentificationOptions.relocate_modes is true but a controller is given; mode "
            "relocation is for open-loop data");
  }
}

IdentificationResult identify(const SampledData& data, const ModelStructure& structure,
                              const IdentificationOptions& options) {
  validate_identification(structure, options);
  const bool closed_loop = options.controller.has_value();
  const RefinedIvEstimator estimator = choose_estimator(structure, closed_loop);
  const std::vector<SubmodelOrder>& orders = structure.orders;

  auto estimate = [&](int delay) {
    RefinedIvOptions o = options.refined_iv;
    o.input_delay = delay;
    switch (estimator) {
      case RefinedIvEstimator::srivc:
        return srivc(data, orders.front(), o);
      case RefinedIvEstimator::clsrivc:
        return clsrivc(data, *options.controller, orders.front(), o);
      case RefinedIvEstimator::additive_srivc:
        return additive_srivc(data, orders, o);
      case RefinedIvEstimator::additive_clsrivc:
        break;
    }
    return additive_clsrivc(data, *options.controller, orders, o);
  };

  std::optional<InputDelayScanResult> scanned;
  std::optional<EstimationResult> fitted;
  if (options.delay_scan) {
    scanned = scan_input_delay(estimate, options.delay_scan->min, options.delay_scan->max);
    fitted = scanned->best;
  } else {
    fitted = estimate(options.refined_iv.input_delay);
  }
  std::optional<ModeRelocationResult> relocated;
  if (options.relocate_modes) {
    RefinedIvOptions o = options.refined_iv;
    o.input_delay = fitted->input_delay;
    o.initial_model = fitted->model;
    relocated = additive_srivc_relocated(data, orders, o, options.relocation);
    fitted = relocated->estimate;
  }

  IdentificationResult result(std::move(*fitted));
  result.estimator = estimator;
  result.closed_loop = closed_loop;
  result.delay_scan = std::move(scanned);
  result.mode_relocation = std::move(relocated);
  return result;
}

}  // namespace ctid
