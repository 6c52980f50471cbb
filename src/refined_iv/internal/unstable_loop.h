// What the closed-loop fits of a plant that may be unstable share (decisions 0038 and 0067):
// their starts (the open-loop starts of initialization.h, with roots moved between the
// half-planes and gains scaled until the known controller stabilises them) and their verdict
// (judged by the fit from r). Private to the estimation layer; shared by unstable_clsrivc (a
// discrete controller) and clsrivc_continuous (a continuous-time one).
#pragma once

#include <functional>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/sampled_data.h"
#include "ctid/core/transfer_function.h"
#include "ctid/refined_iv/estimation_result.h"

namespace ctid::internal {

/// g as one submodel B / (p^l A), A anti-monic.
AdditiveModel loop_start_submodel(const TransferFunction& g);

/// The open-loop start on the input's part that r explains: an open-loop SRIVC fit of r -> u
/// of order loop_order (biproper), simulated from r, free of the noise fed back, then
/// initial_transfer_function on it. None when the record is too short or too poorly excited
/// for that first fit.
std::optional<AdditiveModel> explained_input_start(const SampledData& data,
                                                   const SubmodelOrder& order, int loop_order);

/// The closed-loop fit from r of the model with parameters theta = [a_1..a_n, b_0..b_m], or
/// none when the controller does not stabilise it.
using LoopFit = std::function<std::optional<double>(const Eigen::VectorXd& theta)>;

/// Each base with every combination of its real roots and complex pairs moved to the other
/// half-plane (numerator kept: the static gain and |G(jw)| stay), its gain as it is or else
/// the nearest power of two `fit` stabilises; of those stabilised, the `keep` with the best
/// fit, best first. Empty when none is stabilised.
std::vector<AdditiveModel> stabilised_starts(const std::vector<AdditiveModel>& bases,
                                             const SubmodelOrder& order, const LoopFit& fit,
                                             int keep);

/// `fit` run from each start (at least one), keeping the usable result with the best
/// closed-loop fit from r (an unusable one only if none is usable), its message saying how
/// many starts were tried.
EstimationResult best_loop_fit(const std::vector<AdditiveModel>& starts,
                               const std::function<EstimationResult(const AdditiveModel&)>& fit);

/// The verdict of a closed-loop fit judged by its fit from r (result.closed_loop_fit_percent
/// against start_closed_loop_fit_percent): failed when `loop_stable` is false (the known
/// controller does not stabilise the fitted model); then the cancellation, standard-error and
/// conditioning checks. An unstable plant is not a finding: the loop around it ran.
Verdict unstable_loop_verdict(const EstimationResult& result, bool loop_stable);

}  // namespace ctid::internal
