// The refined IV front door: chooses the estimator, runs the delay scan and the relocation.
#include "ctid/identification/identification.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include <boost/math/tools/minima.hpp>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/refined_iv/clsrivc_continuous.h"
#include "ctid/refined_iv/refined_iv.h"
#include "ctid/refined_iv/unstable_clsrivc.h"
#include "ctid/simulation/simulate.h"
#include "internal/two_stage_covariance.h"
#include "internal/two_stage_stages.h"

namespace ctid {

ModelStructure ModelStructure::unfactored(int poles, int zeros, int integrators) {
  return {ModelKind::unfactored, {SubmodelOrder{poles, zeros, integrators}}};
}

ModelStructure ModelStructure::additive(std::vector<SubmodelOrder> orders) {
  return {ModelKind::additive, std::move(orders)};
}

ModelStructure ModelStructure::modes(int count) {
  require(count >= 1, "ModelStructure::modes: count is ", count, "; it must be >= 1");
  require(count <= kMaxSubmodels, "ModelStructure::modes: count is ", count,
          "; a structure has at most ", kMaxSubmodels, " submodels");
  return {ModelKind::additive,
          std::vector<SubmodelOrder>(static_cast<std::size_t>(count), SubmodelOrder{2, 0, 0})};
}

void ModelStructure::check_size(const std::string& path) const {
  require(orders.size() <= static_cast<std::size_t>(kMaxSubmodels), path, ".orders has ",
          orders.size(), " entries; a structure has at most ", kMaxSubmodels, " submodels");
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

void DelayInterval::check_relations(const std::string& path) const {
  require(max >= min, path, ".max is ", max, " s; it must be >= min (", min, " s)");
}

void IdentificationOptions::check_relations(const std::string& path) const {
  const bool known = refined_iv.input_delay_samples != 0 || refined_iv.input_delay_fraction != 0.0;
  require(!delay_scan_samples || !known, path, ".refined_iv.input_delay_samples is ",
          refined_iv.input_delay_samples, " and ", path,
          ".delay_scan_samples is set; give a known delay or a scan, not both");
  require(!delay_range || !known, path, ".refined_iv.input_delay_samples is ",
          refined_iv.input_delay_samples, " and ", path,
          ".delay_range is set; give a known delay or a range, not both");
  require(!delay_range || !delay_scan_samples, path, ".delay_scan_samples and ", path,
          ".delay_range are both set; a range already scans its whole samples");
  require(!two_stage || !controller, path, ".two_stage and ", path,
          ".controller are both set; the two-stage method is for an unknown controller (with a "
          "known one, CLSRIVC uses it)");
  require(!continuous_controller || (!controller && !two_stage), path,
          ".continuous_controller and ", path, controller ? ".controller" : ".two_stage",
          " are both set; a loop has one controller");
  require(!continuous_controller || (!delay_scan_samples && !delay_range && !known), path,
          ".continuous_controller is set with an input delay; a delay in an analog loop is not "
          "supported");
}

RefinedIvEstimator choose_estimator(const ModelStructure& structure, bool closed_loop,
                                    bool noise_model) {
  using E = RefinedIvEstimator;
  if (structure.is_additive()) {
    if (noise_model) return closed_loop ? E::additive_clrivc : E::additive_rivc;
    return closed_loop ? E::additive_clsrivc : E::additive_srivc;
  }
  if (noise_model) return closed_loop ? E::clrivc : E::rivc;
  return closed_loop ? E::clsrivc : E::srivc;
}

namespace {

// A model of the structure (every coefficient 1): the estimate's parameter layout and names,
// against which constraints are checked and resolved before any fit (decision 0057).
AdditiveModel layout_model(const ModelStructure& structure) {
  Eigen::Index count = 0;
  for (const SubmodelOrder& o : structure.orders) count += o.n + o.m + 1;
  return AdditiveModel::from_parameters(structure.orders, Eigen::VectorXd::Ones(count));
}

}  // namespace

void validate_identification(const ModelStructure& structure,
                             const IdentificationOptions& options) {
  structure.validate();
  options.validate();
  if (options.relocate_modes) {
    require(structure.is_additive(),
            "IdentificationOptions.relocate_modes is true but the structure is unfactored; mode "
            "relocation moves submodels of an additive model");
    require(!options.controller && !options.continuous_controller,
            "IdentificationOptions.relocate_modes is true but a controller is given; mode "
            "relocation is for open-loop data");
  }
  if (options.polish_asked()) {
    validate_constraints(layout_model(structure), options.constraints,
                         options.polish_options.estimate_delay);
  }
  require(!options.polish_asked() ||
              (!options.controller && !options.continuous_controller && !options.two_stage),
          "IdentificationOptions.polish (or a constraint) is set but the data are closed loop (",
          options.two_stage ? "the two-stage method" : "a controller",
          " is given); the output-error polish is for open-loop records");
}

namespace {

// The delay as a continuous parameter (IdentificationOptions::delay_range): the whole samples
// in the range are scanned, then the output error of converged fits is minimised over tau
// within a sample of the best, in two Brent passes (the second on a 1e-4 h scale, since a
// minimum is located only to about sqrt(eps) of the search variable), and the final fit at
// tau carries the delay's sensitivity in its covariance.
template <class Run>
EstimationResult estimate_delay(std::span<const SampledData> records, const DelayInterval& range,
                                const RefinedIvOptions& base, const Run& run,
                                std::optional<InputDelayScanResult>& scanned,
                                const std::function<void(int, int)>& progress) {
  const SampledData* shortest = &records.front();
  for (const SampledData& record : records) {
    if (record.size() < shortest->size()) shortest = &record;
  }
  const double h = shortest->sample_time();
  const double duration = shortest->size() * h;
  require(range.max < duration, "IdentificationOptions.delay_range.max is ", range.max,
          " s; the record lasts only ", duration, " s (", shortest->size(), " samples of ", h,
          " s)");
  auto at = [&](double tau, const std::optional<AdditiveModel>& start, bool final_fit) {
    const DelaySplit split = split_delay(tau, h);
    RefinedIvOptions o = base;
    o.input_delay_samples = split.samples;
    o.input_delay_fraction = split.fraction;
    if (start) o.initial_model = start;
    o.compute_covariance = final_fit && base.compute_covariance;
    o.delay_estimated = final_fit;
    o.record_history = final_fit && base.record_history;
    return run(o);
  };
  const int first = static_cast<int>(std::ceil(range.min / h - 1e-9));
  const int last = static_cast<int>(std::floor(range.max / h + 1e-9));
  std::optional<EstimationResult> best;
  if (first <= last) {
    scanned = scan_input_delay([&](int delay) { return at(delay * h, std::nullopt, false); }, first,
                               last, progress);
    best = scanned->best;
  } else {
    best = at(0.5 * (range.min + range.max), std::nullopt, false);
  }
  const double centre = best->model.input_delay();
  AdditiveModel warm = best->model;
  double warm_error =
      best->verdict.usable ? best->mean_squared_error : std::numeric_limits<double>::infinity();
  auto profile = [&](double tau) {
    const EstimationResult r = at(tau, warm, false);
    if (!r.verdict.usable || !std::isfinite(r.mean_squared_error)) {
      return std::numeric_limits<double>::infinity();
    }
    if (r.mean_squared_error < warm_error) {
      warm_error = r.mean_squared_error;
      warm = r.model;
    }
    return r.mean_squared_error;
  };
  double tau = centre;
  double scale = h;
  for (int pass = 0; pass < 2; ++pass) {
    const double lo = std::max(range.min, tau - scale);
    const double hi = std::min(range.max, tau + scale);
    if (!(hi > lo)) break;
    std::uintmax_t evaluations = 60;
    const double origin = tau;
    const std::pair<double, double> found = boost::math::tools::brent_find_minima(
        [&](double x) { return profile(origin + x * scale); }, (lo - origin) / scale,
        (hi - origin) / scale, std::numeric_limits<double>::digits / 2, evaluations);
    if (!std::isfinite(found.second)) break;
    tau = std::clamp(origin + found.first * scale, range.min, range.max);
    scale *= 1e-4;
  }
  EstimationResult result = at(tau, warm, true);
  result.message += "; delay estimated in [" + format_significant(range.min, 6) + ", " +
                    format_significant(range.max, 6) + "] s: " + format_significant(tau, 10) + " s";
  return result;
}

IdentificationResult identify_two_stage(std::span<const SampledData> records,
                                        const ModelStructure& structure,
                                        const IdentificationOptions& options,
                                        const IdentificationProgress& progress);

// The polish of `fitted` (decision 0057). Asked for (polish_asked()): with its options, the
// initial state estimated when refined_iv estimates it, errors thrown. Otherwise (an iteration
// that did not converge) at the fit's delay, and none when it cannot start: a start that is
// not finite or whose output is not, a record under 10 samples per parameter.
std::optional<OutputErrorPolishResult> polish_fit(const SampledData& record,
                                                  const EstimationResult& fitted,
                                                  const IdentificationOptions& options) {
  // Open loop here: a reference the record carries is not the polish's business.
  const SampledData data = record.has_reference()
                               ? SampledData(record.sample_time(), record.input(), record.output(),
                                             std::nullopt, record.start_time())
                                     .with_input_hold(record.input_hold())
                               : record;
  OutputErrorPolishOptions o = options.polish_options;
  o.estimate_initial_state = o.estimate_initial_state ||
                             options.refined_iv.initial_conditions == InitialConditions::estimate;
  if (options.polish_asked()) {
    return polish_output_error(data, fitted.model, fitted.noise_model, o, options.constraints);
  }
  o.estimate_delay = false;
  if (polish_start_refusal(data, fitted.model, fitted.noise_model, o)) return std::nullopt;
  return polish_output_error(data, fitted.model, fitted.noise_model, o);
}

// Decision 0057: the polish of `fitted`; without polish_asked() (an iteration that did not
// converge), the iteration restarted from the polished model replaces `fitted` when it
// converges to a usable model, and `restarted` says so.
template <class Run>
std::optional<OutputErrorPolishResult> polish_and_restart(const SampledData& data,
                                                          EstimationResult& fitted,
                                                          const IdentificationOptions& options,
                                                          const Run& run, bool& restarted) {
  std::optional<OutputErrorPolishResult> polished = polish_fit(data, fitted, options);
  if (options.polish_asked() || !polished || !polished->verdict.usable) return polished;
  RefinedIvOptions o = options.refined_iv;
  o.input_delay_samples = fitted.input_delay_samples;
  o.input_delay_fraction = fitted.input_delay_fraction;
  o.initial_model = polished->model;
  EstimationResult again = run(o);
  again.message +=
      "; restarted from the output-error polish of an iteration that had not "
      "converged (" +
      std::to_string(fitted.iterations) + " iterations)";
  if (again.converged() && again.verdict.usable) {
    fitted = std::move(again);
    restarted = true;
  }
  return polished;
}

// An analog loop (IdentificationOptions::continuous_controller, decision 0067):
// clsrivc_continuous on one record, an unfactored structure.
IdentificationResult identify_analog_loop(std::span<const SampledData> records,
                                          const ModelStructure& structure,
                                          const IdentificationOptions& options) {
  require(!structure.is_additive(),
          "IdentificationOptions.continuous_controller is set but the structure is additive; "
          "with a continuous-time controller one unfactored model is fitted");
  require(records.size() == 1, "IdentificationOptions.continuous_controller is set but ",
          records.size(),
          " records are given; with a continuous-time controller one record is "
          "fitted");
  require(!options.refined_iv.noise_model,
          "IdentificationOptions.continuous_controller is set with refined_iv.noise_model; "
          "with a continuous-time controller no noise model is fitted");
  IdentificationResult result(clsrivc_continuous(records.front(), *options.continuous_controller,
                                                 structure.orders.front(), options.refined_iv));
  result.estimator = RefinedIvEstimator::clsrivc_continuous;
  result.closed_loop = true;
  return result;
}

IdentificationResult identify_records(std::span<const SampledData> records,
                                      const ModelStructure& structure,
                                      const IdentificationOptions& options,
                                      const IdentificationProgress& progress) {
  if (options.two_stage) return identify_two_stage(records, structure, options, progress);
  validate_identification(structure, options);
  if (options.continuous_controller) return identify_analog_loop(records, structure, options);
  require(!records.empty(), "identify: no data record was given");
  require(!options.relocate_modes || records.size() == 1,
          "IdentificationOptions.relocate_modes is true but ", records.size(),
          " records are given; mode relocation works on one record");
  require(!options.polish_asked() || records.size() == 1,
          "IdentificationOptions.polish (or a constraint) is set but ", records.size(),
          " records are given; the output-error polish works on one record");
  // What needs the records, checked before any work: the structure's parameters and the
  // scanned delays against the data (the estimator's own, finer check comes later).
  int shortest = records.front().size();
  long long total_samples = 0;
  for (const SampledData& record : records) {
    shortest = std::min(shortest, record.size());
    total_samples += record.size();
  }
  long long parameters = 0;
  for (const SubmodelOrder& order : structure.orders) {
    parameters += static_cast<long long>(order.n) + order.m + 1;
  }
  require(total_samples >= 3 * parameters, "identify: ", total_samples,
          " samples are too few for the structure's ", parameters,
          " parameters; at least 3 per parameter are needed (a lower order or fewer modes)");
  require(!options.delay_scan_samples || options.delay_scan_samples->max <= shortest / 2,
          "IdentificationOptions.delay_scan_samples.max is ",
          options.delay_scan_samples ? options.delay_scan_samples->max : 0,
          " samples; the shortest record has ", shortest,
          " samples and a scanned delay may be at most half of it (", shortest / 2, ")");
  const bool closed_loop = options.controller.has_value();
  const RefinedIvEstimator estimator =
      choose_estimator(structure, closed_loop, options.refined_iv.noise_model.has_value());
  const std::vector<SubmodelOrder>& orders = structure.orders;
  const SampledData& data = records.front();

  // Decisions 0057 and 0058: the coefficients the constraints hold or bound in the iteration.
  std::vector<std::pair<Eigen::Index, double>> known;
  std::vector<std::tuple<Eigen::Index, double, double>> bounds;
  if (!options.constraints.empty()) {
    const AdditiveModel layout = layout_model(structure);
    known = held_coefficients(layout, options.constraints);
    bounds = bounded_coefficients(layout, options.constraints);
  }
  // The estimators of srivc.h, on every record.
  auto run = [&](const RefinedIvOptions& o) {
    RefinedIvProblem problem;
    for (const SampledData& record : records) problem.records.push_back(&record);
    problem.orders = orders;
    problem.controller = closed_loop ? &*options.controller : nullptr;
    problem.unfactored = !structure.is_additive();
    problem.name = enum_name(estimator).data();  // the enumerator names are literals
    problem.held_coefficients = known;
    problem.bounded_coefficients = bounds;
    return estimate_refined_iv(problem, o);
  };
  auto estimate = [&](int delay) {
    RefinedIvOptions o = options.refined_iv;
    o.input_delay_samples = delay;
    return run(o);
  };

  std::optional<InputDelayScanResult> scanned;
  std::optional<EstimationResult> fitted;
  if (options.delay_scan_samples) {
    scanned = scan_input_delay(estimate, options.delay_scan_samples->min,
                               options.delay_scan_samples->max, progress.delay_scan);
    fitted = scanned->best;
  } else if (options.delay_range) {
    fitted = estimate_delay(records, *options.delay_range, options.refined_iv, run, scanned,
                            progress.delay_scan);
  } else {
    fitted = estimate(options.refined_iv.input_delay_samples);
  }
  std::optional<ModeRelocationResult> relocated;
  if (options.relocate_modes) {
    RefinedIvOptions o = options.refined_iv;
    o.input_delay_samples = fitted->input_delay_samples;
    o.input_delay_fraction = fitted->input_delay_fraction;
    o.initial_model = fitted->model;
    relocated = additive_srivc_relocated(data, orders, o, options.relocation, progress.relocation);
    fitted = relocated->estimate;
  }

  // Decision 0038: an unusable unfactored closed-loop fit may be of a plant the engine cannot
  // hold (it reflects every unstable root); the fit with a stabilised prefilter replaces it
  // when that one is usable.
  if (closed_loop && !structure.is_additive() && records.size() == 1 &&
      !options.delay_scan_samples && !options.delay_range && !options.relocate_modes &&
      options.constraints.empty() && !fitted->verdict.usable &&
      !unstable_clsrivc_refusal(data, *options.controller, orders[0], options.refined_iv)) {
    try {
      EstimationResult held =
          unstable_clsrivc(data, *options.controller, orders[0], options.refined_iv);
      if (held.verdict.usable) fitted = std::move(held);
    } catch (const InvalidArgument&) {
      // Its bad-input refusals are ruled out above; what is left is initial_transfer_function
      // refusing a record that forms no start of this order (as the engine refuses it): the
      // engine's fit stands.
    }
  }
  // Decision 0057: the output-error polish, asked for or of an iteration that did not converge.
  bool restarted = false;
  std::optional<OutputErrorPolishResult> polished;
  if (!closed_loop && records.size() == 1 && (options.polish_asked() || !fitted->converged())) {
    polished = polish_and_restart(data, *fitted, options, run, restarted);
  }
  IdentificationResult result(std::move(*fitted));
  result.estimator = estimator;
  result.closed_loop = closed_loop;
  result.delay_scan = std::move(scanned);
  result.mode_relocation = std::move(relocated);
  result.polish = std::move(polished);
  result.restarted_from_polish = restarted;
  return result;
}

// Decision 0043: stage 1 models r -> u on every record by an FIR or a discrete output-error
// model (the kind and order chosen on the longest record), stage 2 is the open-loop estimation from
// u_hat = S_hat r, which the noise does not reach when r is external.
IdentificationResult identify_two_stage(std::span<const SampledData> records,
                                        const ModelStructure& structure,
                                        const IdentificationOptions& options,
                                        const IdentificationProgress& progress) {
  validate_identification(structure, options);
  return internal::identify_from_stage_one(internal::fit_stage_one(records, *options.two_stage),
                                           structure, options, progress);
}

}  // namespace

IdentificationResult identify(const SampledData& data, const ModelStructure& structure,
                              const IdentificationOptions& options,
                              const IdentificationProgress& progress) {
  return identify_records(std::span<const SampledData>(&data, 1), structure, options, progress);
}

IdentificationResult identify(const std::vector<SampledData>& records,
                              const ModelStructure& structure, const IdentificationOptions& options,
                              const IdentificationProgress& progress) {
  return identify_records(records, structure, options, progress);
}

IdentificationResult identify(const IrregularRecord& record, const ModelStructure& structure,
                              const IdentificationOptions& options) {
  validate_identification(structure, options);
  const char* why =
      "; irregular time stamps are fitted by srivc_irregular, an unfactored "
      "open-loop SRIVC (docs/decisions/0034)";
  require(!structure.is_additive(), "ModelStructure.kind is additive", why);
  require(!options.controller && !options.continuous_controller,
          "IdentificationOptions.controller is set (closed loop)", why);
  require(!options.delay_scan_samples && !options.delay_range,
          "IdentificationOptions.delay_scan_samples or delay_range is set", why);
  require(!options.relocate_modes, "IdentificationOptions.relocate_modes is true", why);
  require(!options.two_stage, "IdentificationOptions.two_stage is set", why);
  require(!options.polish_asked(), "IdentificationOptions.polish (or a constraint) is set", why);
  require(!options.refined_iv.noise_model, "IdentificationOptions.refined_iv.noise_model is set",
          why);
  IdentificationResult result(
      srivc_irregular(record, structure.orders.front(), options.refined_iv));
  result.estimator = RefinedIvEstimator::srivc_irregular;
  result.closed_loop = false;
  return result;
}

ProcessModelResult identify(const SampledData& data, const ProcessStructure& structure,
                            const ProcessModelOptions& options) {
  return estimate_process_model(data, structure, options);
}

void validate_identification(const ProcessStructure& structure,
                             const ProcessModelOptions& options) {
  validate_process_model(structure, options);
}

TimeResponse time_response(const ProcessModelResult& result, const TimeResponseOptions& options) {
  return process_time_response(result, options);
}

namespace internal {

StageOne fit_stage_one(std::span<const SampledData> records, const TwoStageOptions& two_stage) {
  require(!records.empty(), "identify: no data record was given");
  const SampledData* longest = &records.front();
  for (const SampledData& record : records) {
    require(record.has_reference(),
            "IdentificationOptions.two_stage is set but a record has no reference; the two-stage "
            "method fits the map from the reference r to the input u (--reference-column)");
    if (record.size() > longest->size()) longest = &record;
  }
  // The kind and order are chosen on the longest record, whose fit is then kept as it is.
  StageOne out;
  out.chosen = two_stage;
  std::optional<SensitivityFit> longest_fit;
  if (out.chosen.sensitivity_model == SensitivityModel::automatic ||
      out.chosen.sensitivity_order == 0) {
    longest_fit = fit_sensitivity(*longest, out.chosen);
    out.chosen = TwoStageOptions{longest_fit->model, longest_fit->order};
  }
  out.fits.reserve(records.size());
  out.simulated.reserve(records.size());
  for (const SampledData& record : records) {
    out.fits.push_back(&record == longest && longest_fit ? std::move(*longest_fit)
                                                         : fit_sensitivity(record, out.chosen));
    out.simulated.push_back(SampledData(record.sample_time(), out.fits.back().simulated_input,
                                        record.output(), std::nullopt, record.start_time())
                                .with_input_hold(record.input_hold()));
    out.references.push_back(record.reference());
    out.input_errors.push_back(record.input() - out.fits.back().simulated_input);
  }
  return out;
}

IdentificationResult identify_from_stage_one(const StageOne& stage_one,
                                             const ModelStructure& structure,
                                             const IdentificationOptions& options,
                                             const IdentificationProgress& progress) {
  TwoStageResult stage;
  stage.sensitivity_model = stage_one.chosen.sensitivity_model;
  stage.sensitivity_order = stage_one.chosen.sensitivity_order;
  for (const SensitivityFit& fit : stage_one.fits) {
    stage.sensitivity_fit_percent.push_back(fit.fit_percent);
  }
  IdentificationOptions open = options;
  open.two_stage.reset();
  IdentificationResult result = identify_records(stage_one.simulated, structure, open, progress);
  result.closed_loop = true;
  stage.assumptions = internal::concat(
      "r is external (uncorrelated with the noise) and excites the loop; the loop is linear and "
      "time-invariant, and stage 1's model holds its map r -> u (an FIR its impulse response); ",
      include_stage_one_error(result, structure, open, stage_one)
          ? "the standard errors include stage 1's error and its correlation with stage 2's noise"
          : "the standard errors treat the simulated input as exact, so they leave out stage 1's "
            "error");
  result.estimate.message += internal::concat(
      "; two-stage (unknown controller): r -> u by a ", enum_name(stage.sensitivity_model),
      " model of order ", stage.sensitivity_order, " (fit ",
      format_significant(stage.sensitivity_fit_percent.front(), 4),
      " %), then the plant from the simulated input");
  result.two_stage = std::move(stage);
  return result;
}

}  // namespace internal
}  // namespace ctid
