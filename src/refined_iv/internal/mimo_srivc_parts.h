// The pieces of mimo_srivc (the shared-pole refined IV estimator of several inputs and
// outputs) that its files share: mimo_srivc.cc (the columns, the iteration and the estimate),
// mimo_srivc_start.cc (the start), mimo_srivc_modes.cc (covariance) and
// mimo_rank_one.cc (the rank-one residue refit). Private to refined_iv.
#pragma once

#include <complex>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ctid/filtering/filter_bank.h"
#include "ctid/refined_iv/mimo_srivc.h"
#include "estimation/internal/mimo_layout.h"
#include "estimation/internal/mimo_modes.h"

namespace ctid::mimo_srivc_parts {

using Layout = internal::MimoLayout;

// Submodel i's free responses at the denominator a_i (layout.free_count > 0): `basis`, those
// of 1/(p^l_i A_i) from each unit initial state (N x s_i, s_i = n_i + l_i), and, when asked,
// `filtered[q - 1]` = p^q / A_i of them (q = 1..n_i), exact at the samples by one homogeneous
// recursion of the chain the SISO estimators use (internal::free_response_chain).
struct FreeResponses {
  Eigen::MatrixXd basis;
  std::vector<Eigen::MatrixXd> filtered;
};

// An iterate: the model and, with free responses (layout.free_count > 0), the coefficients of
// every output's free-response columns (free_count x outputs; 0 x outputs without).
struct Iterate {
  MimoAdditiveModel model;
  Eigen::MatrixXd free;
};

// u S^-1 = Q R with S the columns' norms (column_scales), Q thin (N x columns): how the
// numerator columns, the same for every output, are projected out of each output's equations.
struct ScaledQr {
  Eigen::VectorXd scale;
  Eigen::MatrixXd q;
  Eigen::MatrixXd r;  // upper triangular
};

// How a run of the iteration ended: the model to return (the fixed point when it converged,
// else the iterate with the lowest output error, relative_output_error), and its account.
struct Iterations {
  Iterate model;
  double cost = 0.0;  // relative_output_error of `model`
  Termination termination = Termination::not_run;
  std::string message;
  int iterations = 0;
  int step_halvings = 0;
  double reciprocal_condition = std::numeric_limits<double>::quiet_NaN();
  bool start_returned = false;  // not converged, and no iterate fitted better than the start
};

// Rank-one residues (MimoRefinedIvOptions::rank_one_residues): with the shared poles fixed, each
// mode's residue matrix is restricted to Res_i = psi_i L_i^T and the numerators are fitted to
// the outputs by least squares, alternating between the shapes psi (every output's equations
// apart, linear) and the participations L (all outputs together, linear). With
// c_jk = A_i'(s) Res_i[j, k] = psi_j L'_k (s the upper pole, L' = A_i'(s) L), the mode's output
// j is sum_k Re(c_jk) e_k - Im(c_jk) f_k with e_k = p^0 / A_i u_k and, for m_i = 1,
// f_k = -(p / A_i u_k - Re(s) e_k) / Im(s); so N0 = Re c - Re(s) Im c / Im s, N1 = Im c / Im s.
// A mode with m_i = 0 has real c: psi and L real. Every other column (integrators, real poles,
// other modes, D) stays general and is refitted with the shapes. One thin QR of the columns
// turns every step into a problem of their number, whatever the record's length.
struct RankOneFit {
  Iterate model;
  int iterations = 0;
  int modes = 0;
};

// `bank` run over input k, exact for the input hold and the input's delay fraction.
Eigen::MatrixXd filtered_input(const Layout& layout, const FilterRealization& bank,
                               const MimoData& data, int k);
// The filters p^r / (p^{l_i} A_i) of submodel i's numerator columns.
FilterRealization input_bank(const Layout& layout, const std::vector<Polynomial>& a, int i);
FreeResponses free_responses(const Layout& layout, const MimoData& data, const Polynomial& a, int i,
                             bool with_filtered);
// p^r / (p^l_i A_i) u_k for every submodel, input and r <= m_i, then D's and the free responses'.
Eigen::MatrixXd numerator_regressors(const Layout& layout, const MimoData& data,
                                     const std::vector<Polynomial>& a);
std::vector<Polynomial> denominators(const MimoAdditiveModel& model);
// Rows of submodel i's coefficients in Iterate::free.
int free_row(const Layout& layout, int i);
// The model of denominators `a` whose numerators and D are the coefficients `b` of the
// numerator columns (estimation's, shared with frf_matrix_fit).
using internal::model_from_columns;
// Numerators fitted by least squares to every output for the given denominators.
Iterate fit_numerators(const Layout& layout, const MimoData& data,
                       const std::vector<Polynomial>& a);
ScaledQr scaled_thin_qr(const Eigen::MatrixXd& u);
// Sum over the outputs of the mean squared output error relative to the output's mean square.
double relative_output_error(const Layout& layout, const MimoData& data, const Iterate& x);
// The iteration from `model` (mimo_srivc.cc).
Iterations run_iterations(const Layout& layout, const MimoData& data, Iterate model,
                          int max_iterations, double tolerance, Hold output_interpolation,
                          const std::function<void(int, int)>& progress = {});

// The instruments' sources: p^q / A_i (p^r / A_i u_k), q = 1..n_i, for every submodel,
// input and r <= m_i, one cascade of two banks each (exact for the input hold), so that
// -p^q B_ijk / A_i^2 u_k, the a-part of the instrument of output j (the gradient of output
// j's model output with respect to the denominators), is a weighted sum.
class InstrumentSources {
 public:
  InstrumentSources(const Layout& layout, const MimoData& data, const std::vector<Polynomial>& a)
      : layout_(layout), sources_(static_cast<size_t>(layout.size())) {
    for (int i = 0; i < layout.size(); ++i) {
      const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
      if (o.n == 0) continue;  // integrators alone: no denominator to estimate
      const FilterRealization bank = input_bank(layout, a, i);
      const FilterRealization own = derivative_filters(a[static_cast<size_t>(i)]);
      for (int r = 0; r <= o.m; ++r) {
        Eigen::VectorXd pick = Eigen::VectorXd::Zero(bank.outputs());
        pick(r) = 1.0;
        const FilterRealization chain = cascade(bank, pick, own);
        for (int k = 0; k < layout.inputs; ++k) {
          sources_[static_cast<size_t>(i)].push_back(
              filtered_input(layout, chain, data, k).middleCols(1, o.n));
        }
      }
      if (layout.free_count > 0) {
        free_[static_cast<size_t>(i)] =
            free_responses(layout, data, a[static_cast<size_t>(i)], i, true).filtered;
      }
    }
  }

  // psi (N x a_count) = output j's denominator instrument at `x`: with free responses, minus
  // p^q / A_i of submodel i's current free response as well (docs/decisions/0010), so that it
  // stays the gradient of the output error.
  void denominator_instrument(const Iterate& x, int j, Eigen::MatrixXd& psi) const {
    for (int i = 0; i < layout_.size(); ++i) {
      const SubmodelOrder& o = layout_.orders[static_cast<size_t>(i)];
      if (o.n == 0) continue;
      auto instrument = psi.middleCols(layout_.a_at[static_cast<size_t>(i)], o.n);
      instrument.setZero();
      for (int k = 0; k < layout_.inputs; ++k) {
        const Polynomial& b = x.model.numerator(i, j, k);
        for (int r = 0; r <= std::min(o.m, b.degree()); ++r) {
          instrument -=
              b[r] * sources_[static_cast<size_t>(i)][static_cast<size_t>(r * layout_.inputs + k)];
        }
      }
      if (layout_.free_count == 0) continue;
      const Eigen::VectorXd c = x.free.block(free_row(layout_, i), j, layout_.states(i), 1);
      for (int q = 0; q < o.n; ++q) {
        instrument.col(q) -= free_[static_cast<size_t>(i)][static_cast<size_t>(q)] * c;
      }
    }
  }

 private:
  const Layout& layout_;
  std::vector<std::vector<Eigen::MatrixXd>> sources_;
  std::vector<std::vector<Eigen::MatrixXd>> free_ =
      std::vector<std::vector<Eigen::MatrixXd>>(static_cast<size_t>(layout_.size()));
};

// The start found from the data (mimo_srivc_start.cc).
Iterate automatic_start(const Layout& layout, const MimoData& data, Hold interpolation);

// Covariance and modes (mimo_srivc_modes.cc).
Eigen::MatrixXd mimo_covariance(const Layout& layout, const MimoData& data, const Iterate& x,
                                const Eigen::MatrixXd& u, const Eigen::MatrixXd& residuals,
                                NoiseAssumption noise, int max_ar_order);
// The modes (estimation's, shared with frf_matrix_fit): the upper pole of a second-order
// denominator and every second-order submodel as a MimoMode.
using internal::modes_of;
using internal::upper_pole;
Layout model_layout(const Layout& layout);
Eigen::MatrixXd model_block(const Layout& layout, const Eigen::MatrixXd& joint);

// Rank-one residues (mimo_rank_one.cc).
RankOneFit rank_one_residues(const Layout& layout, const MimoData& data, const Iterate& start);

}  // namespace ctid::mimo_srivc_parts
