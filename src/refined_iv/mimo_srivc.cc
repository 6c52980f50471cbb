// mimo_srivc: the shared-pole refined IV estimator of several inputs and outputs. This file
// holds the numerator columns, one step of the iteration (as named phases), the iteration
// with its step control, and the estimate; the start, the covariance and modes, and the
// rank-one refit are in mimo_srivc_start.cc, mimo_srivc_modes.cc and mimo_rank_one.cc.
#include "ctid/refined_iv/mimo_srivc.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <utility>

#include <Eigen/Dense>
#include <Eigen/SVD>

#include "ctid/core/error.h"
#include "ctid/core/fields.h"
#include "ctid/core/format.h"
#include "ctid/estimation/validation.h"
#include "ctid/estimation/verdict.h"
#include "ctid/filtering/filter_bank.h"
#include "ctid/frequency/frf.h"
#include "ctid/frequency/mimo_frf.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/covariance.h"
#include "ctid/refined_iv/initialization.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/simulate.h"
#include "estimation/internal/mimo_layout.h"
#include "estimation/internal/scaled_least_squares.h"
#include "internal/mimo_srivc_parts.h"
#include "internal/refined_iv_engine.h"

namespace ctid::mimo_srivc_parts {

// The model's parameters in one vector: every a-block, then every numerator (submodel,
// output, input, power r <= m_i; a numerator trimmed of exact zeros counts them as zeros),
// then D, for the stopping rule.
Eigen::VectorXd flatten(const Layout& layout, const MimoAdditiveModel& model) {
  std::vector<double> v;
  for (const MimoSubmodel& s : model.submodels()) {
    for (int q = 1; q <= s.a.degree(); ++q) v.push_back(s.a[q]);
  }
  for (int i = 0; i < model.size(); ++i) {
    const int m = layout.orders[static_cast<size_t>(i)].m;
    for (const Polynomial& b : model[i].b) {
      for (int r = 0; r <= m; ++r) v.push_back(r <= b.degree() ? b[r] : 0.0);
    }
  }
  for (Eigen::Index c = 0; c < model.direct().size(); ++c) v.push_back(model.direct()(c));
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

// `bank` run over input k, exact for the input hold and the input's delay fraction.
Eigen::MatrixXd filtered_input(const Layout& layout, const FilterRealization& bank,
                               const MimoData& data, int k) {
  return SampledFilter(bank, data.sample_time(), data.input_hold(), layout.input_fraction(k))
      .apply(data.inputs().col(k));
}

// The inputs at the sample times, each delayed by its fraction of a sample (the direct term's
// columns): u_k itself without one.
Eigen::MatrixXd held_inputs(const Layout& layout, const MimoData& data) {
  Eigen::MatrixXd u = data.inputs();
  for (int k = 0; k < layout.inputs; ++k) {
    if (layout.input_fraction(k) == 0.0) continue;
    const DelayedSample now = delayed_sample(layout.input_fraction(k), data.input_hold());
    u.col(k) =
        now.previous * delay_samples(data.inputs().col(k), 1) + now.current * data.inputs().col(k);
  }
  return u;
}

// The filters p^r / (p^{l_i} A_i) of submodel i's numerator columns (l_i its integrators).
FilterRealization input_bank(const Layout& layout, const std::vector<Polynomial>& a, int i) {
  return derivative_filters(
      Polynomial::monomial(layout.orders[static_cast<size_t>(i)].integrators) *
      a[static_cast<size_t>(i)]);
}

FreeResponses free_responses(const Layout& layout, const MimoData& data, const Polynomial& a, int i,
                             bool with_filtered) {
  const int s = layout.states(i);
  const int n = layout.orders[static_cast<size_t>(i)].n;
  const internal::FreeResponseChain chain = internal::free_response_chain(
      a, layout.orders[static_cast<size_t>(i)].integrators, data.sample_time());
  Eigen::MatrixXd state = Eigen::MatrixXd::Zero(chain.phi.rows(), s);
  state.topRows(s).setIdentity();
  FreeResponses f;
  f.basis.resize(data.size(), s);
  if (with_filtered) f.filtered.assign(static_cast<size_t>(n), Eigen::MatrixXd(data.size(), s));
  Eigen::MatrixXd next(state.rows(), s);
  for (int k = 0; k < data.size(); ++k) {
    f.basis.row(k).noalias() = chain.c0 * state;
    for (int q = 0; q < n && with_filtered; ++q) {
      f.filtered[static_cast<size_t>(q)].row(k).noalias() = chain.ck.row(q) * state;
    }
    next.noalias() = chain.phi * state;
    state.swap(next);
  }
  return f;
}

// p^r / (p^l_i A_i) u_k for every submodel, input and r <= m_i, then D's columns and the
// free-response columns (N x u_count), exact for the input hold.
Eigen::MatrixXd numerator_regressors(const Layout& layout, const MimoData& data,
                                     const std::vector<Polynomial>& a) {
  Eigen::MatrixXd u(data.size(), layout.u_count);
  for (int i = 0; i < layout.size() && layout.free_count > 0; ++i) {
    u.middleCols(layout.free_at[static_cast<size_t>(i)], layout.states(i)) =
        free_responses(layout, data, a[static_cast<size_t>(i)], i, false).basis;
  }
  for (int i = 0; i < layout.size(); ++i) {
    const FilterRealization bank = input_bank(layout, a, i);
    const int m = layout.orders[static_cast<size_t>(i)].m;
    for (int k = 0; k < layout.inputs; ++k) {
      u.middleCols(layout.u_column(i, k, 0), m + 1) =
          filtered_input(layout, bank, data, k).leftCols(m + 1);
    }
  }
  if (layout.direct) u.middleCols(layout.d_at, layout.inputs) = held_inputs(layout, data);
  return u;
}

// Numerators of submodel i as the rows of its numerator columns x outputs.
Eigen::MatrixXd numerator_block(const Layout& layout, const MimoAdditiveModel& model, int i) {
  const int m = layout.orders[static_cast<size_t>(i)].m;
  Eigen::MatrixXd block = Eigen::MatrixXd::Zero(layout.inputs * (m + 1), layout.outputs);
  for (int j = 0; j < layout.outputs; ++j) {
    for (int k = 0; k < layout.inputs; ++k) {
      const Polynomial& b = model.numerator(i, j, k);
      for (int r = 0; r <= std::min(m, b.degree()); ++r) block(k * (m + 1) + r, j) = b[r];
    }
  }
  return block;
}

std::vector<Polynomial> denominators(const MimoAdditiveModel& model) {
  std::vector<Polynomial> a;
  for (const MimoSubmodel& s : model.submodels()) a.push_back(s.a);
  return a;
}

// Rows of submodel i's coefficients in Iterate::free.
int free_row(const Layout& layout, int i) {
  return layout.free_at[static_cast<size_t>(i)] - layout.model_columns();
}

Iterate at_rest(const Layout& layout, MimoAdditiveModel model) {
  return {std::move(model), Eigen::MatrixXd::Zero(layout.free_count, layout.outputs)};
}

// Submodel i's sampled output at every output channel (N x outputs), its free response
// included.
Eigen::MatrixXd submodel_outputs(const Layout& layout, const Eigen::MatrixXd& u, const Iterate& x,
                                 int i) {
  const int m = layout.orders[static_cast<size_t>(i)].m;
  Eigen::MatrixXd out = u.middleCols(layout.u_at[static_cast<size_t>(i)], layout.inputs * (m + 1)) *
                        numerator_block(layout, x.model, i);
  if (layout.free_count > 0) {
    out += u.middleCols(layout.free_at[static_cast<size_t>(i)], layout.states(i)) *
           x.free.middleRows(free_row(layout, i), layout.states(i));
  }
  return out;
}

// The direct term's contribution D u at every output (N x outputs).
Eigen::MatrixXd direct_outputs(const Layout& layout, const Eigen::MatrixXd& u,
                               const MimoAdditiveModel& model) {
  if (!layout.direct) return Eigen::MatrixXd::Zero(u.rows(), layout.outputs);
  return u.middleCols(layout.d_at, layout.inputs) * model.direct().transpose();
}

// The whole model's sampled output (N x outputs).
Eigen::MatrixXd model_outputs(const Layout& layout, const Eigen::MatrixXd& u, const Iterate& x) {
  Eigen::MatrixXd fitted = direct_outputs(layout, u, x.model);
  for (int i = 0; i < layout.size(); ++i) fitted += submodel_outputs(layout, u, x, i);
  return fitted;
}

// The iterate of denominators `a` whose numerators, D and free responses are the
// coefficients `b` of every column (u_count x outputs).
Iterate iterate_from_columns(const Layout& layout, const std::vector<Polynomial>& a,
                             const Eigen::MatrixXd& b) {
  return {model_from_columns(layout, a, b), b.bottomRows(layout.free_count)};
}

// Numerators fitted by least squares to every output for the given denominators.
Iterate fit_numerators(const Layout& layout, const MimoData& data,
                       const std::vector<Polynomial>& a) {
  const Eigen::MatrixXd u = numerator_regressors(layout, data, a);
  const Eigen::VectorXd s = internal::column_scales(u);
  return iterate_from_columns(
      layout, a,
      s.cwiseInverse().asDiagonal() *
          (u * s.cwiseInverse().asDiagonal()).colPivHouseholderQr().solve(data.outputs()));
}

ScaledQr scaled_thin_qr(const Eigen::MatrixXd& u) {
  ScaledQr f;
  f.scale = internal::column_scales(u);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(u * f.scale.cwiseInverse().asDiagonal());
  f.q = qr.householderQ() * Eigen::MatrixXd::Identity(u.rows(), u.cols());
  f.r = qr.matrixQR().topRows(u.cols()).triangularView<Eigen::Upper>();
  return f;
}

// Sum over the outputs of the mean squared output error relative to the output's mean square:
// how the start's candidates are compared (every channel counts alike).
double relative_output_error(const Layout& layout, const MimoData& data, const Iterate& x) {
  const Eigen::MatrixXd fitted =
      model_outputs(layout, numerator_regressors(layout, data, denominators(x.model)), x);
  double total = 0.0;
  for (int j = 0; j < layout.outputs; ++j) {
    total += (data.outputs().col(j) - fitted.col(j)).squaredNorm() /
             std::max(data.outputs().col(j).squaredNorm(), 1e-300);
  }
  return total;
}

struct Step {
  std::optional<Iterate> model;
  std::string failure;  // why the step could not be taken (empty if it was)
  Termination kind = Termination::singular_equations;  // of a failure
  double reciprocal_condition = std::numeric_limits<double>::quiet_NaN();
};

// The model's sampled outputs at an iterate, split by submodel: the numerator columns u at its
// denominators a, each submodel's output, the direct term's and their total.
struct ModelParts {
  std::vector<Polynomial> a;
  Eigen::MatrixXd u;
  std::vector<Eigen::MatrixXd> parts;
  Eigen::MatrixXd direct;
  Eigen::MatrixXd total;
};

ModelParts model_parts(const Layout& layout, const MimoData& data, const Iterate& x) {
  const int submodels = layout.size();
  const MimoAdditiveModel& model = x.model;
  ModelParts m;
  m.a = denominators(model);
  m.u = numerator_regressors(layout, data, m.a);
  m.direct = direct_outputs(layout, m.u, model);
  m.total = m.direct;
  for (int i = 0; i < submodels; ++i) {
    m.parts.push_back(submodel_outputs(layout, m.u, x, i));
    m.total += m.parts.back();
  }
  return m;
}

// The denominators' equations of (29) summed over the outputs with the numerator columns
// projected out (q the thin QR's orthonormal factor), the squared norms of the projected
// regressor and instrument columns, and per output Q' phi and Q' upsilon for the numerators.
struct ProjectedEquations {
  Eigen::MatrixXd m_a;
  Eigen::MatrixXd rhs;
  Eigen::VectorXd phi_norm;
  Eigen::VectorXd psi_norm;
  std::vector<Eigen::MatrixXd> q_phi;
  std::vector<Eigen::MatrixXd> q_upsilon;
};

ProjectedEquations projected_equations(const Layout& layout, const MimoData& data, const Iterate& x,
                                       const ModelParts& model, const Eigen::MatrixXd& q,
                                       Hold output_interpolation) {
  const int n = data.size();
  const int outputs = layout.outputs;
  const int submodels = layout.size();
  const std::vector<Polynomial>& a = model.a;
  const std::vector<Eigen::MatrixXd>& parts = model.parts;
  const Eigen::MatrixXd& direct = model.direct;
  const Eigen::MatrixXd& total = model.total;
  const InstrumentSources sources(layout, data, a);

  // Per output: the denominator regressors -p^q / A_i y~_ij, the instruments -p^q / A_i x_ij
  // (x_ij submodel i's own output, B_ij. / A_i u), and the filtered residuals 1 / A_i y~_ij
  // (one column per submodel: the K right-hand sides of (29)).
  ProjectedEquations e;
  Eigen::MatrixXd& m_a = e.m_a;
  Eigen::MatrixXd& rhs = e.rhs;
  Eigen::VectorXd& phi_norm = e.phi_norm;
  Eigen::VectorXd& psi_norm = e.psi_norm;
  std::vector<Eigen::MatrixXd>& q_phi = e.q_phi;
  std::vector<Eigen::MatrixXd>& q_upsilon = e.q_upsilon;
  m_a = Eigen::MatrixXd::Zero(layout.a_count, layout.a_count);
  rhs = Eigen::MatrixXd::Zero(layout.a_count, layout.columns());
  phi_norm = Eigen::VectorXd::Zero(layout.a_count);
  psi_norm = Eigen::VectorXd::Zero(layout.a_count);
  q_phi.resize(static_cast<size_t>(outputs));
  q_upsilon.resize(static_cast<size_t>(outputs));
  // 1 / A_i on the residuals (not 1 / (p^l_i A_i): (32) of the paper); none for a submodel of
  // integrators alone, whose residual enters as it is.
  std::vector<std::optional<SampledFilter>> filters(static_cast<size_t>(submodels));
  for (int i = 0; i < submodels; ++i) {
    if (layout.orders[static_cast<size_t>(i)].n == 0) continue;
    filters[static_cast<size_t>(i)].emplace(derivative_filters(a[static_cast<size_t>(i)]),
                                            data.sample_time(), output_interpolation);
  }
  Eigen::MatrixXd phi(n, layout.a_count);
  Eigen::MatrixXd psi(n, layout.a_count);
  Eigen::MatrixXd upsilon(n, layout.columns());
  for (int j = 0; j < outputs; ++j) {
    for (int i = 0; i < submodels; ++i) {
      const int n_i = layout.orders[static_cast<size_t>(i)].n;
      const Eigen::VectorXd residual =
          data.outputs().col(j) - total.col(j) + parts[static_cast<size_t>(i)].col(j);
      if (n_i == 0) {
        upsilon.col(i) = residual;
        continue;
      }
      const Eigen::MatrixXd fy = filters[static_cast<size_t>(i)]->apply(residual);
      upsilon.col(i) = fy.col(0);
      phi.middleCols(layout.a_at[static_cast<size_t>(i)], n_i) = -fy.middleCols(1, n_i);
    }
    sources.denominator_instrument(x, j, psi);
    // The direct term's own residual, unfiltered (its denominator is 1).
    if (layout.direct)
      upsilon.col(submodels) = data.outputs().col(j) - total.col(j) + direct.col(j);
    q_phi[static_cast<size_t>(j)] = q.transpose() * phi;
    q_upsilon[static_cast<size_t>(j)] = q.transpose() * upsilon;
    const Eigen::MatrixXd q_psi = q.transpose() * psi;
    m_a += psi.transpose() * phi - q_psi.transpose() * q_phi[static_cast<size_t>(j)];
    rhs += psi.transpose() * upsilon - q_psi.transpose() * q_upsilon[static_cast<size_t>(j)];
    phi_norm +=
        (phi.colwise().squaredNorm() - q_phi[static_cast<size_t>(j)].colwise().squaredNorm())
            .transpose();
    psi_norm += (psi.colwise().squaredNorm() - q_psi.colwise().squaredNorm()).transpose();
  }
  return e;
}

// The denominators' projected system, rows and columns scaled to unit norm, solved into
// `alpha`; the failed step when it is singular.
std::optional<Step> solve_denominators(const ProjectedEquations& e, Eigen::MatrixXd& alpha,
                                       double& rcond) {
  const auto scale_of = [](Eigen::VectorXd squared) {
    for (Eigen::Index k = 0; k < squared.size(); ++k) {
      squared(k) = squared(k) > 0.0 ? std::sqrt(squared(k)) : 1.0;
    }
    return squared;
  };
  const Eigen::VectorXd s_phi = scale_of(e.phi_norm);
  const Eigen::VectorXd s_psi = scale_of(e.psi_norm);
  const Eigen::MatrixXd scaled =
      s_psi.cwiseInverse().asDiagonal() * e.m_a * s_phi.cwiseInverse().asDiagonal();
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(scaled);
  rcond = lu.rcond();
  if (!(rcond >= 1e-14)) {
    return Step{std::nullopt, "the denominators' equations are singular",
                Termination::singular_equations, rcond};
  }
  alpha = s_phi.cwiseInverse().asDiagonal() * lu.solve(s_psi.cwiseInverse().asDiagonal() * e.rhs);
  return std::nullopt;
}

// Each submodel's denominator from the block of its own column of alpha, its unstable roots
// reflected, into `next`; the failed step when one is not finite or lost its leading
// coefficient.
std::optional<Step> next_denominators(const Layout& layout, const Eigen::MatrixXd& alpha,
                                      double rcond, std::vector<MimoSubmodel>& next) {
  const int submodels = layout.size();
  for (int i = 0; i < submodels; ++i) {
    const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
    Eigen::VectorXd coefficients(o.n + 1);
    coefficients(0) = 1.0;
    coefficients.tail(o.n) = alpha.block(layout.a_at[static_cast<size_t>(i)], i, o.n, 1);
    if (!coefficients.allFinite()) {
      return Step{std::nullopt, "an iterate is not finite", Termination::non_finite};
    }
    if (!(std::abs(coefficients(o.n)) > 0.0)) {
      return Step{std::nullopt, "a denominator lost its leading coefficient (a pole at infinity)",
                  Termination::singular_equations, rcond};
    }
    bool reflected = false;
    MimoSubmodel sub{o.n == 0
                         ? Polynomial{1.0}
                         : internal::reflect_unstable_roots(Polynomial(coefficients), reflected),
                     {},
                     o.integrators};
    next.push_back(std::move(sub));
  }
  return std::nullopt;
}

// Per output its numerators, D and free responses from each submodel's own column of the
// numerator columns' solution given alpha; the step to the model they make with `next`.
Step next_numerators(const Layout& layout, const ScaledQr& factors, const ProjectedEquations& e,
                     const Eigen::MatrixXd& alpha, double rcond, std::vector<MimoSubmodel> next) {
  const int outputs = layout.outputs;
  const int submodels = layout.size();
  const Eigen::VectorXd& u_scale = factors.scale;
  const Eigen::MatrixXd& triangle = factors.r;
  const std::vector<Eigen::MatrixXd>& q_phi = e.q_phi;
  const std::vector<Eigen::MatrixXd>& q_upsilon = e.q_upsilon;
  Eigen::MatrixXd next_direct;
  if (layout.direct) next_direct.resize(outputs, layout.inputs);
  Eigen::MatrixXd next_free(layout.free_count, outputs);
  for (int j = 0; j < outputs; ++j) {
    const Eigen::MatrixXd beta =
        u_scale.cwiseInverse().asDiagonal() *
        triangle.triangularView<Eigen::Upper>().solve(q_upsilon[static_cast<size_t>(j)] -
                                                      q_phi[static_cast<size_t>(j)] * alpha);
    // Appended output by output, input by input: the model's own order of numerators.
    for (int i = 0; i < submodels; ++i) {
      const int m = layout.orders[static_cast<size_t>(i)].m;
      for (int k = 0; k < layout.inputs; ++k) {
        next[static_cast<size_t>(i)].b.push_back(Polynomial::trimmed(
            Eigen::VectorXd(beta.block(layout.u_column(i, k, 0), i, m + 1, 1))));
      }
    }
    if (layout.direct) {
      next_direct.row(j) = beta.block(layout.d_at, submodels, layout.inputs, 1).transpose();
    }
    // Each submodel's free response from its own column, like its numerators.
    for (int i = 0; i < submodels && layout.free_count > 0; ++i) {
      next_free.block(free_row(layout, i), j, layout.states(i), 1) =
          beta.block(layout.free_at[static_cast<size_t>(i)], i, layout.states(i), 1);
    }
  }
  // (The denominators were checked before.)
  bool finite = next_direct.allFinite() && next_free.allFinite();
  for (const MimoSubmodel& s : next) {
    for (const Polynomial& b : s.b) finite = finite && b.coefficients().allFinite();
  }
  if (!finite) return {std::nullopt, "an iterate is not finite", Termination::non_finite};
  return {Iterate{MimoAdditiveModel(layout.inputs, layout.outputs, std::move(next), next_direct),
                  std::move(next_free)},
          {},
          Termination::converged,
          rcond};
}

// One step of the shared-pole iteration from `x` (see mimo_srivc.h): the model's outputs,
// the numerator columns projected out with one thin QR (scaled to unit norm), the
// denominators' equations solved, then the numerators given the denominators.
Step iterate(const Layout& layout, const MimoData& data, const Iterate& x,
             Hold output_interpolation) {
  const ModelParts model = model_parts(layout, data, x);
  const ScaledQr factors = scaled_thin_qr(model.u);
  const Eigen::MatrixXd& triangle = factors.r;
  const double r_max = triangle.diagonal().cwiseAbs().maxCoeff();
  if (!(triangle.diagonal().cwiseAbs().minCoeff() > 1e-12 * r_max)) {
    return {std::nullopt, "the numerator regressors are numerically collinear"};
  }
  const ProjectedEquations e =
      projected_equations(layout, data, x, model, factors.q, output_interpolation);
  if (!e.m_a.allFinite() || !e.rhs.allFinite()) {
    return {std::nullopt, "a filtered signal is not finite", Termination::non_finite};
  }
  Eigen::MatrixXd alpha;
  double rcond = 0.0;
  if (std::optional<Step> failed = solve_denominators(e, alpha, rcond)) return std::move(*failed);
  std::vector<MimoSubmodel> next;
  if (std::optional<Step> failed = next_denominators(layout, alpha, rcond, next)) {
    return std::move(*failed);
  }
  return next_numerators(layout, factors, e, alpha, rcond, std::move(next));
}

// The model a fraction w of the way from x to y, parameter by parameter.
MimoAdditiveModel blend(const Layout& layout, const MimoAdditiveModel& x,
                        const MimoAdditiveModel& y, double w);
Iterate blend(const Layout& layout, const Iterate& x, const Iterate& y, double w) {
  return {blend(layout, x.model, y.model, w), (1.0 - w) * x.free + w * y.free};
}
MimoAdditiveModel blend(const Layout& layout, const MimoAdditiveModel& x,
                        const MimoAdditiveModel& y, double w) {
  std::vector<MimoSubmodel> submodels;
  for (int i = 0; i < layout.size(); ++i) {
    MimoSubmodel s{(1.0 - w) * x[i].a + w * y[i].a, {}, x[i].integrators};
    for (size_t c = 0; c < x[i].b.size(); ++c) s.b.push_back((1.0 - w) * x[i].b[c] + w * y[i].b[c]);
    submodels.push_back(std::move(s));
  }
  Eigen::MatrixXd direct;
  if (layout.direct) direct = (1.0 - w) * x.direct() + w * y.direct();
  return MimoAdditiveModel(layout.inputs, layout.outputs, std::move(submodels), direct);
}

Iterations run_iterations(const Layout& layout, const MimoData& data, Iterate model,
                          int max_iterations, double tolerance, Hold output_interpolation,
                          const std::function<void(int, int)>& progress) {
  double cost = relative_output_error(layout, data, model);
  Iterations result{
      model, cost, Termination::not_run, {}, 0, 0, std::numeric_limits<double>::quiet_NaN()};
  Iterate& best = result.model;
  double& best_cost = result.cost;
  int best_iteration = 0;
  // Step control. (1) A step to an iterate whose equations cannot be formed or solved is
  // halved toward the last accepted iterate (kMaxHalvings times at most), as in the SISO
  // engine. (2) On lightly damped measured structures the map x -> T(x) of (29) can have an
  // eigenvalue below -1 at its fixed point: the steps T(x) - x reverse and grow. Such an
  // oscillation halves the relaxation w of x <- x + w (T(x) - x), which has the same fixed
  // points. (3) A step that more than doubles the output error is halved toward x.
  constexpr int kMaxHalvings = 8;
  constexpr double kMinRelaxation = 1.0 / 64.0;
  double relaxation = 1.0;
  // (4) Rounding: on long records of lightly damped modes the step T(x) - x stops shrinking
  // near 1e-8 relative (measured on the flexible structure). Once it has stayed above its
  // smallest value, itself below kFloorFactor * tolerance, for kStallIterations iterations,
  // the iterate is at its fixed point to rounding and counts as converged.
  constexpr double kFloorFactor = 1e3;
  constexpr int kStallIterations = 10;
  double smallest_change = std::numeric_limits<double>::infinity();
  int smallest_at = 0;
  std::optional<Iterate> accepted;
  Eigen::VectorXd last_step;
  for (int iteration = 1; iteration <= max_iterations; ++iteration) {
    if (progress) progress(iteration, max_iterations);
    Step step = iterate(layout, data, model, output_interpolation);
    for (int halvings = 0; !step.model && accepted && halvings < kMaxHalvings; ++halvings) {
      ++result.step_halvings;
      model = blend(layout, *accepted, model, 0.5);
      step = iterate(layout, data, model, output_interpolation);
    }
    result.reciprocal_condition = step.reciprocal_condition;
    if (!step.model) {
      result.termination = step.kind;
      result.message =
          internal::concat("mimo_srivc: stopped at iteration ", iteration, ": ", step.failure);
      break;
    }
    result.iterations = iteration;
    const Eigen::VectorXd here = flatten(layout, model.model);
    const Eigen::VectorXd full_step = flatten(layout, step.model->model) - here;
    const double change = full_step.norm() / here.norm();
    if (change < smallest_change) {
      smallest_change = change;
      smallest_at = iteration;
    }
    const bool stalled =
        smallest_change < kFloorFactor * tolerance && iteration - smallest_at >= kStallIterations;
    if (change < tolerance || stalled) {
      model = std::move(*step.model);
      result.termination = Termination::converged;
      result.message =
          internal::concat("mimo_srivc: converged after ", iteration,
                           " iterations (relative parameter change ", format_brief(change),
                           stalled ? internal::concat(", at the rounding floor: no smaller than ",
                                                      format_brief(smallest_change), " for ",
                                                      kStallIterations, " iterations)")
                                   : std::string(")"));
      break;
    }
    if (last_step.size() > 0 && full_step.dot(last_step) < 0.0 &&
        full_step.norm() > 0.5 * last_step.norm() && relaxation > kMinRelaxation) {
      relaxation *= 0.5;
    }
    last_step = full_step;
    Iterate next =
        relaxation < 1.0 ? blend(layout, model, *step.model, relaxation) : std::move(*step.model);
    double next_cost = relative_output_error(layout, data, next);
    for (int halvings = 0; halvings < kMaxHalvings && !(next_cost <= 2.0 * cost); ++halvings) {
      ++result.step_halvings;
      next = blend(layout, model, next, 0.5);
      next_cost = relative_output_error(layout, data, next);
    }
    accepted = model;
    model = std::move(next);
    cost = next_cost;
    if (std::isfinite(cost) && cost <= best_cost) {
      best = model;
      best_cost = cost;
      best_iteration = iteration;
    }
  }
  if (result.termination == Termination::not_run) {
    result.termination = Termination::iteration_limit;
    result.message =
        internal::concat("mimo_srivc: no convergence in ", max_iterations, " iterations");
  }
  // Converged: the fixed point is the estimate (the covariance describes it), even where an
  // earlier iterate fitted the outputs a little better. Otherwise the best iterate.
  if (result.termination == Termination::converged) {
    best_cost = relative_output_error(layout, data, model);
    best = std::move(model);
  } else if (best_iteration == 0) {
    result.start_returned = true;
    result.message += "; no iterate fitted the outputs better than the start, which is returned";
  } else if (best_iteration != result.iterations) {
    result.message += internal::concat("; the iterate with the lowest output error (", "iteration ",
                                       best_iteration, ") is returned");
  }
  return result;
}

// Submodels of equal orders listed from the slowest up (by the geometric mean of their pole
// magnitudes, a_n^(-1/n)), so that the order in which the start found them does not show.
// Free responses move with their submodels.
Iterate slowest_first(const Layout& layout, Iterate x) {
  for (const SubmodelOrder& o : layout.orders) {
    if (o.n != layout.orders[0].n || o.m != layout.orders[0].m || o.integrators > 0) return x;
  }
  const MimoAdditiveModel& model = x.model;
  std::vector<int> order(static_cast<size_t>(model.size()));
  for (int i = 0; i < model.size(); ++i) order[static_cast<size_t>(i)] = i;
  const auto speed = [&](int i) {
    const Polynomial& a = model[i].a;
    return std::pow(std::abs(a[a.degree()]), -1.0 / a.degree());
  };
  std::stable_sort(order.begin(), order.end(), [&](int i, int k) { return speed(i) < speed(k); });
  std::vector<MimoSubmodel> submodels;
  Eigen::MatrixXd free(x.free.rows(), x.free.cols());
  for (int i = 0; i < model.size(); ++i) {
    const int from = order[static_cast<size_t>(i)];
    submodels.push_back(model[from]);
    if (layout.free_count > 0) {
      free.middleRows(free_row(layout, i), layout.states(i)) =
          x.free.middleRows(free_row(layout, from), layout.states(from));
    }
  }
  return {MimoAdditiveModel(model.inputs(), model.outputs(), std::move(submodels),
                            model.has_direct_term() ? model.direct() : Eigen::MatrixXd(),
                            model.input_delays()),
          std::move(free)};
}

void check_orders(const std::vector<SubmodelOrder>& orders, const MimoData& data, bool direct) {
  require(!orders.empty(), "mimo_srivc: the structure has no submodels");
  int parameters = 0;
  int integrating = 0;
  for (size_t i = 0; i < orders.size(); ++i) {
    orders[i].validate();
    const SubmodelOrder& o = orders[i];
    require(o.n + o.integrators >= 1, "mimo_srivc: submodel ", i + 1,
            " has no poles (n = 0 and no integrators)");
    require(o.integrators <= 4, "mimo_srivc: submodel ", i + 1, " has ", o.integrators,
            " integrators; at most 4 (a rigid-body mode has 2)");
    require(o.m <= o.n + o.integrators, "mimo_srivc: submodel ", i + 1, " has m = ", o.m,
            " > n + integrators = ", o.n + o.integrators, "; the model must be proper");
    if (o.integrators > 0) ++integrating;
    parameters += orders[i].n + data.input_count() * (orders[i].m + 1);
  }
  require(integrating <= 1, "mimo_srivc: ", integrating,
          " submodels have integrators; at most one may have poles at the origin (their "
          "responses would be indistinguishable)");
  if (direct) parameters += data.input_count();
  require(data.size() > 2 * parameters, "mimo_srivc: ", data.size(), " samples are too few for ",
          parameters, " parameters per output (the record needs more than twice as many)");
}

// One input and output through the SISO additive estimator, its result in MIMO form: the
// parameters theta_i = [a_i; b_i] of (3) reordered into the shared-pole layout (every a-block,
// then every numerator).
MimoEstimationResult siso_result(const Layout& layout, const MimoData& data,
                                 const MimoRefinedIvOptions& options,
                                 const std::optional<MimoAdditiveModel>& initial_model) {
  // The settings the two estimators share, by their field tables: the iteration, the
  // interpolation, the noise, the covariance and the initial conditions.
  RefinedIvOptions siso;
  assign_shared_fields(siso, options);
  if (!options.input_delays_samples.empty()) {
    const DelaySplit delay =
        split_delay(options.input_delays_samples.front() * data.sample_time(), data.sample_time());
    siso.input_delay_samples = delay.samples;
    siso.input_delay_fraction = delay.fraction;
  }
  if (initial_model) siso.initial_model = initial_model->channel(0, 0).with_input_delay(0.0);
  const EstimationResult r = additive_srivc(data.channel(0, 0), layout.orders, siso);
  MimoEstimationResult result;
  std::vector<MimoSubmodel> submodels;
  for (const Submodel& s : r.model.submodels()) submodels.push_back({s.a, {s.b}, s.integrators});
  result.model = MimoAdditiveModel(1, 1, std::move(submodels), {},
                                   Eigen::VectorXd::Constant(1, r.model.input_delay()));
  static_cast<Outcome&>(result) = r;
  result.step_halvings = r.step_halvings;
  result.mean_squared_errors = Eigen::VectorXd::Constant(1, r.mean_squared_error);
  result.fit_percent = Eigen::VectorXd::Constant(1, r.fit_percent);
  result.verdict = r.verdict;
  if (r.covariance.size() > 0) {
    // Position of each SISO parameter in the MIMO layout.
    std::vector<Eigen::Index> at;
    for (int i = 0; i < layout.size(); ++i) {
      const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
      for (int q = 1; q <= o.n; ++q) at.push_back(layout.a_index(i, q));
      for (int k = 0; k <= o.m; ++k) at.push_back(layout.b_index(0, layout.u_column(i, 0, k)));
    }
    const auto p = static_cast<Eigen::Index>(at.size());
    result.covariance.resize(p, p);
    for (Eigen::Index x = 0; x < p; ++x) {
      for (Eigen::Index y = 0; y < p; ++y) {
        result.covariance(at[static_cast<size_t>(x)], at[static_cast<size_t>(y)]) =
            r.covariance(x, y);
      }
    }
  }
  result.modes = modes_of(layout, *result.model, result.covariance);
  if (r.initial_conditions.size() > 0) result.initial_conditions = r.initial_conditions;
  return result;
}

// Realisation-free form of the free responses (MimoEstimationResult::initial_conditions): per
// output (column), per submodel, its free response and first n_i + l_i - 1 derivatives at the
// first sample, c0 A^k x0 of 1/(p^l_i A_i), as the SISO estimators report them.
Eigen::MatrixXd free_response_values(const Layout& layout, const Iterate& x) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(layout.free_count, layout.outputs);
  for (int i = 0; i < layout.size(); ++i) {
    const FilterRealization bank = input_bank(layout, denominators(x.model), i);
    const int s = layout.states(i);
    if (bank.order() != s) continue;
    for (int j = 0; j < layout.outputs; ++j) {
      Eigen::VectorXd state = x.free.block(free_row(layout, i), j, s, 1);
      for (int k = 0; k < s; ++k) {
        out(free_row(layout, i) + k, j) = bank.c.row(0).dot(state);
        state = bank.a * state;
      }
    }
  }
  return out;
}

MimoEstimationResult estimate(const Layout& layout, const MimoData& data,
                              const MimoRefinedIvOptions& options,
                              const std::optional<MimoAdditiveModel>& initial_model,
                              const Eigen::VectorXd& input_delays,
                              const std::function<void(int, int)>& progress) {
  // A given start has no free responses yet: the first step estimates them.
  Iterate model = [&] {
    if (initial_model) {
      internal::check_initial_model(layout, *initial_model, "mimo_srivc", "the data");
      return at_rest(layout, *initial_model);
    }
    return automatic_start(layout, data, options.output_interpolation);
  }();

  MimoEstimationResult result;
  Iterations run = run_iterations(layout, data, std::move(model), options.max_iterations,
                                  options.tolerance, options.output_interpolation, progress);
  result.termination = run.termination;
  result.message = std::move(run.message);
  result.iterations = run.iterations;
  result.step_halvings = run.step_halvings;
  const double reciprocal_condition = run.reciprocal_condition;
  model = slowest_first(layout, std::move(run.model));
  if (options.rank_one_residues) {
    RankOneFit one = rank_one_residues(layout, data, model);
    if (one.modes > 0) {
      result.message += internal::concat(
          "; residues of ", one.modes, one.modes == 1 ? " mode" : " modes",
          " constrained to rank one (", one.iterations, " alternating least-squares sweeps)");
    }
    model = std::move(one.model);
  }

  const Eigen::MatrixXd u = numerator_regressors(layout, data, denominators(model.model));
  const Eigen::MatrixXd fitted = model_outputs(layout, u, model);
  result.mean_squared_errors = (data.outputs() - fitted).colwise().squaredNorm().transpose() /
                               static_cast<double>(data.size());
  result.fit_percent.resize(data.output_count());
  for (int j = 0; j < data.output_count(); ++j) {
    result.fit_percent(j) = fit_percent(data.outputs().col(j), fitted.col(j));
  }

  // The verdict: finite, stable, every output's fit not negative, the denominators'
  // equations well conditioned at the last step.
  std::vector<std::complex<double>> poles;
  for (const MimoSubmodel& sub : model.model.submodels()) {
    const Eigen::VectorXcd r = sub.a.roots();
    poles.insert(poles.end(), r.data(), r.data() + r.size());
  }
  check_finite(result.verdict, result.fit_percent.allFinite(), "the fit");
  check_stable(result.verdict, Eigen::Map<const Eigen::VectorXcd>(
                                   poles.data(), static_cast<Eigen::Index>(poles.size())));
  for (int j = 0; j < data.output_count(); ++j) {
    if (!(result.fit_percent(j) >= 0.0)) {
      result.verdict.fail(
          internal::concat("output ", data.output_names()[static_cast<size_t>(j)], " is fitted at ",
                           format_brief(result.fit_percent(j)), " %, worse than its mean"),
          {verdict_advice::better_start, verdict_advice::lower_order});
    }
  }
  check_conditioning(result.verdict, reciprocal_condition);
  if (run.start_returned) {
    result.verdict.fail("the iteration did not improve on its start",
                        {verdict_advice::better_start, verdict_advice::lower_order});
  }
  if (options.compute_covariance) {
    result.covariance =
        model_block(layout, mimo_covariance(layout, data, model, u, data.outputs() - fitted,
                                            options.noise, options.noise_model_max_order));
  }
  result.modes = modes_of(model_layout(layout), model.model, result.covariance);
  for (const MimoMode& mode : result.modes) {
    const std::string name = internal::concat("mode ", mode.submodel + 1);
    check_standard_errors(result.verdict, {name + " natural frequency", name + " damping ratio"},
                          Eigen::Vector2d(mode.natural_frequency, mode.damping_ratio),
                          Eigen::Vector2d(mode.natural_frequency_se, mode.damping_ratio_se));
  }
  result.model = model.model.with_input_delays(input_delays);
  if (layout.free_count > 0) result.initial_conditions = free_response_values(layout, model);
  return result;
}

// The record with every input shifted by its whole samples of delay (none when no input is
// delayed), the fractions set in the layout, and the delays in seconds for the model.
struct DelayedInputs {
  std::optional<MimoData> data;
  Eigen::VectorXd seconds;  // empty: none
};

DelayedInputs delay_inputs(Layout& layout, const MimoData& data,
                           const std::vector<double>& delays) {
  DelayedInputs out;
  if (std::none_of(delays.begin(), delays.end(), [](double d) { return d != 0.0; })) return out;
  const double h = data.sample_time();
  out.seconds.resize(layout.inputs);
  layout.input_fractions.assign(static_cast<size_t>(layout.inputs), 0.0);
  Eigen::MatrixXd inputs(data.size(), layout.inputs);
  for (int k = 0; k < layout.inputs; ++k) {
    const double samples = delays[static_cast<size_t>(k)];
    require(samples < 0.5 * data.size(), "mimo_srivc: input ",
            data.input_names()[static_cast<size_t>(k)], " is delayed by ", samples,
            " samples, more than half of the record's ", data.size());
    out.seconds(k) = samples * h;
    const DelaySplit split = split_delay(out.seconds(k), h);
    inputs.col(k) = delay_samples(data.inputs().col(k), split.samples);
    layout.input_fractions[static_cast<size_t>(k)] = split.fraction;
  }
  out.data = MimoData(h, std::move(inputs), data.outputs(), std::nullopt, data.start_time())
                 .with_names(data.input_names(), data.output_names())
                 .with_input_hold(data.input_hold());
  return out;
}

}  // namespace ctid::mimo_srivc_parts

namespace ctid {

MimoEstimationResult mimo_srivc(const MimoData& data, const std::vector<SubmodelOrder>& orders,
                                const MimoRefinedIvOptions& options,
                                const std::optional<MimoAdditiveModel>& initial_model,
                                const std::function<void(int, int)>& progress) {
  options.validate();
  mimo_srivc_parts::check_orders(orders, data, options.direct_term);
  require(options.input_delays_samples.empty() ||
              static_cast<int>(options.input_delays_samples.size()) == data.input_count(),
          "mimo_srivc: input_delays_samples has ", options.input_delays_samples.size(),
          " entries but the data have ", data.input_count(),
          " inputs (one delay per input, in samples)");
  mimo_srivc_parts::Layout layout(orders, data.input_count(), data.output_count(),
                                  options.direct_term);
  if (options.siso_engine && layout.inputs == 1 && layout.outputs == 1 && !layout.direct) {
    if (initial_model) {
      require(initial_model->inputs() == 1 && initial_model->outputs() == 1 &&
                  !initial_model->has_direct_term(),
              "mimo_srivc: the initial model is ", initial_model->outputs(), " x ",
              initial_model->inputs(), initial_model->has_direct_term() ? " with" : " without",
              " a direct term but the data have 1 output and 1 input and no direct term is asked");
    }
    return mimo_srivc_parts::siso_result(layout, data, options, initial_model);
  }
  // Known input delays: whole samples shifted into the record once, the fractions left to the
  // filters (layout.input_fractions); every step below runs on the shifted record.
  if (options.initial_conditions == InitialConditions::estimate) layout.add_free_responses();
  const mimo_srivc_parts::DelayedInputs delayed =
      mimo_srivc_parts::delay_inputs(layout, data, options.input_delays_samples);
  const MimoData& record = delayed.data ? *delayed.data : data;
  return mimo_srivc_parts::estimate(layout, record, options, initial_model, delayed.seconds,
                                    progress);
}

}  // namespace ctid
