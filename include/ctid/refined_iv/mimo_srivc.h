// Open-loop refined IV for several inputs and outputs with poles shared by every channel
// (issue 13): the additive iteration (29) of González et al. generalised to
// y_j = sum_i sum_k R_i[j, k](p) / A_i(p) u_k + v_j. Each output j contributes the equations
// of (28) with its own residuals y~_ij = y_j - sum_{l != i} G_l,j u; the denominators' rows
// are summed over the outputs and every numerator has its own rows. The numerator regressors
// p^r / A_l u_k are the same for every output, so they are projected out once per iteration
// (one QR factorisation) and the denominators come from the small projected system; each
// output's numerators follow by back-substitution. One output and one input give the
// equations of (29) exactly. See docs/decisions/0018-mimo-shared-poles.md.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/fields.h"
#include "ctid/core/hold.h"
#include "ctid/core/mimo_data.h"
#include "ctid/core/mimo_model.h"
#include "ctid/estimation/mimo_modes.h"
#include "ctid/estimation/termination.h"
#include "ctid/estimation/verdict.h"
#include "ctid/refined_iv/refined_iv_options.h"

namespace ctid {

struct MimoRefinedIvOptions {
  /// Upper bound on the iterations. >= 1.
  int max_iterations = 100;
  /// Stop when ||beta_{j+1} - beta_j|| / ||beta_j|| < tolerance. In (0, 1).
  double tolerance = 1e-10;
  /// Interpolation of the measured outputs between samples before filtering.
  Hold output_interpolation = Hold::first_order_hold;
  /// Estimate a direct term D (outputs x inputs) besides the strictly proper or biproper
  /// submodels: G = sum_i R_i / A_i + D (e.g. accelerations from forces with m_i < n_i).
  bool direct_term = false;
  /// Compute the covariance and the modes' standard errors.
  bool compute_covariance = true;
  /// Noise on each output for the covariance: white, or coloured (an AR model of each
  /// output's residual, order <= noise_model_max_order by AIC); outputs independent.
  NoiseAssumption noise = NoiseAssumption::coloured;
  int noise_model_max_order = 20;
  /// One input, one output and no direct term: run the SISO additive estimator
  /// (additive_srivc, its own start), so the result equals its result bit for bit. false runs
  /// the shared-pole iteration on the single channel instead (same stationary point).
  bool siso_engine = true;
  /// Known delay of every input in samples (whole and fractional, each >= 0; the filters see
  /// input k delayed exactly by input_delays_samples[k] h, held as the record's input hold says),
  /// or empty for none. The model's input_delays() are these times h.
  std::vector<double> input_delays_samples;
  /// Restrict each mode's residue matrix to rank one, Res_i = psi_i L_i^T (one shape, one
  /// participation vector): with the iteration's poles fixed, the numerators are refitted by
  /// alternating least squares. Standard errors stay those of the general residues
  /// (docs/decisions/0018).
  bool rank_one_residues = false;
  /// State at the first sample, as RefinedIvOptions::initial_conditions: `estimate` adds the
  /// free response of every submodel at every output (n_i + l_i coefficients each, the same
  /// columns for every output) to the regressor and the instrument, so that records which
  /// start mid-motion are not biased (docs/decisions/0010, 0026).
  InitialConditions initial_conditions = InitialConditions::zero;

  static constexpr std::string_view type_name = "MimoRefinedIvOptions";
  static constexpr auto fields() {
    using O = MimoRefinedIvOptions;
    return std::tuple{
        field("max_iterations", &O::max_iterations, AtLeast{1}, "Upper bound on the iterations."),
        field("tolerance", &O::tolerance, Between{0.0, 1.0},
              "Relative parameter change that stops the iteration."),
        field("output_interpolation", &O::output_interpolation,
              "Interpolation of the measured outputs before filtering.")
            .with_flag("interpolation"),
        field("direct_term", &O::direct_term, "Estimate a direct term D as well.")
            .with_flag("direct"),
        field("compute_covariance", &O::compute_covariance,
              "Compute the covariance and the modes' standard errors."),
        field("noise", &O::noise, "Noise assumption of the covariance (per output)."),
        field("noise_model_max_order", &O::noise_model_max_order, AtLeast{1},
              "Largest AR order of each output's noise model."),
        field("siso_engine", &O::siso_engine,
              "One input and output, no direct term: run additive_srivc (bit-identical)."),
        field("input_delays_samples", &O::input_delays_samples, Each{Finite{AtLeast{0.0}}},
              "Known delay of every input [samples, may be fractional]; empty: none."),
        field("rank_one_residues", &O::rank_one_residues,
              "Restrict every mode's residue matrix to rank one (shape x participation).")
            .with_flag("rank-one"),
        field("initial_conditions", &O::initial_conditions,
              "State at the first sample: zero, or each output's free responses estimated."),
    };
  }
  void validate() const { validate_fields(*this); }
};

/// Derives termination, message and iterations from Outcome.
struct MimoEstimationResult : Outcome {
  /// The estimate: the fixed point when the iteration converged, else the iterate with the
  /// lowest output error (none if nothing was computed).
  std::optional<MimoAdditiveModel> model;
  /// Steps halved toward the last accepted iterate because the equations at the new one could
  /// not be formed or solved (numerator regressors collinear, singular denominators' system).
  int step_halvings = 0;
  /// Per output: mean squared output error y_j - G_j u and fit_percent on the data.
  Eigen::VectorXd mean_squared_errors;
  Eigen::VectorXd fit_percent;
  /// Finite, stable, no output fitted worse than its mean, well-conditioned equations, and
  /// no mode whose natural frequency or damping ratio has a standard error above its value.
  Verdict verdict;
  /// Covariance of the parameters [a of every submodel; then per output j the numerator
  /// coefficients (submodel, input, power) and D[j, .]]; empty unless computed.
  Eigen::MatrixXd covariance;
  /// Every second-order submodel as a mode, in submodel order.
  std::vector<MimoMode> modes;
  /// MimoRefinedIvOptions::initial_conditions = estimate: per output (column), per submodel,
  /// the value and first n_i + l_i - 1 derivatives at the first sample of its estimated free
  /// response; empty otherwise.
  Eigen::MatrixXd initial_conditions;

  static constexpr std::string_view type_name = "MimoEstimationResult";
  static constexpr auto fields() {
    using S = MimoEstimationResult;
    return join_fields(
        Outcome::fields(),
        std::tuple{
            field("model", &S::model,
                  "The estimate: the fixed point, or the iterate with the lowest output error."),
            field("step_halvings", &S::step_halvings, "Steps halved toward the last accepted one."),
            field("mean_squared_errors", &S::mean_squared_errors,
                  "Per output: mean squared output error."),
            field("fit_percent", &S::fit_percent, "Per output: fit_percent on the data."),
            field("verdict", &S::verdict, "Whether the model is usable, and why not."),
            field("covariance", &S::covariance,
                  "Covariance of [a of every submodel; per output its numerators and D]."),
            field("modes", &S::modes, "MimoMode of every second-order submodel."),
            field("initial_conditions", &S::initial_conditions,
                  "Per output, per submodel: estimated free response and derivatives at t_0."),
        });
  }
};

/// Estimates the shared denominators and every numerator of `orders` (n_i >= 1, m_i, no
/// integrators) from open-loop data, starting from `initial_model` (its orders must match) or,
/// without one, from the best of a common-denominator least-squares fit over every channel
/// at a grid of state-variable-filter bandwidths (poles grouped into the submodels, numerators
/// by least squares). Throws InvalidArgument for bad options,
/// orders, start or too few samples; the outcome of the iteration is in the result.
/// `progress`, if given, is called with (iteration, options.max_iterations) as each iteration
/// of (29) starts (not on the single-channel SISO path), for a progress line.
MimoEstimationResult mimo_srivc(const MimoData& data, const std::vector<SubmodelOrder>& orders,
                                const MimoRefinedIvOptions& options = {},
                                const std::optional<MimoAdditiveModel>& initial_model = {},
                                const std::function<void(int, int)>& progress = {});

}  // namespace ctid
