// Candidate structures fitted with identify() and scored on held-out data (structure_scan.h).
#include "ctid/identification/structure_scan.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/core/parallel.h"
#include "ctid/estimation/validation.h"
#include "ctid/identification/two_stage.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/simulate.h"
#include "internal/two_stage_stages.h"

namespace ctid {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// Poles of g besides the origin's (integrators), one of each complex pair.
std::vector<std::complex<double>> upper_poles(const TransferFunction& g) {
  std::vector<std::complex<double>> out;
  const Eigen::VectorXcd poles = g.poles();
  for (Eigen::Index i = 0; i < poles.size(); ++i) {
    const std::complex<double> s = poles(i);
    if (std::abs(s) == 0.0) continue;
    if (s.imag() > 1e-9 * std::abs(s)) out.push_back(s);
  }
  return out;
}

double variance_about_mean(const Eigen::VectorXd& x) {
  return (x.array() - x.mean()).square().mean();
}

// Submodels inner[i..] matched one to one with unused submodels of outer, each inner one to an
// outer one with as many poles and zeros and the same integrators.
bool match_submodels(const std::vector<SubmodelOrder>& outer,
                     const std::vector<SubmodelOrder>& inner, std::size_t i,
                     std::vector<bool>& used) {
  if (i == inner.size()) return true;
  for (std::size_t j = 0; j < outer.size(); ++j) {
    if (used[j] || outer[j].integrators != inner[i].integrators || outer[j].n < inner[i].n ||
        outer[j].m < inner[i].m) {
      continue;
    }
    used[j] = true;
    if (match_submodels(outer, inner, i + 1, used)) return true;
    used[j] = false;
  }
  return false;
}

// True when every model of `inner` is a model of `outer` or a limit of them: the same kind, and
// each submodel of inner has its own submodel of outer with at least as many poles and zeros
// and the same integrators (the extra leading coefficients of A and B at zero, outer's other
// submodels at zero gain). The fit of `outer` then has at least as small an output error on
// the estimation data at its optimum.
bool contains(const ModelStructure& outer, const ModelStructure& inner) {
  if (outer.kind != inner.kind || outer.orders.size() < inner.orders.size()) return false;
  std::vector<bool> used(outer.orders.size(), false);
  return match_submodels(outer.orders, inner.orders, 0, used);
}

std::string describe(const ModelStructure& structure) {
  std::string out = structure.is_additive() ? "the submodels (n, m, l) = " : "(n, m, l) = ";
  for (std::size_t i = 0; i < structure.orders.size(); ++i) {
    const SubmodelOrder& o = structure.orders[i];
    out += (i > 0 ? ", (" : "(") + std::to_string(o.n) + ", " + std::to_string(o.m) + ", " +
           std::to_string(o.integrators) + ")";
  }
  return out;
}

// Where the record is split: the first `fitted` samples are fitted, the last `held_out` scored.
struct ScanSplit {
  int fitted = 0;
  int held_out = 0;
};

ScanSplit split_for_scan(int total, double validation_fraction) {
  const int held_out = static_cast<int>(std::floor(validation_fraction * total));
  const int fitted = total - held_out;
  require(fitted >= 8, "scan_structures: too few samples: ", fitted,
          " samples remain for estimation after holding out validation_fraction = ",
          validation_fraction, " of ", total);
  require(validation_fraction == 0.0 || held_out >= 8,
          "scan_structures: too few samples: validation_fraction = ", validation_fraction, " of ",
          total, " samples holds out ", held_out, "; at least 8 are needed");
  return {fitted, held_out};
}

// The model's output over the whole record from its first sample: from rest, or, when the
// fits estimate initial conditions, from the state fitted on the estimation part alone, so
// the held-out part is still a prediction.
Eigen::VectorXd scan_simulation(const AdditiveModel& model, const SampledData& data, int fitted,
                                const StructureScanOptions& options) {
  if (options.identification.refined_iv.initial_conditions == InitialConditions::estimate) {
    ValidationOptions from_state;
    from_state.initial_state = InitialState::estimate;
    from_state.window_start = data.start_time();
    from_state.window_end = data.start_time() + (fitted - 1) * data.sample_time();
    return validation_output(model, data, from_state);
  }
  // A digital loop: the model's output from r through the known controller, as a closed-loop
  // fit is judged (decision 0028); NaN where the model does not stabilise the loop.
  if (const std::optional<DiscreteTransferFunction>& c = options.identification.controller) {
    const StateSpace plant = zoh_equivalent(model, data.sample_time());
    if (!digital_loop_is_stable(plant, *c)) {
      return Eigen::VectorXd::Constant(data.size(), std::numeric_limits<double>::quiet_NaN());
    }
    return simulate_closed_loop(plant, *c, data.reference()).output;
  }
  // An analog loop's plant input is not held and its plant may be unstable: the model's output
  // from r through the loop, which its fit is judged by (decision 0067).
  if (const std::optional<TransferFunction>& c = options.identification.continuous_controller) {
    const TransferFunction g = model.to_transfer_function();
    if (!analog_loop_is_stable(g, *c)) {
      return Eigen::VectorXd::Constant(data.size(), std::numeric_limits<double>::quiet_NaN());
    }
    return simulate_closed_loop(g, *c, data.reference(), data.sample_time(), Eigen::VectorXd(),
                                data.input_hold())
        .output;
  }
  return model_output(model, data.input(), data.sample_time(), data.input_hold());
}

// With the two-stage method, stage 1 fitted once on the estimation part, as identify fits it
// there; every candidate's stage 2 starts from it (decision 0071).
std::optional<internal::StageOne> scan_stage_one(const SampledData& estimation,
                                                 const StructureScanOptions& options) {
  const std::optional<TwoStageOptions>& two_stage = options.identification.two_stage;
  if (!two_stage) return std::nullopt;
  return internal::fit_stage_one(std::span<const SampledData>(&estimation, 1), *two_stage);
}

// A candidate's identification on the estimation part: identify itself, or with the two-stage
// method the checks and stage 2 of identify's two-stage path, from the scan's stage 1.
IdentificationResult identify_candidate(const SampledData& estimation,
                                        const std::optional<internal::StageOne>& stage_one,
                                        const ModelStructure& structure,
                                        const IdentificationOptions& options) {
  if (!stage_one) return identify(estimation, structure, options);
  validate_identification(structure, options);
  return internal::identify_from_stage_one(*stage_one, structure, options, {});
}

// The record the candidates are scored on: the data itself, or with the two-stage method the
// data with u replaced by u_hat = S_hat r over the whole record, S_hat stage 1's model
// (decision 0071). Stage 2 fits from u_hat, and the measured u carries the noise fed back, so
// y - G u would misjudge the candidates as it does with a known controller (decision 0070).
SampledData scoring_record(const SampledData& data,
                           const std::optional<internal::StageOne>& stage_one) {
  if (!stage_one) return data;
  return SampledData(data.sample_time(),
                     sensitivity_output(stage_one->fits.front(), data.reference()), data.output(),
                     data.reference(), data.start_time())
      .with_input_hold(data.input_hold());
}

// The scores of a fit (fit percentages, held-out error, RT2, AIC, BIC, YIC); returns the mean
// squared output error on the estimation part.
double score_fit(StructureFit& fit, const EstimationResult& e, const SampledData& data,
                 const Eigen::VectorXd& simulated, ScanSplit split) {
  const int fitted = split.fitted;
  const int held_out = split.held_out;
  const Eigen::VectorXd y_est = data.output().head(fitted);
  const Eigen::VectorXd e_est = y_est - simulated.head(fitted);
  fit.estimation_fit = fit_percent(y_est, simulated.head(fitted));
  fit.validation_fit = held_out > 0
                           ? fit_percent(data.output().tail(held_out), simulated.tail(held_out))
                           : fit.estimation_fit;
  fit.validation_error =
      held_out > 0
          ? (data.output().tail(held_out) - simulated.tail(held_out)).squaredNorm() / held_out
          : e_est.squaredNorm() / fitted;
  const double error_variance = e_est.squaredNorm() / fitted;
  const double output_variance = variance_about_mean(y_est);
  fit.rt2 = 1.0 - error_variance / output_variance;
  fit.aic = fitted * std::log(error_variance) + 2.0 * fit.parameters;
  fit.bic = fitted * std::log(error_variance) + fit.parameters * std::log(double(fitted));
  if (e.covariance.rows() == fit.parameters && fit.parameters > 0) {
    double relative = 0.0;
    for (int i = 0; i < fit.parameters; ++i) {
      relative += e.covariance(i, i) / (e.parameters(i) * e.parameters(i));
    }
    fit.yic = std::log(error_variance / output_variance) + std::log(relative / fit.parameters);
  }
  return error_variance;
}

// One candidate fitted on the estimation part and scored; `estimation_error` receives its mean
// squared output error on that part (NaN when the fit failed).
StructureFit fit_candidate(const SampledData& data, const SampledData& estimation,
                           const std::optional<internal::StageOne>& stage_one,
                           const ModelStructure& structure, const StructureScanOptions& options,
                           ScanSplit split, double& estimation_error) {
  StructureFit fit;
  fit.structure = structure;
  fit.yic = fit.rt2 = fit.aic = fit.bic = kNan;
  fit.estimation_fit = fit.validation_fit = fit.validation_error = kNan;
  try {
    const IdentificationResult r =
        identify_candidate(estimation, stage_one, structure, options.identification);
    const EstimationResult& e = r.estimate;
    fit.parameters = static_cast<int>(e.parameters.size());
    static_cast<Outcome&>(fit) = e;
    fit.message = e.brief_report();  // the one-line report, not the bare message
    fit.transfer_function = e.transfer_function;
    const Eigen::VectorXd simulated = scan_simulation(e.model, data, split.fitted, options);
    estimation_error = score_fit(fit, e, data, simulated, split);
    // The verdict already asks for finite parameters and stable poles (integrators aside).
    fit.usable = e.verdict.usable && std::isfinite(fit.validation_fit) &&
                 std::isfinite(fit.estimation_fit) && std::isfinite(fit.validation_error);
    fit.reasons = e.verdict.reasons;
  } catch (const InvalidArgument& error) {
    fit.message = error.what();
    fit.usable = false;
  }
  return fit;
}

// The usable fit j < i in parameters whose structure fit i contains and whose `error` is the
// lowest among those that fit i's exceeds by more than the noise's tolerance; none if none.
std::optional<std::size_t> contained_better_fit(const std::vector<StructureFit>& fits,
                                                const std::vector<bool>& usable_fit,
                                                const std::vector<double>& error, std::size_t i,
                                                double noise_tolerance) {
  std::optional<std::size_t> better;
  for (std::size_t j = 0; j < fits.size(); ++j) {
    if (j == i || !usable_fit[j] || fits[j].parameters >= fits[i].parameters ||
        !contains(fits[i].structure, fits[j].structure) ||
        !(error[i] > (1.0 + noise_tolerance) * error[j])) {
      continue;
    }
    if (!better || error[j] < error[*better]) better = j;
  }
  return better;
}

// A fit that matches the estimation data worse than a usable fit of a structure it contains
// stopped short of its optimum (at its optimum it fits at least as well): not usable
// (decision 0016). The refined IV optimum is not exactly the least output error one, so
// "worse" is beyond the noise's tolerance, whatever error_tolerance the parsimony uses. And a
// fit that predicts the held-out data worse, beyond the same tolerance, than a usable fit of a
// structure it contains is over-fitted: its extra parameters model the estimation record's
// noise (decision 0016).
void judge_against_contained(std::vector<StructureFit>& fits,
                             const std::vector<double>& estimation_error, double noise_tolerance,
                             int held_out) {
  std::vector<bool> usable_fit;
  std::vector<double> validation_error;
  for (const StructureFit& fit : fits) {
    usable_fit.push_back(fit.usable);
    validation_error.push_back(fit.validation_error);
  }
  for (std::size_t i = 0; i < fits.size(); ++i) {
    StructureFit& fit = fits[i];
    if (!usable_fit[i]) continue;
    const std::optional<std::size_t> better =
        contained_better_fit(fits, usable_fit, estimation_error, i, noise_tolerance);
    if (better) {
      fit.usable = false;
      fit.reasons.push_back("its estimation error " + format_significant(estimation_error[i], 4) +
                            " is larger than that of a structure it contains, " +
                            describe(fits[*better].structure) + " (" +
                            format_significant(estimation_error[*better], 4) +
                            "): the fit stopped short of its optimum");
      continue;
    }
    if (held_out == 0) continue;
    const std::optional<std::size_t> simpler =
        contained_better_fit(fits, usable_fit, validation_error, i, noise_tolerance);
    if (!simpler) continue;
    fit.usable = false;
    fit.reasons.push_back(
        "its held-out error " + format_significant(fit.validation_error, 4) +
        " is larger than that of a structure it contains, " + describe(fits[*simpler].structure) +
        " (" + format_significant(fits[*simpler].validation_error, 4) + "): over-fitted");
  }
}

// Recommendation: parsimony within `tolerance` of the best usable held-out error (ties: lower
// YIC), with the sentence that says why.
void recommend(StructureScanResult& result, double tolerance) {
  double best = std::numeric_limits<double>::infinity();
  double best_fit = kNan;
  for (const StructureFit& fit : result.fits) {
    if (fit.usable && fit.validation_error < best) {
      best = fit.validation_error;
      best_fit = fit.validation_fit;
    }
  }
  for (std::size_t i = 0; i < result.fits.size(); ++i) {
    const StructureFit& fit = result.fits[i];
    if (!fit.usable || !(fit.validation_error <= best * (1.0 + tolerance))) continue;
    if (result.recommended < 0) {
      result.recommended = static_cast<int>(i);
      continue;
    }
    const StructureFit& kept = result.fits[static_cast<std::size_t>(result.recommended)];
    const bool fewer = fit.parameters < kept.parameters;
    const bool tie_better_yic = fit.parameters == kept.parameters && fit.yic < kept.yic;
    if (fewer || tie_better_yic) result.recommended = static_cast<int>(i);
  }
  const std::string where = result.validation_samples > 0 ? "held-out" : "estimation";
  if (result.recommended < 0) {
    result.rule = "no candidate gave a usable fit";
  } else {
    result.rule = "fewest parameters among the usable fits whose " + where + " error is within " +
                  format_significant(100.0 * tolerance, 2) + " % of the best (fit " +
                  format_significant(best_fit, 4) + " %)";
  }
}

// Stabilisation diagram: the pole pairs of each fit, each against the fit before it in the list.
std::vector<StabilisationPoint> stabilisation_diagram(const std::vector<StructureFit>& fits,
                                                      const StructureScanOptions& options) {
  std::vector<StabilisationPoint> points;
  std::vector<std::vector<std::complex<double>>> poles;
  for (const StructureFit& fit : fits) poles.push_back(upper_poles(fit.transfer_function));
  for (std::size_t i = 0; i < fits.size(); ++i) {
    const std::vector<std::complex<double>> none;
    const std::vector<std::complex<double>>& previous = i == 0 ? none : poles[i - 1];
    int order = 0;  // poles besides integrators
    for (const SubmodelOrder& o : fits[i].structure.orders) order += o.n;
    for (const std::complex<double>& s : poles[i]) {
      StabilisationPoint point;
      point.fit = static_cast<int>(i);
      point.order = order;
      point.frequency = std::abs(s);
      point.damping_ratio = -s.real() / std::abs(s);
      point.stable_pole = s.real() < 0.0;
      for (const std::complex<double>& q : previous) {
        const double w = std::abs(q);
        const double zeta = -q.real() / w;
        if (std::abs(point.frequency - w) <= options.frequency_tolerance * w) {
          point.stable_frequency = true;
          if (std::abs(point.damping_ratio - zeta) <= options.damping_tolerance * std::abs(zeta)) {
            point.stable_damping = true;
          }
        }
      }
      points.push_back(point);
    }
  }
  return points;
}

}  // namespace

StructureScanResult scan_structures(const SampledData& data,
                                    const std::vector<ModelStructure>& candidates,
                                    const StructureScanOptions& options,
                                    const std::function<void(int, int)>& progress) {
  options.validate();
  require(!candidates.empty(), "scan_structures: no candidate structure given");
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    candidates[i].validate();
  }
  const ScanSplit split = split_for_scan(data.size(), options.validation_fraction);
  const SampledData estimation = data.segment(0, split.fitted);
  const std::optional<internal::StageOne> stage_one = scan_stage_one(estimation, options);
  const SampledData scored = scoring_record(data, stage_one);

  StructureScanResult result;
  result.estimation_samples = split.fitted;
  result.validation_samples = split.held_out;
  // Mean squared output error on the estimation part, per candidate.
  std::vector<double> estimation_error(candidates.size(), kNan);
  // The candidates are fitted in parallel (core/parallel.h), each into its own slot, so the
  // table is the serial one whatever the number of threads.
  result.fits.resize(candidates.size());
  std::mutex progress_mutex;
  int done = 0;
  parallel_for(static_cast<int>(candidates.size()), 0, [&](int index) {
    const auto slot = static_cast<std::size_t>(index);
    result.fits[slot] = fit_candidate(scored, estimation, stage_one, candidates[slot], options,
                                      split, estimation_error[slot]);
    if (progress) {
      const std::lock_guard<std::mutex> lock(progress_mutex);
      progress(++done, static_cast<int>(candidates.size()));
    }
  });

  const int scored_samples = split.held_out > 0 ? split.held_out : split.fitted;
  const double noise_tolerance = 2.0 * std::sqrt(2.0 / scored_samples);
  judge_against_contained(result.fits, estimation_error, noise_tolerance, split.held_out);
  recommend(result, options.error_tolerance.value_or(noise_tolerance));
  result.stabilisation = stabilisation_diagram(result.fits, options);
  return result;
}

}  // namespace ctid
