// The one iteration behind SRIVC, CLSRIVC and the additive estimators: eq. (29) of
// González et al. with K = 1 giving eq. (30). Private to the estimation layer.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/core/sampled_data.h"
#include "ctid/frequency/frf.h"
#include "ctid/refined_iv/estimation_result.h"
#include "ctid/refined_iv/initialization.h"
#include "ctid/refined_iv/refined_iv.h"
#include "ctid/refined_iv/refined_iv_options.h"

namespace ctid::internal {

// The problem is public (ctid/refined_iv/refined_iv.h); the engine keeps its old name for it.
using RefinedIvProblem = ::ctid::RefinedIvProblem;

/// The unfactored start screened from the data (initial_transfer_function), kept for another
/// run on the same records with the same start options and total order (an additive and an
/// unfactored fit from one start method).
struct ScreenedStart {
  std::optional<TransferFunction> g;
};

/// The refined IV iteration from options.initial_model or, without one, from the start
/// initialization.h finds in the data; `shared`, when given, is screened here and stored only
/// when it holds no start yet. As a value (decision 0050): none, with the reason in
/// `failure` if given, when no start can be formed (no candidate in the data, a start whose
/// poles do not group into the submodels, a degenerate start). A degenerate iterate ends the
/// run as Termination::non_finite with the last finite iterate and a failed verdict. Bad input
/// (records, structure, options) throws InvalidArgument.
std::optional<EstimationResult> run_refined_iv_if_started(const RefinedIvProblem& problem,
                                                          const RefinedIvOptions& options,
                                                          ScreenedStart* shared = nullptr,
                                                          std::string* failure = nullptr);
/// run_refined_iv_if_started with a start that cannot be formed thrown as InvalidArgument.
EstimationResult run_refined_iv_from_start(const RefinedIvProblem& problem,
                                           const RefinedIvOptions& options,
                                           ScreenedStart* shared = nullptr);
/// run_refined_iv_from_start, except for an additive model in closed loop without an initial
/// model: the iteration then runs from several starts and keeps the usable estimate with the
/// best output-error fit (decision 0028).
EstimationResult run_refined_iv(const RefinedIvProblem& problem, const RefinedIvOptions& options);

/// The homogeneous chain 1/(p^l A) -> p^k/A (k = 1..n) behind a submodel's free responses
/// (InitialConditions::estimate, docs/decisions/0010): the transition matrix phi of one sample,
/// the row c0 reading 1/(p^l A) from the chain's state and the rows ck reading p^k/A of it. The
/// free response of 1/(p^l A) from its state x0 (the second stage at rest) at sample k is
/// c0 phi^k [x0; 0], and ck phi^k [x0; 0] its filtered p^k/A, exact at the samples.
struct FreeResponseChain {
  Eigen::MatrixXd phi;
  Eigen::RowVectorXd c0;
  Eigen::MatrixXd ck;
};
FreeResponseChain free_response_chain(const Polynomial& a, int integrators, double h);

/// Assumption 1's persistency check: sets checks.persistently_exciting from excitation_order
/// and excitation_order_required, and warns that `signal` ("input", "reference") excites too
/// little for consistency when it is below.
void note_excitation(DataChecks& checks, const std::string& signal);
/// Assumption 4 on an estimate: its fastest pole against pi / step (`limit`, e.g. "the
/// Nyquist frequency", names that bound in the warning when the pole is not below it).
void note_sampling_rate(DataChecks& checks, const AdditiveModel& model, double step,
                        const std::string& limit);

/// Parameters of `model` laid out for `orders` (b padded with zeros up to m_i); throws
/// InvalidArgument if the structure does not fit.
Eigen::VectorXd parameters_for_orders(const AdditiveModel& model,
                                      const std::vector<SubmodelOrder>& orders);

/// The single-submodel parameterisation of an unfactored transfer function B/(p^l A).
Eigen::VectorXd unfactored_parameters(const TransferFunction& g, const SubmodelOrder& order);

/// Anti-monic polynomial with the right-half-plane roots of `a` mirrored; `reflected` tells
/// whether anything changed.
Polynomial reflect_unstable_roots(const Polynomial& a, bool& reflected);
/// reflect_unstable_roots as a value (decision 0045): none, with the reason in `failure` if
/// given, when the mirrored roots make no anti-monic polynomial (a root that is not finite,
/// coefficients that overflow: a degenerate A that lost its leading coefficient).
std::optional<Polynomial> reflect_unstable_roots_if_finite(const Polynomial& a, bool& reflected,
                                                           std::string* failure = nullptr);

/// The start formations of initialization.h as values (decision 0045), for the start screen
/// that steers on whether a candidate exists:
/// - lssvf, or none when its parameters are not finite or its filter has no finite
///   realisation (a bandwidth that gives a degenerate start);
/// - mode_from_peak, or none when the peak gives no finite mode (a peak at frequency 0);
/// - frf_peak_start, or none when the FRF has too few peaks (failure left as it is) or its
///   peaks give no finite start or do not fit the order (the reason in `failure` if given).
std::optional<TransferFunction> lssvf_if_finite(const SampledData& data, const SubmodelOrder& order,
                                                double bandwidth, int input_delay);
std::optional<Polynomial> mode_from_peak_if_finite(const ResonancePeak& peak);
std::optional<TransferFunction> frf_peak_start_if_formed(const SampledData& data,
                                                         const SubmodelOrder& order,
                                                         int input_delay,
                                                         std::string* failure = nullptr);

/// initial_transfer_function and additive_model_from_start as values (decision 0050): none,
/// with the reason they throw in `failure` if given, when no candidate start can be formed
/// (too few resonance peaks for the FRF start, no finite candidate) or the start's poles do
/// not group into the submodels. Bad options still throw InvalidArgument.
std::optional<TransferFunction> initial_transfer_function_if_formed(
    const SampledData& record, const SubmodelOrder& order, const InitializationOptions& options,
    std::string* failure = nullptr);
std::optional<AdditiveModel> additive_model_from_start_if_formed(
    const TransferFunction& g, const SampledData& record, const std::vector<SubmodelOrder>& orders,
    const InitializationOptions& options, std::string* failure = nullptr);

/// group_into_submodels as a value (decision 0045): none, with the reason it throws in
/// `failure` if given, when g's poles do not fit the structure (the counts differ: a start whose
/// A lost its leading coefficient) or make no finite denominators or filters. Throws
/// InvalidArgument, as group_into_submodels does, for a structure that is not an additive
/// model's (empty, more than one biproper submodel or submodel with integrators, ...).
std::optional<AdditiveModel> grouped_submodels(const TransferFunction& g,
                                               const std::vector<SubmodelOrder>& orders,
                                               const SampledData& data, int input_delay,
                                               std::string* failure = nullptr);

/// Whether `controller` stabilises the sampled loop with the model `beta` (laid out for
/// `orders`, ZOH with `input_delay` samples): every closed-loop pole inside the unit circle and
/// the loop well posed. The same test that decides whether S_uo r (instrument (20)) can be
/// formed, so a start that passes it does not stop CLSRIVC at iteration 0.
bool controller_stabilises(const std::vector<SubmodelOrder>& orders, const Eigen::VectorXd& beta,
                           const DiscreteTransferFunction& controller, double h, int input_delay);

}  // namespace ctid::internal
