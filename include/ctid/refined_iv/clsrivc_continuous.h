// CLSRIVC with a known continuous-time controller (issue 37, docs/decisions/0067): the loop
// u = C(p)(r - y) is analog, C = N_c / D_c, and only the reference r is held between the
// samples (as the data's input hold says). The plant input u is then not piecewise constant,
// so the plant-side equation A y = B u cannot be filtered exactly from samples; the loop's
// equation can. With the plant G = B / (p^l A) and the closed-loop denominator
// A_cl = p^l A D_c + B N_c, A_cl y = B N_c r, i.e.
//   p^l D_c y = -sum_i a_i p^(l+i) D_c y + sum_j b_j p^j N_c (r - y),
// linear in theta = [a_1..a_n, b_0..b_m]. Filtered by 1/A_cl of the current iterate (stable
// whenever the controller stabilises it, even for an unstable or non-minimum-phase plant), every
// term is a combination of one bank p^k / A_cl on y and on r, so the y-terms add up to y at the
// samples whatever the interpolation of y (ESTIMATOR-NOTES): noise-free data give the plant to
// rounding. The instrument is the same regressor with y replaced by the model's output x from
// r, x = B N_c / A_cl r: the gradient of the closed-loop output error y - x, so the fixed point
// is that criterion's stationary point, and its covariance the sandwich of refined_iv's
// covariance.h with the residual y - x.
#pragma once

#include <optional>
#include <string>

#include "ctid/core/additive_model.h"
#include "ctid/core/sampled_data.h"
#include "ctid/core/transfer_function.h"
#include "ctid/refined_iv/estimation_result.h"
#include "ctid/refined_iv/refined_iv_options.h"

namespace ctid {

/// The estimate of one unfactored model B / (p^l A) from closed-loop data with a reference,
/// with the known continuous-time controller, from options.initial_model or, without one,
/// from the open-loop starts of initialization.h with their roots moved between the
/// half-planes until the controller stabilises them (the usable fit with the best fit from r
/// kept). fit_percent and closed_loop_fit_percent are both the fit of the model's output from
/// r through the controller. Uses options.max_iterations, tolerance, max_step_halvings,
/// output_interpolation, compute_covariance, noise and initial_model. Throws InvalidArgument
/// for bad input (clsrivc_continuous_refusal); a numerical failure is the termination and
/// the verdict.
EstimationResult clsrivc_continuous(const SampledData& data, const TransferFunction& controller,
                                    const SubmodelOrder& order,
                                    const RefinedIvOptions& options = {});

/// Why clsrivc_continuous refuses its arguments, or none: no reference, a controller that is
/// improper, has a delay or a non-finite coefficient, n + integrators < 1 or m outside
/// 0..n + integrators, an input delay, a noise model, estimated initial conditions, too few
/// samples for the parameters, a reference not persistently exciting of the parameters' count. Bad
/// options still throw (RefinedIvOptions::validate).
std::optional<std::string> clsrivc_continuous_refusal(const SampledData& data,
                                                      const TransferFunction& controller,
                                                      const SubmodelOrder& order,
                                                      const RefinedIvOptions& options = {});

}  // namespace ctid
