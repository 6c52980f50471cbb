// CLSRIVC for a plant that may be unstable (or marginally stable, or non-minimum-phase) inside
// a stable loop (issue 37, docs/decisions/0038-closed-loop-unstable-plants.md). The loop is
// u_k = C_d(q)(r_k - y_k) with a known discrete controller and a measured reference r.
//
// The refined IV engine (clsrivc()) filters with 1/A of the current model and reflects every
// iterate's right-half-plane roots, so it cannot hold an unstable plant: from the true model it
// reflects the unstable pole at once, and the loop it then models is not the recorded one.
// Here the iterate keeps its unstable roots; only the prefilter is stabilised:
//   - prefilter 1/A_f, A_f = A with its right-half-plane roots reflected (A_f = A when A is
//     stable, where the equations are CLSRIVC's);
//   - regression (A / A_f) y = B / (p^l A_f) u, regressor [-p^k/A_f y, p^j/(p^l A_f) u];
//   - instrument [-p^k/A_f x, p^j/(p^l A_f) u_r], u_r = S_uo r and x the model's output from r
//     through the known controller, both from one closed-loop recursion of the ZOH model with
//     the prefilter cascaded after it, so the unstable mode is never integrated open loop;
//   - y is interpolated between samples as x plus the linear interpolant of y - x: exact
//     whatever the interpolation when y = x (noise-free data at the true model), so noise-free
//     data give the plant to rounding.
// A step to a model the controller does not stabilise is halved toward the iterate; if no
// halved step is stabilised, the full step is taken with the last closed-loop pass reused
// (sensitivity_fallbacks), and the fit cannot converge or be usable until a loop is stable.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/core/sampled_data.h"
#include "ctid/refined_iv/estimation_result.h"
#include "ctid/refined_iv/refined_iv_options.h"

namespace ctid {

/// The estimate of one unfactored model B / (p^l A) from closed-loop data with a reference,
/// from options.initial_model or, without one, from each start in
/// unstable_clsrivc_starts() (the usable fit with the best closed-loop fit from r kept).
/// fit_percent and closed_loop_fit_percent are both the fit of the model's output from r
/// through the controller (an output G u with the measured u diverges for an unstable G).
/// Uses options.max_iterations, tolerance, max_step_halvings and initial_model; the input
/// delay must be 0. Throws InvalidArgument for bad input; a numerical failure is the
/// termination and the verdict.
EstimationResult unstable_clsrivc(const SampledData& data,
                                  const DiscreteTransferFunction& controller,
                                  const SubmodelOrder& order, const RefinedIvOptions& options = {});

/// Why unstable_clsrivc refuses `data`, `controller`, `order` and `options` (a noise model, no
/// reference, another sample time, n < 1 or m outside 0..n + integrators, an input delay, too
/// few samples), or none: its refusals of bad input as a value, before any work, for a caller
/// that tries it only where it applies. Bad options still throw (RefinedIvOptions::validate).
std::optional<std::string> unstable_clsrivc_refusal(const SampledData& data,
                                                    const DiscreteTransferFunction& controller,
                                                    const SubmodelOrder& order,
                                                    const RefinedIvOptions& options = {});

/// The starts tried without an initial model: the open-loop and the closed-loop start of
/// initialization.h (initial_transfer_function without and with the controller), each with
/// every combination of its real roots and complex pairs moved to the other half-plane; of
/// those the controller stabilises, the three with the best closed-loop fit from r (or, if
/// none is stabilised, the closed-loop start, whose fit then fails and says so).
std::vector<AdditiveModel> unstable_clsrivc_starts(const SampledData& data,
                                                   const DiscreteTransferFunction& controller,
                                                   const SubmodelOrder& order);

}  // namespace ctid
