// Shared-pole refined IV for several inputs and outputs (mimo_srivc.h).
#include "ctid/refined_iv/mimo_srivc.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <utility>

#include <Eigen/Dense>
#include <Eigen/SVD>

#include "ctid/core/error.h"
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
#include "internal/mimo_layout.h"
#include "internal/refined_iv_engine.h"
#include "internal/scaled_least_squares.h"

namespace ctid {

namespace {

using Layout = internal::MimoLayout;

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

// Submodel i's free responses at the denominator a_i (layout.free_count > 0): `basis`, those
// of 1/(p^l_i A_i) from each unit initial state (N x s_i, s_i = n_i + l_i), and, when asked,
// `filtered[q - 1]` = p^q / A_i of them (q = 1..n_i), exact at the samples by one homogeneous
// recursion of the chain the SISO estimators use (internal::free_response_chain).
struct FreeResponses {
  Eigen::MatrixXd basis;
  std::vector<Eigen::MatrixXd> filtered;
};

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

// An iterate: the model and, with free responses (layout.free_count > 0), the coefficients of
// every output's free-response columns (free_count x outputs; 0 x outputs without).
struct Iterate {
  MimoAdditiveModel model;
  Eigen::MatrixXd free;
};

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

// Numerators fitted by least squares to every output for the given denominators.
// The model of denominators `a` whose numerators and D are the coefficients `b` of the
// numerator columns (u_count x outputs, one column per output).
MimoAdditiveModel model_from_columns(const Layout& layout, const std::vector<Polynomial>& a,
                                     const Eigen::MatrixXd& b) {
  std::vector<MimoSubmodel> submodels;
  for (int i = 0; i < layout.size(); ++i) {
    MimoSubmodel sub{
        a[static_cast<size_t>(i)], {}, layout.orders[static_cast<size_t>(i)].integrators};
    const int m = layout.orders[static_cast<size_t>(i)].m;
    for (int j = 0; j < layout.outputs; ++j) {
      for (int k = 0; k < layout.inputs; ++k) {
        // An estimate may be exactly zero (a numerator the data do not need).
        sub.b.push_back(
            Polynomial::trimmed(Eigen::VectorXd(b.block(layout.u_column(i, k, 0), j, m + 1, 1))));
      }
    }
    submodels.push_back(std::move(sub));
  }
  Eigen::MatrixXd direct;
  if (layout.direct) direct = b.middleRows(layout.d_at, layout.inputs).transpose();
  return MimoAdditiveModel(layout.inputs, layout.outputs, std::move(submodels), direct);
}

// The iterate of denominators `a` whose numerators, D and free responses are the
// coefficients `b` of every column (u_count x outputs).
Iterate iterate_from_columns(const Layout& layout, const std::vector<Polynomial>& a,
                             const Eigen::MatrixXd& b) {
  return {model_from_columns(layout, a, b), b.bottomRows(layout.free_count)};
}

Iterate fit_numerators(const Layout& layout, const MimoData& data,
                       const std::vector<Polynomial>& a) {
  const Eigen::MatrixXd u = numerator_regressors(layout, data, a);
  const Eigen::VectorXd s = internal::column_scales(u);
  return iterate_from_columns(
      layout, a,
      s.cwiseInverse().asDiagonal() *
          (u * s.cwiseInverse().asDiagonal()).colPivHouseholderQr().solve(data.outputs()));
}

// u S^-1 = Q R with S the columns' norms (column_scales), Q thin (N x columns): how the
// numerator columns, the same for every output, are projected out of each output's equations.
struct ScaledQr {
  Eigen::VectorXd scale;
  Eigen::MatrixXd q;
  Eigen::MatrixXd r;  // upper triangular
};

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

// The common-denominator state-variable-filter least squares over every channel, the MIMO form
// of the SISO start's LSSVF: A(p) y_j = sum_k B_jk(p) u_k with one A of degree n = sum n_i,
// every signal through 1 / (1 + p / lambda)^n. The numerator columns are the same for every
// output, so they are projected out once and A comes from a system of n unknowns. Its poles
// are grouped into the structure's submodels (group_into_submodels); none if they do not fit.
// Whether (1 + p / lambda)^order and its companion realisation (coefficients divided by the
// leading one) have every coefficient well inside double precision: a structure of a hundred
// modes would overflow them at most bandwidths.
bool binomial_filter_is_representable(int order, double lambda) {
  const double log_lambda = std::log10(lambda);
  for (int k = 0; k <= order; ++k) {
    const double log_binomial =
        (std::lgamma(order + 1.0) - std::lgamma(k + 1.0) - std::lgamma(order - k + 1.0)) /
        std::log(10.0);
    const double coefficient = log_binomial - k * log_lambda;         // of p^k in f
    const double realised = log_binomial + (order - k) * log_lambda;  // divided by the lead
    if (std::abs(coefficient) > 250.0 || std::abs(realised) > 250.0) return false;
  }
  return true;
}

std::optional<std::vector<Polynomial>> common_denominator_start(const Layout& layout,
                                                                const MimoData& data, double lambda,
                                                                Hold interpolation) {
  // With l integrators (in at most one submodel) the common form is A(p) p^l y_j = B_j(p) u:
  // the output's derivatives start at p^l, and A holds the other poles only.
  int n = 0;
  int l = 0;
  for (const SubmodelOrder& o : layout.orders) {
    n += o.n;
    l += o.integrators;
  }
  if (n == 0) return std::vector<Polynomial>(layout.orders.size(), Polynomial{1.0});
  int m = layout.direct ? n + l : 0;  // a direct term makes every channel biproper
  for (const SubmodelOrder& o : layout.orders) m = std::max(m, o.m + n - o.n + l - o.integrators);
  if (!binomial_filter_is_representable(n + l, lambda)) return std::nullopt;
  Polynomial f{1.0};
  for (int q = 0; q < n + l; ++q) f = f * Polynomial{1.0, 1.0 / lambda};
  const FilterRealization bank = derivative_filters(f);
  const SampledFilter on_outputs(bank, data.sample_time(), interpolation);
  Eigen::MatrixXd u(data.size(), layout.inputs * (m + 1));
  for (int k = 0; k < layout.inputs; ++k) {
    u.middleCols(k * (m + 1), m + 1) = filtered_input(layout, bank, data, k).leftCols(m + 1);
  }
  const Eigen::MatrixXd q = scaled_thin_qr(u).q;
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  for (int j = 0; j < layout.outputs; ++j) {
    const Eigen::MatrixXd fy = on_outputs.apply(data.outputs().col(j));
    Eigen::MatrixXd phi = -fy.middleCols(l + 1, n);
    phi -= q * (q.transpose() * phi);
    const Eigen::VectorXd y0 = fy.col(l) - q * (q.transpose() * fy.col(l));
    // Each output weighted by its own size, so that every channel counts alike.
    const double w = 1.0 / std::max(fy.col(l).squaredNorm(), 1e-300);
    normal += w * phi.transpose() * phi;
    rhs += w * phi.transpose() * y0;
  }
  const Eigen::VectorXd s = internal::column_scales(normal);
  const Eigen::VectorXd a_tail =
      s.cwiseInverse().asDiagonal() *
      (s.cwiseInverse().asDiagonal() * normal * s.cwiseInverse().asDiagonal())
          .colPivHouseholderQr()
          .solve(s.cwiseInverse().asDiagonal() * rhs);
  if (!a_tail.allFinite()) return std::nullopt;
  Eigen::VectorXd a(n + 1);
  a(0) = 1.0;
  a.tail(n) = a_tail;
  try {
    // A's poles grouped into the submodels that have poles besides integrators.
    std::vector<SubmodelOrder> with_poles;
    for (SubmodelOrder o : layout.orders) {
      if (o.n == 0) continue;
      o.m = std::min(o.m, o.n);
      o.integrators = 0;
      with_poles.push_back(o);
    }
    const AdditiveModel grouped = group_into_submodels(
        TransferFunction(Polynomial{1.0}, Polynomial(a)), with_poles, data.channel(0, 0));
    std::vector<Polynomial> denominators;
    int next = 0;
    for (const SubmodelOrder& o : layout.orders) {
      denominators.push_back(o.n == 0 ? Polynomial{1.0}
                                      : grouped.submodels()[static_cast<size_t>(next++)].a);
    }
    return denominators;
  } catch (const InvalidArgument&) {
    return std::nullopt;  // poles that do not fit the structure: not a candidate
  }
}

struct Step {
  std::optional<Iterate> model;
  std::string failure;  // why the step could not be taken (empty if it was)
  Termination kind = Termination::singular_equations;  // of a failure
  double reciprocal_condition = std::numeric_limits<double>::quiet_NaN();
};

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

// One step of the shared-pole iteration from `x` (see mimo_srivc.h).
Step iterate(const Layout& layout, const MimoData& data, const Iterate& x,
             Hold output_interpolation) {
  const int n = data.size();
  const int outputs = layout.outputs;
  const int submodels = layout.size();
  const MimoAdditiveModel& model = x.model;
  const std::vector<Polynomial> a = denominators(model);
  const Eigen::MatrixXd u = numerator_regressors(layout, data, a);
  std::vector<Eigen::MatrixXd> parts;
  const Eigen::MatrixXd direct = direct_outputs(layout, u, model);
  Eigen::MatrixXd total = direct;
  for (int i = 0; i < submodels; ++i) {
    parts.push_back(submodel_outputs(layout, u, x, i));
    total += parts.back();
  }

  // The numerator columns, scaled to unit norm, projected out with one thin QR.
  const ScaledQr factors = scaled_thin_qr(u);
  const Eigen::VectorXd& u_scale = factors.scale;
  const Eigen::MatrixXd& triangle = factors.r;
  const Eigen::MatrixXd& q = factors.q;
  const double r_max = triangle.diagonal().cwiseAbs().maxCoeff();
  if (!(triangle.diagonal().cwiseAbs().minCoeff() > 1e-12 * r_max)) {
    return {std::nullopt, "the numerator regressors are numerically collinear"};
  }

  const InstrumentSources sources(layout, data, a);

  // Per output: the denominator regressors -p^q / A_i y~_ij, the instruments -p^q / A_i x_ij
  // (x_ij submodel i's own output, B_ij. / A_i u), and the filtered residuals 1 / A_i y~_ij
  // (one column per submodel: the K right-hand sides of (29)).
  Eigen::MatrixXd m_a = Eigen::MatrixXd::Zero(layout.a_count, layout.a_count);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(layout.a_count, layout.columns());
  Eigen::VectorXd phi_norm = Eigen::VectorXd::Zero(layout.a_count);
  Eigen::VectorXd psi_norm = Eigen::VectorXd::Zero(layout.a_count);
  std::vector<Eigen::MatrixXd> q_phi(static_cast<size_t>(outputs));
  std::vector<Eigen::MatrixXd> q_upsilon(static_cast<size_t>(outputs));
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
  if (!m_a.allFinite() || !rhs.allFinite()) {
    return {std::nullopt, "a filtered signal is not finite", Termination::non_finite};
  }

  // The denominators' projected system, rows and columns scaled to unit norm.
  const auto scale_of = [](Eigen::VectorXd squared) {
    for (Eigen::Index k = 0; k < squared.size(); ++k) {
      squared(k) = squared(k) > 0.0 ? std::sqrt(squared(k)) : 1.0;
    }
    return squared;
  };
  const Eigen::VectorXd s_phi = scale_of(phi_norm);
  const Eigen::VectorXd s_psi = scale_of(psi_norm);
  const Eigen::MatrixXd scaled =
      s_psi.cwiseInverse().asDiagonal() * m_a * s_phi.cwiseInverse().asDiagonal();
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(scaled);
  const double rcond = lu.rcond();
  if (!(rcond >= 1e-14)) {
    return {std::nullopt, "the denominators' equations are singular",
            Termination::singular_equations, rcond};
  }
  const Eigen::MatrixXd alpha =
      s_phi.cwiseInverse().asDiagonal() * lu.solve(s_psi.cwiseInverse().asDiagonal() * rhs);

  // Each submodel's block of its own column: its denominator, and per output its numerators.
  std::vector<MimoSubmodel> next;
  for (int i = 0; i < submodels; ++i) {
    const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
    Eigen::VectorXd coefficients(o.n + 1);
    coefficients(0) = 1.0;
    coefficients.tail(o.n) = alpha.block(layout.a_at[static_cast<size_t>(i)], i, o.n, 1);
    if (!coefficients.allFinite()) {
      return {std::nullopt, "an iterate is not finite", Termination::non_finite};
    }
    if (!(std::abs(coefficients(o.n)) > 0.0)) {
      return {std::nullopt, "a denominator lost its leading coefficient (a pole at infinity)",
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
  // (The denominators were checked above.)
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

Iterations run_iterations(const Layout& layout, const MimoData& data, Iterate model,
                          int max_iterations, double tolerance, Hold output_interpolation,
                          const std::function<void(int, int)>& progress = {}) {
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

// Denominators from the most prominent peaks of the summed-power FRF over every channel
// (summed_power_frf of the Welch FRF matrix, segments of `segment_length` samples), one mode
// per peak (mode_from_peak); none unless every submodel is a mode (n = 2) and the FRF has as
// many peaks as there are modes.
std::optional<std::vector<Polynomial>> frf_peak_denominators(const Layout& layout,
                                                             const MimoData& data,
                                                             int segment_length) {
  // Integrators alone (a rigid-body submodel) have A = 1; every other submodel must be a mode.
  int modes = 0;
  for (const SubmodelOrder& o : layout.orders) {
    if (o.n == 2 && o.integrators == 0) {
      ++modes;
    } else if (o.n != 0) {
      return std::nullopt;
    }
  }
  if (modes == 0 || data.size() < segment_length) return std::nullopt;
  WelchOptions welch;
  welch.segment_length = segment_length;
  PeakOptions options;
  options.max_peaks = modes;
  std::vector<ResonancePeak> peaks =
      resonance_peaks(summed_power_frf(welch_frf(data, welch)), options);
  if (static_cast<int>(peaks.size()) < modes) return std::nullopt;
  std::sort(peaks.begin(), peaks.end(), [](const ResonancePeak& x, const ResonancePeak& y) {
    return x.frequency < y.frequency;
  });
  std::vector<Polynomial> a;
  auto peak = peaks.begin();
  for (const SubmodelOrder& o : layout.orders) {
    a.push_back(o.n == 0 ? Polynomial{1.0} : mode_from_peak(*peak++));
  }
  return a;
}

// The start. Candidates: the common-denominator fit at each bandwidth of the SISO start's grid
// (Nyquist / 128 up to Nyquist by octaves), numerators by least squares; the
// kRefinedCandidates of them with the smallest relative output error and the FRF-peak
// candidates (default and fine Welch segments) are each given kRefinementIterations of the
// iteration, and the best refined one is the start (a candidate that fits well as it is can
// still lead the iteration astray).
constexpr int kRefinedCandidates = 3;

// The finer of the FRF-peak candidates' Welch segments: the largest power of two of at most a
// quarter of the record (seven half-overlapping averages), so that close modes separate.
int fine_segment_length(int samples) {
  int length = default_segment_length(samples);
  while (length * 2 <= samples / 4) length *= 2;
  return length;
}
constexpr int kRefinementIterations = 5;

Iterate automatic_start(const Layout& layout, const MimoData& data, Hold interpolation) {
  std::vector<std::pair<double, Iterate>> candidates;
  const double nyquist = M_PI / data.sample_time();
  for (double lambda = nyquist / 128.0; lambda <= nyquist * 1.0001; lambda *= 2.0) {
    const std::optional<std::vector<Polynomial>> a =
        common_denominator_start(layout, data, lambda, interpolation);
    if (!a) continue;
    Iterate candidate = fit_numerators(layout, data, *a);
    const double cost = relative_output_error(layout, data, candidate);
    if (std::isfinite(cost)) candidates.emplace_back(cost, std::move(candidate));
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const auto& x, const auto& y) { return x.first < y.first; });
  if (candidates.size() > static_cast<size_t>(kRefinedCandidates)) {
    candidates.erase(candidates.begin() + kRefinedCandidates, candidates.end());
  }
  // The FRF-peak candidates are refined whatever their first fit: lightly damped modes put at
  // the right frequencies with a rough damping fit badly before the iteration corrects them.
  std::vector<int> lengths{default_segment_length(data.size())};
  if (fine_segment_length(data.size()) > lengths[0]) {
    lengths.push_back(fine_segment_length(data.size()));
  }
  for (int length : lengths) {
    try {
      const std::optional<std::vector<Polynomial>> a = frf_peak_denominators(layout, data, length);
      if (a) {
        Iterate candidate = fit_numerators(layout, data, *a);
        const double cost = relative_output_error(layout, data, candidate);
        if (std::isfinite(cost)) candidates.emplace_back(cost, std::move(candidate));
      }
    } catch (const InvalidArgument&) {
      // an FRF that gives no start is not a candidate
    }
  }
  require(!candidates.empty(), "mimo_srivc: no start found from the data (neither the ",
          "common-denominator least squares at any filter bandwidth nor the FRF peaks gave a ",
          "model of this structure); give an initial model");
  std::optional<Iterations> best;
  for (auto& [cost, candidate] : candidates) {
    Iterations refined = run_iterations(layout, data, std::move(candidate), kRefinementIterations,
                                        0.0, interpolation);
    if (!best || refined.cost < best->cost) best = std::move(refined);
  }
  return std::move(best->model);
}

// Sandwich covariance R^-1 Q R^-1 of the estimate: output j's gradient is [psi_j, 0.., U (in
// j's numerator slot), 0..], R the sum of their products and Q that of the AR-whitened
// gradients (adjoint_ar_filter) weighted by the outputs' innovation covariance (below).
Eigen::MatrixXd mimo_covariance(const Layout& layout, const MimoData& data, const Iterate& x,
                                const Eigen::MatrixXd& u, const Eigen::MatrixXd& residuals,
                                NoiseAssumption noise, int max_ar_order) {
  const MimoAdditiveModel& model = x.model;
  const int n = data.size();
  const int pa = layout.a_count;
  const int pu = layout.u_count;
  const int p = pa + layout.outputs * pu;
  const InstrumentSources sources(layout, data, denominators(model));
  std::vector<Eigen::MatrixXd> psi(static_cast<size_t>(layout.outputs), Eigen::MatrixXd(n, pa));
  Eigen::VectorXd s_a = Eigen::VectorXd::Zero(pa);
  for (int j = 0; j < layout.outputs; ++j) {
    sources.denominator_instrument(x, j, psi[static_cast<size_t>(j)]);
    s_a += psi[static_cast<size_t>(j)].colwise().squaredNorm().transpose();
  }
  for (Eigen::Index c = 0; c < pa; ++c) s_a(c) = s_a(c) > 0.0 ? std::sqrt(s_a(c)) : 1.0;
  const Eigen::VectorXd s_u = internal::column_scales(u);
  const Eigen::MatrixXd us = u * s_u.cwiseInverse().asDiagonal();
  Eigen::MatrixXd r = Eigen::MatrixXd::Zero(p, p);
  Eigen::MatrixXd q = Eigen::MatrixXd::Zero(p, p);
  const double dof = static_cast<double>(n) / static_cast<double>(std::max(1, n - pu - pa));
  // Per output: its (whitened) gradient g_j ((pa + pu) x N) and its innovations.
  std::vector<Eigen::MatrixXd> g(static_cast<size_t>(layout.outputs));
  Eigen::MatrixXd innovations(n, layout.outputs);
  Eigen::VectorXd variance(layout.outputs);  // of each output's innovations (AR or residual)
  for (int j = 0; j < layout.outputs; ++j) {
    const Eigen::MatrixXd ps = psi[static_cast<size_t>(j)] * s_a.cwiseInverse().asDiagonal();
    const int at = pa + j * pu;
    r.topLeftCorner(pa, pa) += ps.transpose() * ps;
    r.block(0, at, pa, pu) = ps.transpose() * us;
    r.block(at, 0, pu, pa) = r.block(0, at, pa, pu).transpose();
    r.block(at, at, pu, pu) = us.transpose() * us;
    Eigen::MatrixXd both(n, pa + pu);
    both << ps, us;
    if (noise == NoiseAssumption::white) {
      g[static_cast<size_t>(j)] = both.transpose();
      innovations.col(j) = residuals.col(j);
      variance(j) = residuals.col(j).squaredNorm() / static_cast<double>(n) * dof;
    } else {
      const AutoregressiveModel ar = fit_autoregressive(residuals.col(j), max_ar_order);
      g[static_cast<size_t>(j)] = adjoint_ar_filter(both, ar);
      variance(j) = ar.innovation_variance * dof;
      const Eigen::Index order = ar.coefficients.size() - 1;
      for (Eigen::Index t = 0; t < n; ++t) {
        double e = residuals(t, j);
        for (Eigen::Index k = 1; k <= std::min(order, t); ++k) {
          e += ar.coefficients(k) * residuals(t - k, j);
        }
        innovations(t, j) = e;
      }
    }
  }
  // The outputs' innovations are white in time but may be correlated with each other (one
  // disturbance seen by every sensor): Q = sum_jl Sigma_jl g_j g_l'. With Sigma diagonal this is
  // the independent-outputs sandwich; on the measured flexible structure the cross terms
  // make the shared denominators' errors several times larger.
  // Sigma: each output's own innovation variance (as the SISO covariance has it) and the
  // correlations of the innovation series between outputs.
  const Eigen::MatrixXd products = innovations.transpose() * innovations;
  Eigen::MatrixXd sigma(layout.outputs, layout.outputs);
  for (int j = 0; j < layout.outputs; ++j) {
    for (int l = 0; l < layout.outputs; ++l) {
      const double norms = std::sqrt(products(j, j) * products(l, l));
      const double correlation = j == l ? 1.0 : (norms > 0.0 ? products(j, l) / norms : 0.0);
      sigma(j, l) = correlation * std::sqrt(variance(j) * variance(l));
    }
  }
  for (int l = 0; l < layout.outputs; ++l) {
    const Eigen::MatrixXd& gl = g[static_cast<size_t>(l)];
    Eigen::MatrixXd weighted_a = Eigen::MatrixXd::Zero(pa, n);
    for (int j = 0; j < layout.outputs; ++j) {
      weighted_a += sigma(j, l) * g[static_cast<size_t>(j)].topRows(pa);
    }
    const int at = pa + l * pu;
    q.topLeftCorner(pa, pa) += weighted_a * gl.topRows(pa).transpose();
    q.block(0, at, pa, pu) = weighted_a * gl.bottomRows(pu).transpose();
    q.block(at, 0, pu, pa) = q.block(0, at, pa, pu).transpose();
  }
  // The numerator blocks: white noise leaves every output's numerator gradient U itself.
  const Eigen::MatrixXd uu =
      noise == NoiseAssumption::white ? Eigen::MatrixXd(us.transpose() * us) : Eigen::MatrixXd();
  for (int j = 0; j < layout.outputs; ++j) {
    for (int l = j; l < layout.outputs; ++l) {
      const Eigen::MatrixXd block =
          noise == NoiseAssumption::white
              ? Eigen::MatrixXd(sigma(j, l) * uu)
              : Eigen::MatrixXd(sigma(j, l) * g[static_cast<size_t>(j)].bottomRows(pu) *
                                g[static_cast<size_t>(l)].bottomRows(pu).transpose());
      q.block(pa + j * pu, pa + l * pu, pu, pu) = block;
      if (l != j) q.block(pa + l * pu, pa + j * pu, pu, pu) = block.transpose();
    }
  }
  const Eigen::MatrixXd r_inv = r.completeOrthogonalDecomposition().pseudoInverse();
  Eigen::VectorXd scale(p);
  scale << s_a, s_u.replicate(layout.outputs, 1);
  return scale.cwiseInverse().asDiagonal() * (r_inv * q * r_inv) *
         scale.cwiseInverse().asDiagonal();
}

// The mode shape of a residue matrix (see MimoMode) and its share of the residue.
Eigen::VectorXcd principal_shape(const Eigen::MatrixXcd& residue, double* share = nullptr) {
  const Eigen::JacobiSVD<Eigen::MatrixXcd> svd(residue, Eigen::ComputeThinU);
  Eigen::VectorXcd shape = svd.matrixU().col(0);
  Eigen::Index largest = 0;
  shape.cwiseAbs().maxCoeff(&largest);
  if (std::abs(shape(largest)) > 0.0) shape *= std::conj(shape(largest)) / std::abs(shape(largest));
  if (share != nullptr) {
    const Eigen::VectorXd sigma = svd.singularValues();
    *share = sigma.squaredNorm() > 0.0 ? sigma(0) * sigma(0) / sigma.squaredNorm() : 1.0;
  }
  return shape;
}

// Residue matrix of submodel i (second order) at its upper pole, from its denominator
// coefficients and per-channel numerator coefficients (numerators[j * inputs + k]).
// The root with a non-negative imaginary part of 1 + a1 s + a2 s^2.
std::complex<double> upper_pole(double a1, double a2) {
  const std::complex<double> pole =
      (-a1 + std::sqrt(std::complex<double>(a1 * a1 - 4.0 * a2))) / (2.0 * a2);
  return pole.imag() < 0.0 ? std::conj(pole) : pole;
}

Eigen::MatrixXcd residue_matrix(const Layout& layout, double a1, double a2,
                                const std::vector<Eigen::VectorXd>& numerators) {
  const std::complex<double> pole = upper_pole(a1, a2);
  const std::complex<double> slope = a1 + 2.0 * a2 * pole;
  Eigen::MatrixXcd res(layout.outputs, layout.inputs);
  for (int j = 0; j < layout.outputs; ++j) {
    for (int k = 0; k < layout.inputs; ++k) {
      const Eigen::VectorXd& b = numerators[static_cast<size_t>(j * layout.inputs + k)];
      std::complex<double> value = 0.0;
      for (Eigen::Index r = b.size() - 1; r >= 0; --r) value = value * pole + b(r);
      res(j, k) = value / slope;
    }
  }
  return res;
}

// Every second-order submodel as a MimoMode, with delta-method standard errors when the
// covariance is given (numerical derivatives of the shape with respect to the submodel's own
// parameters).
std::vector<MimoMode> modes_of(const Layout& layout, const MimoAdditiveModel& model,
                               const Eigen::MatrixXd& covariance) {
  std::vector<MimoMode> modes;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < layout.size(); ++i) {
    const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
    const Polynomial& a = model[i].a;
    // A complex pair only (not one times integrators).
    if (o.n != 2 || o.integrators > 0 || !(a[1] * a[1] < 4.0 * a[2])) continue;
    std::vector<Eigen::VectorXd> numerators;
    std::vector<int> indices{layout.a_index(i, 1), layout.a_index(i, 2)};
    for (int j = 0; j < layout.outputs; ++j) {
      for (int k = 0; k < layout.inputs; ++k) {
        Eigen::VectorXd b = Eigen::VectorXd::Zero(o.m + 1);
        const Polynomial& given = model.numerator(i, j, k);
        for (int r = 0; r <= std::min(o.m, given.degree()); ++r) b(r) = given[r];
        numerators.push_back(b);
        for (int r = 0; r <= o.m; ++r)
          indices.push_back(layout.b_index(j, layout.u_column(i, k, r)));
      }
    }
    MimoMode mode;
    mode.submodel = i;
    mode.natural_frequency = 1.0 / std::sqrt(a[2]);
    mode.damping_ratio = a[1] / (2.0 * std::sqrt(a[2]));
    const auto shape_at = [&](double a1, double a2, const std::vector<Eigen::VectorXd>& b) {
      return principal_shape(residue_matrix(layout, a1, a2, b));
    };
    const Eigen::MatrixXcd res = residue_matrix(layout, a[1], a[2], numerators);
    mode.shape = principal_shape(res, &mode.rank_one_share);
    mode.participation = res.transpose() * mode.shape.conjugate();
    mode.natural_frequency_se = mode.damping_ratio_se = nan;
    mode.shape_se_real = mode.shape_se_imag = Eigen::VectorXd::Constant(layout.outputs, nan);
    if (covariance.size() > 0) {
      const Eigen::Index m = static_cast<Eigen::Index>(indices.size());
      Eigen::MatrixXd c(m, m);
      for (Eigen::Index x = 0; x < m; ++x) {
        for (Eigen::Index y = 0; y < m; ++y) c(x, y) = covariance(indices[x], indices[y]);
      }
      // w_n = a2^(-1/2), zeta = a1 / (2 sqrt(a2)).
      Eigen::RowVector2d dw(0.0, -0.5 * std::pow(a[2], -1.5));
      Eigen::RowVector2d dz(0.5 / std::sqrt(a[2]), -0.25 * a[1] * std::pow(a[2], -1.5));
      mode.natural_frequency_se = std::sqrt((dw * c.topLeftCorner(2, 2) * dw.transpose())(0));
      mode.damping_ratio_se = std::sqrt((dz * c.topLeftCorner(2, 2) * dz.transpose())(0));
      // Central differences of [Re shape; Im shape] in every one of the submodel's parameters.
      Eigen::MatrixXd jac(2 * layout.outputs, m);
      for (Eigen::Index x = 0; x < m; ++x) {
        double a1 = a[1];
        double a2 = a[2];
        std::vector<Eigen::VectorXd> b = numerators;
        double* value = nullptr;
        if (x == 0) {
          value = &a1;
        } else if (x == 1) {
          value = &a2;
        } else {
          const Eigen::Index c0 = x - 2;
          value = &b[static_cast<size_t>(c0 / (o.m + 1))](c0 % (o.m + 1));
        }
        const double step = 1e-6 * std::max(std::abs(*value), 1e-6 * std::abs(a[x == 0 ? 1 : 2]));
        const double saved = *value;
        *value = saved + step;
        const Eigen::VectorXcd plus = shape_at(a1, a2, b);
        *value = saved - step;
        const Eigen::VectorXcd minus = shape_at(a1, a2, b);
        const Eigen::VectorXcd d = (plus - minus) / (2.0 * step);
        jac.col(x) << d.real(), d.imag();
      }
      const Eigen::VectorXd var = (jac * c * jac.transpose()).diagonal();
      mode.shape_se_real = var.head(layout.outputs).cwiseMax(0.0).cwiseSqrt();
      mode.shape_se_imag = var.tail(layout.outputs).cwiseMax(0.0).cwiseSqrt();
    }
    modes.push_back(std::move(mode));
  }
  return modes;
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

}  // namespace

double modal_assurance(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b) {
  require(a.size() == b.size(), "modal_assurance: shapes of ", a.size(), " and ", b.size(),
          " entries; they must have equal lengths");
  const double aa = a.squaredNorm();
  const double bb = b.squaredNorm();
  return aa > 0.0 && bb > 0.0 ? std::norm(a.dot(b)) / (aa * bb) : 0.0;
}

Eigen::MatrixXd modal_assurance(const std::vector<MimoMode>& a, const std::vector<MimoMode>& b) {
  Eigen::MatrixXd mac(static_cast<Eigen::Index>(a.size()), static_cast<Eigen::Index>(b.size()));
  for (size_t x = 0; x < a.size(); ++x) {
    for (size_t y = 0; y < b.size(); ++y) {
      mac(static_cast<Eigen::Index>(x), static_cast<Eigen::Index>(y)) =
          modal_assurance(a[x].shape, b[y].shape);
    }
  }
  return mac;
}

std::vector<MimoMode> mimo_modes(const MimoAdditiveModel& model,
                                 const std::vector<SubmodelOrder>& orders,
                                 const Eigen::MatrixXd& covariance) {
  require(static_cast<int>(orders.size()) == model.size(), "mimo_modes: ", orders.size(),
          " orders for a model of ", model.size(), " submodels");
  const Layout layout(orders, model.inputs(), model.outputs(), model.has_direct_term());
  require(covariance.size() == 0 ||
              (covariance.rows() == covariance.cols() &&
               covariance.rows() == layout.a_count + layout.outputs * layout.u_count),
          "mimo_modes: the covariance is ", covariance.rows(), " x ", covariance.cols(),
          "; the model has ", layout.a_count + layout.outputs * layout.u_count, " parameters");
  return modes_of(layout, model, covariance);
}

namespace {

// One input and output through the SISO additive estimator, its result in MIMO form: the
// parameters theta_i = [a_i; b_i] of (3) reordered into the shared-pole layout (every a-block,
// then every numerator).
MimoEstimationResult siso_result(const Layout& layout, const MimoData& data,
                                 const MimoRefinedIvOptions& options,
                                 const std::optional<MimoAdditiveModel>& initial_model) {
  RefinedIvOptions siso;
  siso.max_iterations = options.max_iterations;
  siso.tolerance = options.tolerance;
  siso.output_interpolation = options.output_interpolation;
  siso.noise = options.noise;
  siso.noise_model_max_order = options.noise_model_max_order;
  siso.compute_covariance = options.compute_covariance;
  siso.initial_conditions = options.initial_conditions;
  if (!options.input_delays.empty()) {
    const DelaySplit delay =
        split_delay(options.input_delays.front() * data.sample_time(), data.sample_time());
    siso.input_delay = delay.samples;
    siso.input_delay_fraction = delay.fraction;
  }
  if (initial_model) siso.initial_model = initial_model->channel(0, 0).with_input_delay(0.0);
  const EstimationResult r = additive_srivc(data.channel(0, 0), layout.orders, siso);
  MimoEstimationResult result;
  std::vector<MimoSubmodel> submodels;
  for (const Submodel& s : r.model.submodels()) submodels.push_back({s.a, {s.b}, s.integrators});
  result.model = MimoAdditiveModel(1, 1, std::move(submodels), {},
                                   Eigen::VectorXd::Constant(1, r.model.input_delay()));
  result.termination = r.termination;
  result.message = r.message;
  result.iterations = r.iterations;
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

// Free-response columns stay general too.
RankOneFit rank_one_residues(const Layout& layout, const MimoData& data, const Iterate& start) {
  const MimoAdditiveModel& general = start.model;
  struct Mode {
    int submodel;
    bool complex;  // m_i = 1
    std::complex<double> pole;
    int at;  // first basis column: e_0..e_{nu-1}, then f_0..f_{nu-1} when complex
    Eigen::VectorXcd psi;
    Eigen::VectorXcd l;
  };
  const int nu = layout.inputs;
  const int ny = layout.outputs;
  const Eigen::MatrixXd u = numerator_regressors(layout, data, denominators(general));
  std::vector<Mode> modes;
  std::vector<bool> in_mode(static_cast<size_t>(layout.u_count), false);
  int p = 0;
  for (int i = 0; i < layout.size(); ++i) {
    const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
    const Polynomial& a = general[i].a;
    if (o.n != 2 || o.integrators > 0 || o.m > 1 || !(a[1] * a[1] < 4.0 * a[2])) continue;
    modes.push_back({i, o.m == 1, upper_pole(a[1], a[2]), p, {}, {}});
    p += o.m == 1 ? 2 * nu : nu;
    for (int k = 0; k < nu; ++k) {
      for (int r = 0; r <= o.m; ++r) in_mode[static_cast<size_t>(layout.u_column(i, k, r))] = true;
    }
  }
  std::vector<int> others;
  for (int c = 0; c < layout.u_count; ++c) {
    if (!in_mode[static_cast<size_t>(c)]) others.push_back(c);
  }
  if (modes.empty()) return {start, 0, 0};
  const int n_modes = static_cast<int>(modes.size());
  const int n_other = static_cast<int>(others.size());
  const int p_all = p + n_other;

  // The basis F = [e, f of every mode | the other columns] and its thin QR.
  Eigen::MatrixXd f(data.size(), p_all);
  for (const Mode& m : modes) {
    for (int k = 0; k < nu; ++k) {
      const auto e = u.col(layout.u_column(m.submodel, k, 0));
      f.col(m.at + k) = e;
      if (m.complex) {
        f.col(m.at + nu + k) =
            -(u.col(layout.u_column(m.submodel, k, 1)) - m.pole.real() * e) / m.pole.imag();
      }
    }
  }
  for (int c = 0; c < n_other; ++c) f.col(p + c) = u.col(others[static_cast<size_t>(c)]);
  const ScaledQr qr = scaled_thin_qr(f);
  // F = Q R S (S the column norms): R S maps coefficients of F to the QR coordinates, q_y = Q^T y.
  const Eigen::MatrixXd r = qr.r * qr.scale.asDiagonal();
  const Eigen::MatrixXd q_y = qr.q.transpose() * data.outputs();

  // Start: the principal singular pair of each mode's c = A'(s) Res matrix.
  for (Mode& m : modes) {
    Eigen::MatrixXcd c(ny, nu);
    for (int j = 0; j < ny; ++j) {
      for (int k = 0; k < nu; ++k) {
        const Polynomial& b = general.numerator(m.submodel, j, k);
        std::complex<double> value = 0.0;
        for (int q = b.degree(); q >= 0; --q) value = value * m.pole + b[q];
        c(j, k) = value;
      }
    }
    if (!m.complex) c = c.real().cast<std::complex<double>>();
    const Eigen::JacobiSVD<Eigen::MatrixXcd> svd(c, Eigen::ComputeThinU | Eigen::ComputeThinV);
    m.psi = svd.matrixU().col(0) * svd.singularValues()(0);
    m.l = svd.matrixV().col(0).conjugate();
    if (!m.complex) {
      // A real matrix's singular vectors may carry a common phase: take it out.
      Eigen::Index big = 0;
      m.psi.cwiseAbs().maxCoeff(&big);
      const std::complex<double> phase = m.psi(big) / std::abs(m.psi(big));
      m.psi = (m.psi / phase).real().cast<std::complex<double>>();
      m.l = (m.l * phase).real().cast<std::complex<double>>();
    }
  }

  // Coefficients of output j in F's columns for given shapes and participations.
  const auto theta_of = [&](int j, const Eigen::VectorXd& general_part) {
    Eigen::VectorXd theta(p_all);
    for (const Mode& m : modes) {
      for (int k = 0; k < nu; ++k) {
        const std::complex<double> c = m.psi(j) * m.l(k);
        theta(m.at + k) = c.real();
        if (m.complex) theta(m.at + nu + k) = -c.imag();
      }
    }
    theta.tail(n_other) = general_part;
    return theta;
  };
  Eigen::MatrixXd other(n_other, ny);  // the general columns' coefficients, per output
  double cost = std::numeric_limits<double>::infinity();
  int iteration = 0;
  constexpr int kMaxSweeps = 2000;
  for (iteration = 1; iteration <= kMaxSweeps; ++iteration) {
    // Shapes (and the other columns), output by output: theta_j = T(L) [Re psi, Im psi, other].
    int q_cols = n_other;
    for (const Mode& m : modes) q_cols += m.complex ? 2 : 1;
    Eigen::MatrixXd t = Eigen::MatrixXd::Zero(p_all, q_cols);
    int col = 0;
    for (const Mode& m : modes) {
      for (int k = 0; k < nu; ++k) {
        // Re c = Re psi Re L - Im psi Im L; -Im c = -(Re psi Im L + Im psi Re L).
        t(m.at + k, col) = m.l(k).real();
        if (m.complex) {
          t(m.at + k, col + 1) = -m.l(k).imag();
          t(m.at + nu + k, col) = -m.l(k).imag();
          t(m.at + nu + k, col + 1) = -m.l(k).real();
        }
      }
      col += m.complex ? 2 : 1;
    }
    for (int c = 0; c < n_other; ++c) t(p + c, col + c) = 1.0;
    const Eigen::MatrixXd shapes = (r * t).colPivHouseholderQr().solve(q_y);
    col = 0;
    for (Mode& m : modes) {
      for (int j = 0; j < ny; ++j) {
        m.psi(j) = m.complex ? std::complex<double>(shapes(col, j), shapes(col + 1, j))
                             : std::complex<double>(shapes(col, j), 0.0);
      }
      col += m.complex ? 2 : 1;
    }
    other = shapes.bottomRows(n_other);
    // Participations, every output together: theta_j = S(psi_j) lambda + [0; other_j].
    int l_cols = 0;
    for (const Mode& m : modes) l_cols += m.complex ? 2 * nu : nu;
    Eigen::MatrixXd stacked(static_cast<Eigen::Index>(ny) * p_all, l_cols);
    Eigen::VectorXd target(static_cast<Eigen::Index>(ny) * p_all);
    for (int j = 0; j < ny; ++j) {
      Eigen::MatrixXd s_j = Eigen::MatrixXd::Zero(p_all, l_cols);
      int at = 0;
      for (const Mode& m : modes) {
        const double re = m.psi(j).real();
        const double im = m.psi(j).imag();
        for (int k = 0; k < nu; ++k) {
          if (m.complex) {
            // lambda = [Re L_0..Re L_{nu-1}, Im L_0..Im L_{nu-1}] of this mode.
            s_j(m.at + k, at + k) = re;
            s_j(m.at + k, at + nu + k) = -im;
            s_j(m.at + nu + k, at + k) = -im;
            s_j(m.at + nu + k, at + nu + k) = -re;
          } else {
            s_j(m.at + k, at + k) = re;
          }
        }
        at += m.complex ? 2 * nu : nu;
      }
      Eigen::VectorXd fixed = Eigen::VectorXd::Zero(p_all);
      fixed.tail(n_other) = other.col(j);
      stacked.middleRows(static_cast<Eigen::Index>(j) * p_all, p_all) = r * s_j;
      target.segment(static_cast<Eigen::Index>(j) * p_all, p_all) = q_y.col(j) - r * fixed;
    }
    const Eigen::VectorXd lambda = stacked.colPivHouseholderQr().solve(target);
    int at = 0;
    for (Mode& m : modes) {
      for (int k = 0; k < nu; ++k) {
        m.l(k) = m.complex ? std::complex<double>(lambda(at + k), lambda(at + nu + k))
                           : std::complex<double>(lambda(at + k), 0.0);
      }
      at += m.complex ? 2 * nu : nu;
      // Scale: psi of unit length (the product psi L' is what the model holds).
      const double norm = m.psi.norm();
      if (norm > 0.0) {
        m.psi /= norm;
        m.l *= norm;
      }
    }
    double next = 0.0;
    for (int j = 0; j < ny; ++j) next += (q_y.col(j) - r * theta_of(j, other.col(j))).squaredNorm();
    const bool done = !(next < cost * (1.0 - 1e-13)) && iteration > 1;
    cost = next;
    if (done || !std::isfinite(next)) break;
  }

  // The model: each mode's numerators from c = psi L', the other columns as fitted.
  Eigen::MatrixXd b(layout.u_count, ny);
  for (int c = 0; c < n_other; ++c) b.row(others[static_cast<size_t>(c)]) = other.row(c);
  for (const Mode& m : modes) {
    for (int j = 0; j < ny; ++j) {
      for (int k = 0; k < nu; ++k) {
        const std::complex<double> c = m.psi(j) * m.l(k);
        const double n1 = m.complex ? c.imag() / m.pole.imag() : 0.0;
        b(layout.u_column(m.submodel, k, 0), j) = c.real() - m.pole.real() * n1;
        if (m.complex) b(layout.u_column(m.submodel, k, 1), j) = n1;
      }
    }
  }
  return {{model_from_columns(layout, denominators(general), b)
               .with_input_delays(general.input_delays()),
           b.bottomRows(layout.free_count)},
          iteration,
          n_modes};
}

// The layout without free responses: that of the model's parameters and the covariance.
Layout model_layout(const Layout& layout) {
  Layout plain(layout.orders, layout.inputs, layout.outputs, layout.direct);
  plain.input_fractions = layout.input_fractions;
  return plain;
}

// The model's block of the joint covariance of the parameters and the free responses' coefficients
// (docs/decisions/0010): the free responses' uncertainty is accounted for, their entries dropped.
Eigen::MatrixXd model_block(const Layout& layout, const Eigen::MatrixXd& joint) {
  if (layout.free_count == 0) return joint;
  std::vector<Eigen::Index> keep;
  for (int c = 0; c < layout.a_count; ++c) keep.push_back(c);
  for (int j = 0; j < layout.outputs; ++j) {
    for (int c = 0; c < layout.model_columns(); ++c) keep.push_back(layout.b_index(j, c));
  }
  const auto p = static_cast<Eigen::Index>(keep.size());
  Eigen::MatrixXd block(p, p);
  for (Eigen::Index x = 0; x < p; ++x) {
    for (Eigen::Index y = 0; y < p; ++y) {
      block(x, y) = joint(keep[static_cast<size_t>(x)], keep[static_cast<size_t>(y)]);
    }
  }
  return block;
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

}  // namespace

MimoEstimationResult mimo_srivc(const MimoData& data, const std::vector<SubmodelOrder>& orders,
                                const MimoRefinedIvOptions& options,
                                const std::optional<MimoAdditiveModel>& initial_model,
                                const std::function<void(int, int)>& progress) {
  options.validate();
  check_orders(orders, data, options.direct_term);
  require(options.input_delays.empty() ||
              static_cast<int>(options.input_delays.size()) == data.input_count(),
          "mimo_srivc: input_delays has ", options.input_delays.size(),
          " entries but the data have ", data.input_count(),
          " inputs (one delay per input, in samples)");
  Layout layout(orders, data.input_count(), data.output_count(), options.direct_term);
  if (options.siso_engine && layout.inputs == 1 && layout.outputs == 1 && !layout.direct) {
    if (initial_model) {
      require(initial_model->inputs() == 1 && initial_model->outputs() == 1 &&
                  !initial_model->has_direct_term(),
              "mimo_srivc: the initial model is ", initial_model->outputs(), " x ",
              initial_model->inputs(), initial_model->has_direct_term() ? " with" : " without",
              " a direct term but the data have 1 output and 1 input and no direct term is asked");
    }
    return siso_result(layout, data, options, initial_model);
  }
  // Known input delays: whole samples shifted into the record once, the fractions left to the
  // filters (layout.input_fractions); every step below runs on the shifted record.
  if (options.initial_conditions == InitialConditions::estimate) layout.add_free_responses();
  const DelayedInputs delayed = delay_inputs(layout, data, options.input_delays);
  const MimoData& record = delayed.data ? *delayed.data : data;
  return estimate(layout, record, options, initial_model, delayed.seconds, progress);
}

}  // namespace ctid
