// The refined IV iteration (29) shared by every estimator of González et al.: per iteration
// and submodel, one filter bank of u through 1/(p^l A_i) (regressor B-part, model output),
// one cascade p^k B_i/(p^l A_i^2) of the instrument source (u or S_uo r), and one bank of the
// residual output y~_i (23) through 1/A_i. Columns are scaled to unit norm before solving.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/estimation/validation.h"
#include "ctid/estimation/verdict.h"
#include "ctid/filtering/filter_bank.h"
#include "ctid/refined_iv/covariance.h"
#include "ctid/refined_iv/initialization.h"
#include "ctid/simulation/discretization.h"
#include "refined_iv/internal/covariance_sums.h"
#include "refined_iv/internal/refined_iv_engine.h"

namespace ctid {

namespace internal {
namespace {

// The augmented vector of (29): beta first, then (InitialConditions::estimate) the n_i + l_i
// free-response coefficients of every submodel in every record, so the parameter block of any
// joint matrix is its top-left p x p corner.
struct Layout {
  std::vector<SubmodelOrder> orders;
  std::vector<int> offset;
  std::vector<int> free_offset;  // of record r's submodel i: [r * K + i]
  int parameters = 0;
  int poles = 0;      // sum n_i + l_i
  int records = 1;    // each with its own initial state
  int augmented = 0;  // parameters, plus records * poles when initial conditions are estimated
  Hold input_hold = Hold::zero_order_hold;  // how the measured input behaves between samples
  double delay_fraction = 0.0;              // of a sample, on top of the whole-sample delay

  Layout(std::vector<SubmodelOrder> o, bool initial_conditions, int record_count)
      : orders(std::move(o)), records(record_count) {
    for (const SubmodelOrder& s : orders) {
      offset.push_back(parameters);
      parameters += s.n + s.m + 1;
      poles += s.n + s.integrators;
    }
    augmented = parameters;
    if (initial_conditions) {
      for (int r = 0; r < records; ++r) {
        for (const SubmodelOrder& s : orders) {
          free_offset.push_back(augmented);
          augmented += s.n + s.integrators;
        }
      }
    }
  }
  explicit Layout(std::vector<SubmodelOrder> o) : Layout(std::move(o), false, 1) {}
  bool free_responses() const { return augmented > parameters; }
  int free_at(int record, int i) const {
    return free_offset[static_cast<size_t>(record * size() + i)];
  }
  int states(int i) const {
    return orders[static_cast<size_t>(i)].n + orders[static_cast<size_t>(i)].integrators;
  }
  int size() const { return static_cast<int>(orders.size()); }
  int count(int i) const {
    return orders[static_cast<size_t>(i)].n + orders[static_cast<size_t>(i)].m + 1;
  }
};

// The stopping rule's relative change, block by block: the largest over the submodels of
// ||d a_i|| / ||a_i|| and ||d b_i|| / ||b_i||. One norm over the whole of beta lets the block
// with the largest coefficients decide: with a gain of 1e6 the numerators dominate and the
// iteration stopped with the poles still moving by 1e-4 (issue 16). A block whose norm
// vanishes is measured against the whole vector's norm.
double relative_change(const Layout& layout, const Eigen::VectorXd& from,
                       const Eigen::VectorXd& to) {
  const double whole = std::max(from.norm(), 1e-300);
  double largest = 0.0;
  for (int i = 0; i < layout.size(); ++i) {
    const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
    const int at = layout.offset[static_cast<size_t>(i)];
    for (const auto& [first, count] : {std::pair{at, o.n}, std::pair{at + o.n, o.m + 1}}) {
      if (count == 0) continue;
      const double size = from.segment(first, count).norm();
      const double step = (to.segment(first, count) - from.segment(first, count)).norm();
      largest = std::max(largest, step / (size > 1e-12 * whole ? size : whole));
    }
  }
  return largest;
}

Polynomial denominator_of(const Layout& layout, const Eigen::VectorXd& beta, int i) {
  const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
  Eigen::VectorXd a(o.n + 1);
  a(0) = 1.0;
  a.tail(o.n) = beta.segment(layout.offset[static_cast<size_t>(i)], o.n);
  return Polynomial::trimmed(a);
}

Eigen::VectorXd numerator_of(const Layout& layout, const Eigen::VectorXd& beta, int i) {
  const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
  return beta.segment(layout.offset[static_cast<size_t>(i)] + o.n, o.m + 1);
}

}  // namespace

FreeResponseChain free_response_chain(const Polynomial& a, int integrators, double h) {
  const FilterRealization bank = derivative_filters(Polynomial::monomial(integrators) * a);
  const int n = a.degree();
  FilterRealization chain = bank;
  if (n > 0) {
    Eigen::VectorXd first = Eigen::VectorXd::Zero(bank.outputs());
    first(0) = 1.0;
    chain = cascade(bank, first, derivative_filters(a));
  }
  const int states = chain.order();
  FreeResponseChain out;
  out.phi = discretize_zoh(chain.a, chain.b, h).phi;
  out.c0 = Eigen::RowVectorXd::Zero(states);
  out.c0.head(bank.order()) = bank.c.row(0);
  out.ck = n > 0 ? Eigen::MatrixXd(chain.c.middleRows(1, n)) : Eigen::MatrixXd(0, states);
  return out;
}

namespace {

// Realisation of B/(p^l A): the bank of 1/(p^l A) with the outputs combined by b.
FilterRealization submodel_realization(const Polynomial& a, const Eigen::VectorXd& b, int l) {
  const FilterRealization bank = derivative_filters(Polynomial::monomial(l) * a);
  Eigen::VectorXd w = Eigen::VectorXd::Zero(bank.outputs());
  w.head(b.size()) = b;
  return combine_outputs(bank, w);
}

// S_uo(q) r with S_uo = C_d / (1 + G_d C_d), G_d = ZOH equivalent of the model with the input
// delay; std::nullopt when the loop is unstable or ill-posed.
std::optional<Eigen::VectorXd> sensitivity_filtered_reference(
    const Layout& layout, const Eigen::VectorXd& beta, const DiscreteTransferFunction& controller,
    const Eigen::VectorXd& r, double h, int delay) {
  // Plant: submodels side by side, each with the fraction of the delay (one more state).
  std::vector<StateSpace> parts;
  double dg = 0.0;
  int ng = 0;
  for (int i = 0; i < layout.size(); ++i) {
    const FilterRealization f =
        submodel_realization(denominator_of(layout, beta, i), numerator_of(layout, beta, i),
                             layout.orders[static_cast<size_t>(i)].integrators);
    parts.push_back(
        discretize_zoh(StateSpace{f.a, f.b, f.c.row(0), f.d(0)}, h, layout.delay_fraction));
    dg += parts.back().d;
    ng += parts.back().order();
  }
  const StateSpace c = controller.to_state_space();
  const int nc = c.order();
  const int n = ng + delay + nc;
  // State X = [x_g; u_{k-1} .. u_{k-delay}; x_c]; u_k = ku X + kr r_k, y_k = yx X + yr r_k.
  Eigen::RowVectorXd cg = Eigen::RowVectorXd::Zero(n);
  Eigen::MatrixXd phig = Eigen::MatrixXd::Zero(ng, ng);
  Eigen::VectorXd gammag(ng);
  int at = 0;
  for (const StateSpace& part : parts) {
    const int s = part.order();
    phig.block(at, at, s, s) = part.a;
    gammag.segment(at, s) = part.b;
    cg.segment(at, s) = part.c;
    at += s;
  }
  Eigen::RowVectorXd cc = Eigen::RowVectorXd::Zero(n);
  cc.tail(nc) = c.c;
  Eigen::RowVectorXd ku(n);
  double kr = 0.0;
  Eigen::RowVectorXd yx(n);
  double yr = 0.0;
  if (delay > 0) {
    // y_k = C_g x_g + D_g u_{k-delay}: no algebraic loop.
    yx = cg;
    yx(ng + delay - 1) += dg;
    yr = 0.0;
    ku = cc - c.d * yx;
    kr = c.d;
  } else {
    const double loop = 1.0 + c.d * dg;
    if (!(std::abs(loop) > 1e-12)) return std::nullopt;
    ku = (cc - c.d * cg) / loop;
    kr = c.d / loop;
    yx = cg + dg * ku;
    yr = dg * kr;
  }
  Eigen::MatrixXd acl = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd bcl = Eigen::VectorXd::Zero(n);
  acl.topLeftCorner(ng, ng) = phig;
  if (delay > 0) {
    acl.block(0, ng + delay - 1, ng, 1) += gammag;
    acl.row(ng) = ku;
    bcl(ng) = kr;
    for (int j = 1; j < delay; ++j) acl(ng + j, ng + j - 1) = 1.0;
  } else {
    acl.topRows(ng) += gammag * ku;
    bcl.head(ng) = gammag * kr;
  }
  // x_c+ = A_c x_c + B_c (r - y)
  acl.bottomRows(nc) += -c.b * yx;
  acl.bottomRightCorner(nc, nc) += c.a;
  bcl.tail(nc) += c.b * (1.0 - yr);
  if (!acl.allFinite()) return std::nullopt;
  if (n > 0) {
    const Eigen::VectorXcd eig = acl.eigenvalues();
    if (eig.cwiseAbs().maxCoeff() >= 1.0 - 1e-9) return std::nullopt;
  }
  Eigen::VectorXd out(r.size());
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd next(n);
  for (Eigen::Index k = 0; k < r.size(); ++k) {
    out(k) = ku.dot(x) + kr * r(k);
    next.noalias() = acl * x;
    next += bcl * r(k);
    x.swap(next);
  }
  if (!out.allFinite()) return std::nullopt;
  return out;
}

// Rows of the record processed together: the block buffers (a few times kBlock x p doubles)
// stay in cache, and the sums of eq. (29) are formed block by block, so no N x p matrix is
// ever stored during the iteration.
constexpr Eigen::Index kBlock = 256;

// Sums of eq. (29) over the record: Z'Phi, Z'Upsilon and the squared column norms of the
// instrument Z and regressor Phi (for the unit-norm scaling).
struct Moments {
  Eigen::MatrixXd zp;  // p x p
  Eigen::MatrixXd zy;  // p x K
  Eigen::VectorXd zz;  // p
  Eigen::VectorXd pp;  // p

  bool all_finite() const {
    return zp.allFinite() && zy.allFinite() && zz.allFinite() && pp.allFinite();
  }
};

// The filters of one submodel at one iterate. Outputs of `source`: rows 0..m are
// p^j/(p^l A) z (B-part of the instrument), rows m+1..m+n are p^k B/(p^l A^2) z, k = 1..n
// (one cascade whose first stage is the 1/(p^l A) bank itself), and in open loop row m+n+1
// is the model output B/(p^l A) u. `input` (closed loop, or when no instrument is needed)
// gives p^j/(p^l A) u in rows 0..m and B/(p^l A) u in row m+1. `output` is the bank of
// 1/A on the residual output y~_i (23).
// Free responses of one submodel at one iterate (InitialConditions::estimate), exact at the
// samples: the homogeneous chain 1/(p^l A) -> p^k/A with transition matrix phi, propagated
// from the s = n + l initial states [e_j; 0] (columns j < s: the basis 1/(p^l A) of the
// submodel's free responses, regressor and instrument columns alike) and from [c_i; 0]
// (column s: the current free response f_i, added to the model output, and p^k/A f_i,
// added to the a-part of the open-loop instrument).
struct FreeResponse {
  Eigen::MatrixXd phi;
  Eigen::MatrixXd state;  // chain states x (s + 1)
  Eigen::MatrixXd next;
  Eigen::RowVectorXd c0;     // 1/(p^l A)
  Eigen::MatrixXd ck;        // p^k/A of it, k = 1..n
  Eigen::MatrixXd basis;     // kBlock x s
  Eigen::VectorXd value;     // kBlock: f_i
  Eigen::MatrixXd filtered;  // kBlock x n: p^k/A f_i
};

struct SubmodelFilters {
  std::optional<FreeResponse> free;
  std::optional<SampledFilter> source;
  std::optional<SampledFilter> input;
  std::optional<SampledFilter> output;
  SampledFilter::Stream source_stream;
  SampledFilter::Stream input_stream;
  SampledFilter::Stream output_stream;
};

// Block buffers reused by every pass of one estimate.
struct Workspace {
  Eigen::MatrixXd instrument;  // kBlock x p
  Eigen::MatrixXd regressor;   // kBlock x p
  Eigen::MatrixXd filtered;    // kBlock x K, Upsilon (26)
  Eigen::MatrixXd outputs;     // kBlock x K, G_i u
  Eigen::VectorXd total;       // kBlock
  Eigen::VectorXd residual_output;
  std::vector<Eigen::MatrixXd> source_out;
  std::vector<Eigen::MatrixXd> input_out;
  std::vector<Eigen::MatrixXd> output_out;

  explicit Workspace(const Layout& layout)
      : instrument(kBlock, layout.augmented),
        regressor(kBlock, layout.augmented),
        filtered(kBlock, layout.size()),
        outputs(kBlock, layout.size()),
        total(kBlock),
        residual_output(kBlock),
        source_out(static_cast<size_t>(layout.size())),
        input_out(static_cast<size_t>(layout.size())),
        output_out(static_cast<size_t>(layout.size())) {}
};

FilterRealization with_rows(const FilterRealization& f, const Eigen::MatrixXd& c,
                            const Eigen::VectorXd& d) {
  FilterRealization out;
  out.a = f.a;
  out.b = f.b;
  out.c = c;
  out.d = d;
  return out;
}

SubmodelFilters submodel_filters(const Layout& layout, const Eigen::VectorXd& beta,
                                 const Eigen::VectorXd& initial_states, int record, int i, double h,
                                 Hold output_interpolation, bool closed_loop, bool need_instrument,
                                 bool need_regressor) {
  const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
  const Polynomial a = denominator_of(layout, beta, i);
  const Eigen::VectorXd b = numerator_of(layout, beta, i);
  const FilterRealization bank = derivative_filters(Polynomial::monomial(o.integrators) * a);
  const int s1 = bank.order();
  Eigen::VectorXd w = Eigen::VectorXd::Zero(bank.outputs());
  w.head(o.m + 1) = b;
  const Eigen::RowVectorXd model_c = w.transpose() * bank.c;
  const double model_d = w.dot(bank.d);
  SubmodelFilters f;
  if (need_instrument) {
    const bool with_model = !closed_loop;
    const int rows = o.m + 1 + o.n + (with_model ? 1 : 0);
    // The cascade carries B / ||B||, and ||B|| multiplies its outputs instead: with B in the
    // coupling of the state matrix, a gain of 1e6 made the discretised chain lose the
    // small entries and moved the fixed point of noise-free data by 1e-4 (issue 16).
    const double gain = w.norm() > 0.0 ? w.norm() : 1.0;
    FilterRealization chain = bank;
    if (o.n > 0) chain = cascade(bank, w / gain, derivative_filters(a));
    const int states = chain.order();
    Eigen::MatrixXd c = Eigen::MatrixXd::Zero(rows, states);
    Eigen::VectorXd d = Eigen::VectorXd::Zero(rows);
    c.topLeftCorner(o.m + 1, s1) = bank.c.topRows(o.m + 1);
    d.head(o.m + 1) = bank.d.head(o.m + 1);
    if (o.n > 0) {
      c.middleRows(o.m + 1, o.n) = gain * chain.c.middleRows(1, o.n);
      d.segment(o.m + 1, o.n) = gain * chain.d.segment(1, o.n);
    }
    if (with_model) {
      c.block(rows - 1, 0, 1, s1) = model_c;
      d(rows - 1) = model_d;
    }
    // Open loop the source is the measured input; closed loop it is the controller's output
    // S_uo r, held by the DAC.
    f.source.emplace(with_rows(chain, c, d), h,
                     closed_loop ? Hold::zero_order_hold : layout.input_hold,
                     layout.delay_fraction);
    f.source_stream = f.source->start();
  }
  if (closed_loop || !need_instrument) {
    Eigen::MatrixXd c(o.m + 2, s1);
    Eigen::VectorXd d(o.m + 2);
    c.topRows(o.m + 1) = bank.c.topRows(o.m + 1);
    d.head(o.m + 1) = bank.d.head(o.m + 1);
    c.row(o.m + 1) = model_c;
    d(o.m + 1) = model_d;
    f.input.emplace(with_rows(bank, c, d), h, layout.input_hold, layout.delay_fraction);
    f.input_stream = f.input->start();
  }
  if (need_regressor && o.n > 0) {
    f.output.emplace(derivative_filters(a), h, output_interpolation);
    f.output_stream = f.output->start();
  }
  if (layout.free_responses()) {
    const int s = layout.states(i);
    FreeResponseChain chain = free_response_chain(a, o.integrators, h);
    const int states = static_cast<int>(chain.phi.rows());
    const int given = std::min(s, s1);  // s1 < s only if the iterate lost its leading a_in
    FreeResponse& r = f.free.emplace();
    r.phi = std::move(chain.phi);
    r.state = Eigen::MatrixXd::Zero(states, s + 1);
    r.state.topLeftCorner(given, given).setIdentity();
    r.state.block(0, s, given, 1) =
        initial_states.segment(layout.free_at(record, i) - layout.parameters, given);
    r.next.resize(states, s + 1);
    r.c0 = std::move(chain.c0);
    r.ck = std::move(chain.ck);
    r.basis.resize(kBlock, s);
    r.value.resize(kBlock);
    r.filtered.resize(kBlock, o.n);
  }
  return f;
}

// One record's signals: the input delayed by the whole samples of the delay, the output, and
// in closed loop S_uo r (delayed likewise) and S_uo r itself; `offset` is the row of its
// first sample in the stacked residual and instrument.
struct RecordSignals {
  Eigen::VectorXd u;
  const Eigen::VectorXd* y = nullptr;
  std::optional<Eigen::VectorXd> source;
  Eigen::VectorXd undelayed_source;
  Eigen::Index offset = 0;
};

// One record's filters at beta, from rest; the workspace's free-response columns of the other
// records are cleared (they are zero on this record's rows).
std::vector<SubmodelFilters> record_filters(const Layout& layout, const Eigen::VectorXd& beta,
                                            const Eigen::VectorXd& initial_states, int record,
                                            double h, Hold output_interpolation, bool closed_loop,
                                            bool need_instrument, bool need_regressor,
                                            Workspace& w) {
  std::vector<SubmodelFilters> filters;
  filters.reserve(static_cast<size_t>(layout.size()));
  for (int i = 0; i < layout.size(); ++i) {
    filters.push_back(submodel_filters(layout, beta, initial_states, record, i, h,
                                       output_interpolation, closed_loop, need_instrument,
                                       need_regressor));
  }
  if (layout.free_responses()) {
    const int free = layout.augmented - layout.parameters;
    w.instrument.rightCols(free).setZero();
    w.regressor.rightCols(free).setZero();
  }
  return filters;
}

// Where a record's filters are between two blocks: enough to run them on from there.
struct FilterCheckpoint {
  std::vector<SampledFilter::Stream> source;
  std::vector<SampledFilter::Stream> input;
  std::vector<SampledFilter::Stream> output;
  std::vector<Eigen::MatrixXd> free;
};

FilterCheckpoint checkpoint(const std::vector<SubmodelFilters>& filters) {
  FilterCheckpoint c;
  for (const SubmodelFilters& f : filters) {
    c.source.push_back(f.source_stream);
    c.input.push_back(f.input_stream);
    c.output.push_back(f.output_stream);
    c.free.push_back(f.free ? f.free->state : Eigen::MatrixXd());
  }
  return c;
}

void restore(std::vector<SubmodelFilters>& filters, const FilterCheckpoint& c) {
  for (size_t i = 0; i < filters.size(); ++i) {
    filters[i].source_stream = c.source[i];
    filters[i].input_stream = c.input[i];
    filters[i].output_stream = c.output[i];
    if (filters[i].free) filters[i].free->state = c.free[i];
  }
}

// Rows [k0, k0 + len) of one record through its filters, which continue from row k0: the
// instrument and regressor rows, the submodel outputs and their sum and, with the regressor,
// the filtered residual outputs (22).
void filter_block(const Layout& layout, int record, const RecordSignals& signals,
                  const Eigen::VectorXd* source, Eigen::Index k0, Eigen::Index len,
                  bool need_instrument, bool need_regressor, std::vector<SubmodelFilters>& filters,
                  Workspace& w) {
  const Eigen::VectorXd& u = signals.u;
  const Eigen::VectorXd& y = *signals.y;
  const int k_count = layout.size();
  const bool closed_loop = source != nullptr;
  for (int i = 0; i < k_count; ++i) {
    const auto at = static_cast<size_t>(i);
    const SubmodelOrder& o = layout.orders[at];
    const int off = layout.offset[at];
    SubmodelFilters& f = filters[at];
    if (f.source) {
      Eigen::MatrixXd& out = w.source_out[at];
      out.resize(len, f.source->outputs());
      f.source->run((closed_loop ? *source : u).segment(k0, len), f.source_stream, out);
      w.instrument.block(0, off + o.n, len, o.m + 1) = out.leftCols(o.m + 1);
      if (o.n > 0) w.instrument.block(0, off, len, o.n) = -out.middleCols(o.m + 1, o.n);
      if (!closed_loop) {
        w.outputs.col(i).head(len) = out.col(o.m + o.n + 1);
        if (need_regressor) w.regressor.block(0, off + o.n, len, o.m + 1) = out.leftCols(o.m + 1);
      }
    }
    if (f.input) {
      Eigen::MatrixXd& out = w.input_out[at];
      out.resize(len, f.input->outputs());
      f.input->run(u.segment(k0, len), f.input_stream, out);
      w.outputs.col(i).head(len) = out.col(o.m + 1);
      if (need_regressor) w.regressor.block(0, off + o.n, len, o.m + 1) = out.leftCols(o.m + 1);
    }
    if (f.free) {
      FreeResponse& r = *f.free;
      const int s = layout.states(i);
      for (Eigen::Index k = 0; k < len; ++k) {
        r.basis.row(k).noalias() = r.c0 * r.state.leftCols(s);
        r.value(k) = r.c0.dot(r.state.col(s));
        if (o.n > 0) r.filtered.row(k).noalias() = (r.ck * r.state.col(s)).transpose();
        r.next.noalias() = r.phi * r.state;
        r.state.swap(r.next);
      }
      const int free_off = layout.free_at(record, i);
      w.outputs.col(i).head(len) += r.value.head(len);
      if (need_instrument) {
        w.instrument.block(0, free_off, len, s) = r.basis.topRows(len);
        if (!closed_loop && o.n > 0) {
          w.instrument.block(0, off, len, o.n) -= r.filtered.topRows(len);
        }
      }
      if (need_regressor) w.regressor.block(0, free_off, len, s) = r.basis.topRows(len);
    }
  }
  w.total.head(len) = w.outputs.topRows(len).rowwise().sum();
  if (need_regressor) {
    for (int i = 0; i < k_count; ++i) {
      const auto at = static_cast<size_t>(i);
      const SubmodelOrder& o = layout.orders[at];
      const int off = layout.offset[at];
      SubmodelFilters& f = filters[at];
      w.residual_output.head(len) =
          y.segment(k0, len) - w.total.head(len) + w.outputs.col(i).head(len);  // (23)
      if (f.output) {
        Eigen::MatrixXd& out = w.output_out[at];
        out.resize(len, f.output->outputs());
        f.output->run(w.residual_output.head(len), f.output_stream, out);
        w.filtered.col(i).head(len) = out.col(0);                       // (22)
        w.regressor.block(0, off, len, o.n) = -out.middleCols(1, o.n);  // (24)
      } else {
        w.filtered.col(i).head(len) = w.residual_output.head(len);
      }
    }
  }
}

// Rows of a record between two checkpoints of the instrument pass.
constexpr Eigen::Index kSegment = 16 * kBlock;

// The instrument's share of the covariance, streamed so that the N x q instrument psi is
// never stored: its Gram matrix psi' psi and, for the coloured-noise sandwich, each record's
// filter states every kSegment rows, from which psi is formed again segment by segment, newest
// first (adjoint_instrument_sum). psi is the stacked instrument at beta with `extra` (the
// delay's column, stacked like the residual) appended when it is estimated.
struct InstrumentPass {
  const Eigen::VectorXd* extra = nullptr;
  bool keep_checkpoints = false;
  Eigen::MatrixXd* stored = nullptr;  // psi itself (RefinedIvProblem::stored_instrument_covariance)
  Eigen::MatrixXd gram;               // q x q
  std::vector<std::vector<FilterCheckpoint>> saved;  // [record][segment]
  Eigen::MatrixXd rows;                              // kBlock x q, the pass's block of psi

  int columns(const Layout& layout) const { return layout.augmented + (extra != nullptr ? 1 : 0); }

  // psi's rows [k0, k0 + len) of the record starting at `first`, from the workspace, into `to`
  // (len x q).
  void copy_rows(const Layout& layout, const Workspace& w, Eigen::Index first, Eigen::Index k0,
                 Eigen::Index len, Eigen::Ref<Eigen::MatrixXd> to) const {
    to.leftCols(layout.augmented) = w.instrument.topRows(len);
    if (extra != nullptr) to.col(layout.augmented) = extra->segment(first + k0, len);
  }
};

// evaluate() on one record: its filters from rest, its free responses, its rows of the
// stacked residual and instrument; the sums are added to.
void evaluate_record(const Layout& layout, const Eigen::VectorXd& beta,
                     const Eigen::VectorXd& initial_states, int record,
                     const RecordSignals& signals, const Eigen::VectorXd* source, double h,
                     Hold output_interpolation, Workspace& w, Moments* moments,
                     Eigen::VectorXd* residual, InstrumentPass* instrument, double* sse) {
  const Eigen::VectorXd& y = *signals.y;
  const Eigen::Index n = signals.u.size();
  const Eigen::Index first = signals.offset;
  const bool need_instrument = moments != nullptr || instrument != nullptr;
  const bool need_regressor = moments != nullptr;
  std::vector<SubmodelFilters> filters =
      record_filters(layout, beta, initial_states, record, h, output_interpolation,
                     source != nullptr, need_instrument, need_regressor, w);
  for (Eigen::Index k0 = 0; k0 < n; k0 += kBlock) {
    const Eigen::Index len = std::min(kBlock, n - k0);
    if (instrument != nullptr && instrument->keep_checkpoints && k0 % kSegment == 0) {
      instrument->saved[static_cast<size_t>(record)].push_back(checkpoint(filters));
    }
    filter_block(layout, record, signals, source, k0, len, need_instrument, need_regressor, filters,
                 w);
    if (moments != nullptr) {
      const auto z = w.instrument.topRows(len);
      const auto phi = w.regressor.topRows(len);
      moments->zp.noalias() += z.transpose() * phi;
      moments->zy.noalias() += z.transpose() * w.filtered.topRows(len);
      moments->zz += z.colwise().squaredNorm().transpose();
      moments->pp += phi.colwise().squaredNorm().transpose();
    }
    if (residual != nullptr) {
      residual->segment(first + k0, len) = y.segment(k0, len) - w.total.head(len);
    }
    if (sse != nullptr) *sse += (y.segment(k0, len) - w.total.head(len)).squaredNorm();
    if (instrument != nullptr) {
      auto z = instrument->rows.topRows(len);
      instrument->copy_rows(layout, w, first, k0, len, z);
      instrument->gram.noalias() += z.transpose() * z;
      if (instrument->stored != nullptr) instrument->stored->middleRows(first + k0, len) = z;
    }
  }
}

// One pass over the records at beta (instrument source: u in open loop, S_uo r when
// `with_source`); each record's filters start at rest at its first sample and its free
// responses have their own coefficients. With `moments`: the sums of eq. (29) over all
// records; with `residual`: y - sum_i G_i u, records stacked; with `instrument`: the
// instrument's sums for the covariance (InstrumentPass); with `sse`: the sum of squared output
// errors
// ||y - sum_i G_i u||^2 (the model output is formed on every pass anyway).
void evaluate(const Layout& layout, const Eigen::VectorXd& beta,
              const Eigen::VectorXd& initial_states, const std::vector<RecordSignals>& records,
              bool with_source, double h, Hold output_interpolation, Workspace& w, Moments* moments,
              Eigen::VectorXd* residual, InstrumentPass* instrument, double* sse = nullptr) {
  Eigen::Index n = 0;
  for (const RecordSignals& record : records) n += record.u.size();
  const int k_count = layout.size();
  const int p = layout.augmented;
  for (int i = 0; i < k_count; ++i) {
    if (denominator_of(layout, beta, i).degree() < layout.orders[static_cast<size_t>(i)].n) {
      // A_i lost its leading coefficient: the iterate has fewer poles than the structure and
      // its filters cannot be formed. The pass reads as non-finite, so the iteration treats
      // it as a failed step (and a final model as not usable).
      const double nan = std::numeric_limits<double>::quiet_NaN();
      if (moments != nullptr) {
        moments->zp = Eigen::MatrixXd::Constant(p, p, nan);
        moments->zy = Eigen::MatrixXd::Constant(p, k_count, nan);
        moments->zz = Eigen::VectorXd::Constant(p, nan);
        moments->pp = Eigen::VectorXd::Constant(p, nan);
      }
      if (residual != nullptr) *residual = Eigen::VectorXd::Constant(n, nan);
      if (instrument != nullptr) {
        const int q = instrument->columns(layout);
        instrument->gram = Eigen::MatrixXd::Constant(q, q, nan);
      }
      if (sse != nullptr) *sse = nan;
      return;
    }
  }
  if (moments != nullptr) {
    moments->zp = Eigen::MatrixXd::Zero(p, p);
    moments->zy = Eigen::MatrixXd::Zero(p, k_count);
    moments->zz = Eigen::VectorXd::Zero(p);
    moments->pp = Eigen::VectorXd::Zero(p);
  }
  if (residual != nullptr) residual->resize(n);
  if (instrument != nullptr) {
    const int q = instrument->columns(layout);
    instrument->gram = Eigen::MatrixXd::Zero(q, q);
    instrument->rows.resize(kBlock, q);
    instrument->saved.assign(records.size(), {});
    if (instrument->stored != nullptr) instrument->stored->resize(n, q);
  }
  if (sse != nullptr) *sse = 0.0;
  for (int record = 0; record < static_cast<int>(records.size()); ++record) {
    const RecordSignals& signals = records[static_cast<size_t>(record)];
    evaluate_record(layout, beta, initial_states, record, signals,
                    with_source ? &*signals.source : nullptr, h, output_interpolation, w, moments,
                    residual, instrument, sse);
  }
}

// The coloured-noise middle factor's sum (AdjointArOuterSum) over the instrument of an
// InstrumentPass that kept its checkpoints: records and their segments newest first, each
// segment's rows formed again from its checkpoint, so only kSegment rows of psi are held.
Eigen::MatrixXd adjoint_instrument_sum(const Layout& layout, const Eigen::VectorXd& beta,
                                       const Eigen::VectorXd& initial_states,
                                       const std::vector<RecordSignals>& records, bool with_source,
                                       double h, Hold output_interpolation, Workspace& w,
                                       const InstrumentPass& pass, const AutoregressiveModel& ar,
                                       const Eigen::VectorXd& scales) {
  AdjointArOuterSum sum(ar, scales);
  Eigen::MatrixXd segment(kSegment, pass.columns(layout));
  for (int record = static_cast<int>(records.size()) - 1; record >= 0; --record) {
    const RecordSignals& signals = records[static_cast<size_t>(record)];
    const Eigen::VectorXd* source = with_source ? &*signals.source : nullptr;
    const Eigen::Index n = signals.u.size();
    std::vector<SubmodelFilters> filters =
        record_filters(layout, beta, initial_states, record, h, output_interpolation,
                       source != nullptr, true, false, w);
    const std::vector<FilterCheckpoint>& saved = pass.saved[static_cast<size_t>(record)];
    for (auto s = static_cast<Eigen::Index>(saved.size()) - 1; s >= 0; --s) {
      restore(filters, saved[static_cast<size_t>(s)]);
      const Eigen::Index start = s * kSegment;
      const Eigen::Index length = std::min(kSegment, n - start);
      for (Eigen::Index k0 = start; k0 < start + length; k0 += kBlock) {
        const Eigen::Index len = std::min(kBlock, n - k0);
        filter_block(layout, record, signals, source, k0, len, true, false, filters, w);
        pass.copy_rows(layout, w, signals.offset, k0, len, segment.middleRows(k0 - start, len));
      }
      sum.add_earlier(segment.topRows(length));
    }
  }
  return sum.sum();
}

// The free-response coefficients of every submodel in every record from the submodel's own
// column of the solution of (29).
Eigen::VectorXd free_response_coefficients(const Layout& layout, const Eigen::MatrixXd& solution) {
  Eigen::VectorXd c(layout.augmented - layout.parameters);
  for (int r = 0; r < layout.records && layout.free_responses(); ++r) {
    for (int i = 0; i < layout.size(); ++i) {
      const int at = layout.free_at(r, i);
      c.segment(at - layout.parameters, layout.states(i)) =
          solution.block(at, i, layout.states(i), 1);
    }
  }
  return c;
}

// Realisation-independent form of the coefficients: per record and submodel, the free
// response f_i and its first n_i + l_i - 1 derivatives at the record's first sample, c0 A^k x0
// of 1/(p^l A_i).
Eigen::VectorXd free_response_derivatives(const Layout& layout, const Eigen::VectorXd& beta,
                                          const Eigen::VectorXd& initial_states) {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(initial_states.size());
  for (int i = 0; i < layout.size(); ++i) {
    const FilterRealization bank =
        derivative_filters(Polynomial::monomial(layout.orders[static_cast<size_t>(i)].integrators) *
                           denominator_of(layout, beta, i));
    const int s = layout.states(i);
    if (bank.order() != s) continue;
    for (int r = 0; r < layout.records; ++r) {
      const int at = layout.free_at(r, i) - layout.parameters;
      Eigen::VectorXd x = initial_states.segment(at, s);
      for (int k = 0; k < s; ++k) {
        out(at + k) = bank.c.row(0).dot(x);
        x = bank.a * x;
      }
    }
  }
  return out;
}

Eigen::VectorXd norms_from_squares(const Eigen::VectorXd& squares) {
  Eigen::VectorXd s = squares.cwiseSqrt();
  for (Eigen::Index j = 0; j < s.size(); ++j) {
    if (!(s(j) > 0.0) || !std::isfinite(s(j))) s(j) = 1.0;
  }
  return s;
}

// The solution of (29) from its sums with unit-norm columns, or nothing if they are not
// finite or the equations are singular.
std::optional<Eigen::MatrixXd> solve_scaled(const Moments& sums) {
  if (!sums.all_finite()) return std::nullopt;
  const Eigen::VectorXd sz = norms_from_squares(sums.zz);
  const Eigen::VectorXd sp = norms_from_squares(sums.pp);
  const Eigen::MatrixXd m =
      sz.cwiseInverse().asDiagonal() * sums.zp * sp.cwiseInverse().asDiagonal();
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(m);
  if (!(lu.rcond() > 1e-14)) return std::nullopt;
  const Eigen::MatrixXd rhs = sz.cwiseInverse().asDiagonal() * sums.zy;
  Eigen::MatrixXd solution = sp.cwiseInverse().asDiagonal() * Eigen::MatrixXd(lu.solve(rhs));
  if (!solution.allFinite()) return std::nullopt;
  return solution;
}

}  // namespace

Verdict refined_iv_verdict(const EstimationResult& r, bool closed_loop, bool loop_unstable) {
  // A returned start (no step completed, or none fitted better) is judged like any model, by
  // its fit and the checks below, never by the iteration count: on noise-free data the start
  // can already be exact (issue 33), and a poor start fails the fit check. The termination
  // message says that the model is the start.
  Verdict verdict;
  check_finite(verdict, r.parameters.allFinite(), "a parameter");
  if (closed_loop) {
    check_fit(verdict, r.fit_percent, std::numeric_limits<double>::quiet_NaN());
    check_closed_loop_fit(verdict, r.closed_loop_fit_percent, r.start_closed_loop_fit_percent);
  } else {
    check_fit(verdict, r.fit_percent, r.start_fit_percent);
  }
  if (loop_unstable) {
    // The record came from a loop that ran; a model the controller cannot hold is not it.
    verdict.fail(
        "the known controller does not stabilise the fitted model, so the model cannot "
        "describe the loop that was recorded",
        {verdict_advice::better_start, verdict_advice::lower_order});
  }
  Eigen::VectorXcd poles(0);
  for (int i = 0; i < r.model.size(); ++i) {
    if (r.model[i].a.degree() < 1) continue;
    const Eigen::VectorXcd roots = r.model[i].a.roots();
    poles.conservativeResize(poles.size() + roots.size());
    poles.tail(roots.size()) = roots;
  }
  if (poles.allFinite()) {
    check_stable(verdict, poles);
    const Eigen::VectorXcd zeros = r.transfer_function.numerator().degree() >= 1
                                       ? r.transfer_function.zeros()
                                       : Eigen::VectorXcd(0);
    if (zeros.allFinite()) check_cancellation(verdict, poles, zeros);
  }
  std::vector<std::string> names;
  Eigen::VectorXd values(static_cast<Eigen::Index>(r.modes.size()));
  Eigen::VectorXd errors(values.size());
  for (size_t k = 0; k < r.modes.size(); ++k) {
    const ModalEstimate& m = r.modes[k];
    names.push_back("the natural frequency of submodel " + std::to_string(m.submodel + 1));
    values(static_cast<Eigen::Index>(k)) = m.value.natural_frequency;
    errors(static_cast<Eigen::Index>(k)) = m.standard_error.natural_frequency;
  }
  check_standard_errors(verdict, names, values, errors);
  check_conditioning(verdict, r.reciprocal_condition, r.fit_percent);
  return verdict;
}

Polynomial reflect_unstable_roots(const Polynomial& a, bool& reflected) {
  reflected = false;
  if (a.degree() < 1) return a;
  Eigen::VectorXcd roots = a.roots();
  for (Eigen::Index j = 0; j < roots.size(); ++j) {
    if (roots(j).real() > 0.0) {
      roots(j) = std::complex<double>(-roots(j).real(), roots(j).imag());
      reflected = true;
    }
  }
  if (!reflected) return a;
  return Polynomial::from_roots(roots).anti_monic();
}

bool controller_stabilises(const std::vector<SubmodelOrder>& orders, const Eigen::VectorXd& beta,
                           const DiscreteTransferFunction& controller, double h, int input_delay) {
  try {
    // An empty reference: only the loop's poles are checked, nothing is filtered.
    return sensitivity_filtered_reference(Layout(orders), beta, controller, Eigen::VectorXd(), h,
                                          input_delay)
        .has_value();
  } catch (const InvalidArgument&) {
    return false;  // a degenerate model (e.g. A lost its leading coefficient) has no loop
  }
}

Eigen::VectorXd parameters_for_orders(const AdditiveModel& model,
                                      const std::vector<SubmodelOrder>& orders) {
  require(model.size() == static_cast<int>(orders.size()), "initial model has ", model.size(),
          " submodels; the structure asks for ", orders.size());
  const Layout layout(orders);
  Eigen::VectorXd beta = Eigen::VectorXd::Zero(layout.parameters);
  for (int i = 0; i < model.size(); ++i) {
    const Submodel& s = model[i];
    const SubmodelOrder& o = orders[static_cast<size_t>(i)];
    require(s.n() == o.n && s.integrators == o.integrators && s.m() <= o.m, "initial submodel ",
            i + 1, " has n = ", s.n(), ", m = ", s.m(), ", integrators = ", s.integrators,
            "; the structure asks for n = ", o.n, ", m <= ", o.m,
            ", integrators = ", o.integrators);
    const int off = layout.offset[static_cast<size_t>(i)];
    for (int k = 1; k <= o.n; ++k) beta(off + k - 1) = s.a[k];
    for (int k = 0; k <= s.m(); ++k) beta(off + o.n + k) = s.b[k];
  }
  return beta;
}

Eigen::VectorXd unfactored_parameters(const TransferFunction& g, const SubmodelOrder& order) {
  const Polynomial& den = g.denominator();
  int l = 0;
  while (l <= den.degree() && den[l] == 0.0) ++l;
  require(
      l == order.integrators && den.degree() - l == order.n && g.numerator().degree() <= order.m,
      "initial transfer function has ", den.degree() - l, " non-zero poles, ", l,
      " poles at the origin and numerator degree ", g.numerator().degree(),
      "; the structure asks for n = ", order.n, ", integrators = ", order.integrators,
      ", m <= ", order.m);
  const double scale = den[l];
  Eigen::VectorXd beta = Eigen::VectorXd::Zero(order.n + order.m + 1);
  for (int k = 1; k <= order.n; ++k) beta(k - 1) = den[l + k] / scale;
  for (int k = 0; k <= g.numerator().degree(); ++k) beta(order.n + k) = g.numerator()[k] / scale;
  return beta;
}

EstimationResult run_refined_iv_from_start(const RefinedIvProblem& problem,
                                           const RefinedIvOptions& options, ScreenedStart* shared) {
  options.validate();
  const std::string name = problem.name;
  const std::vector<const SampledData*>& records = problem.records;
  require(!records.empty(), name, ": no data record was given");
  // The start (and the data checks) use the longest record; every record shares its sample
  // time and input hold.
  size_t longest_index = 0;
  for (size_t r = 1; r < records.size(); ++r) {
    if (records[r]->size() > records[longest_index]->size()) longest_index = r;
  }
  const SampledData& data = *records[longest_index];
  for (size_t r = 1; r < records.size(); ++r) {
    const double h0 = records.front()->sample_time();
    const double hr = records[r]->sample_time();
    require(std::abs(hr - h0) <= 1e-9 * h0, name, ": record ", r + 1, " is sampled every ", hr,
            " s but record 1 every ", h0, " s; records of one estimate share their sample time");
    require(records[r]->input_hold() == records.front()->input_hold(), name, ": record ", r + 1,
            "'s input is ", enum_name(records[r]->input_hold()), " but record 1's is ",
            enum_name(records.front()->input_hold()),
            "; records of one estimate share their input hold");
    require(records[r]->has_reference() == records.front()->has_reference(), name, ": record ",
            r + 1, (records[r]->has_reference() ? " has" : " has no"), " reference but record 1",
            (records.front()->has_reference() ? " has" : " has none"),
            "; records of one estimate have the same signals");
  }
  Layout layout(problem.orders, options.initial_conditions == InitialConditions::estimate,
                static_cast<int>(records.size()));
  layout.input_hold = data.input_hold();
  layout.delay_fraction = options.input_delay_fraction;
  require(layout.size() >= 1, name, ": the model structure has no submodels");
  {
    int biproper = 0;
    int integrating = 0;
    for (size_t i = 0; i < layout.orders.size(); ++i) {
      const SubmodelOrder& o = layout.orders[i];
      require(o.n >= 0 && o.m >= 0 && o.integrators >= 0, name, ": submodel ", i + 1,
              " has a negative order (n = ", o.n, ", m = ", o.m, ", integrators = ", o.integrators,
              ")");
      require(o.n + o.integrators >= 1, name, ": submodel ", i + 1,
              " has no poles (n = 0 and no integrators)");
      require(o.m <= o.n + o.integrators, name, ": submodel ", i + 1, " has m = ", o.m,
              " > n + integrators = ", o.n + o.integrators, " (improper)");
      if (o.m == o.n + o.integrators) ++biproper;
      if (o.integrators > 0) ++integrating;
    }
    require(biproper <= 1, name, ": ", biproper,
            " submodels are biproper; at most one may be (the split would not be unique)");
    require(integrating <= 1, name, ": ", integrating,
            " submodels have integrators; at most one may have poles at the origin");
  }
  const int delay = options.input_delay;
  require(
      options.record_input_delays.empty() || options.record_input_delays.size() == records.size(),
      name, ": record_input_delays has ", options.record_input_delays.size(), " entries for ",
      records.size(), " records; give one per record or none");
  // Whole samples by which each record's input is delayed: the model's delay plus the
  // record's own (an acquisition that lags its input).
  auto delay_of = [&](size_t r) {
    return delay + (options.record_input_delays.empty() ? 0 : options.record_input_delays[r]);
  };
  int n_samples = 0;
  for (const SampledData* record : records) n_samples += record->size();
  const int p = layout.parameters;
  const int unknowns = layout.augmented;  // with the free-response coefficients
  int lost = 0;
  for (size_t r = 0; r < records.size(); ++r) lost += delay_of(r);
  require(n_samples - lost >= std::max(3 * unknowns, unknowns + 20), name, ": ", n_samples,
          " samples (input delay ", delay, ") are too few for ", unknowns,
          " parameters and initial conditions; at least ",
          std::max(3 * unknowns, unknowns + 20) + lost, " are needed");
  const bool closed_loop = problem.controller != nullptr;
  const double h = data.sample_time();
  if (closed_loop) {
    require(data.has_reference(), name, ": closed-loop estimation needs a measured reference r");
    require(std::abs(problem.controller->sample_time() - h) <= 1e-9 * h, name,
            ": the controller's sample time ", problem.controller->sample_time(),
            " differs from the data's ", h);
  }

  // Assumption 1: persistency of excitation (of the best-excited record when there are several).
  DataChecks checks;
  const int nc = closed_loop ? problem.controller->denominator().degree() : 0;
  checks.excitation_order_required = 2 * layout.poles + nc;
  for (const SampledData* record : records) {
    const Eigen::VectorXd& excitation = closed_loop ? record->reference() : record->input();
    checks.excitation_order = std::max(
        checks.excitation_order,
        persistent_excitation_order(excitation, std::max(checks.excitation_order_required, p)));
  }
  require(checks.excitation_order >= p, name, ": the ", closed_loop ? "reference" : "input",
          " is persistently exciting of order ", checks.excitation_order, " only; the ", p,
          " parameters need at least order ", p, " (e.g. a constant or a single sine cannot)");
  checks.persistently_exciting = checks.excitation_order >= checks.excitation_order_required;
  if (!checks.persistently_exciting) {
    checks.warnings.push_back("the " + std::string(closed_loop ? "reference" : "input") +
                              " is persistently exciting of order " +
                              std::to_string(checks.excitation_order) + ", below the " +
                              std::to_string(checks.excitation_order_required) +
                              " of Assumption 1; consistency is not guaranteed");
  }

  // Starting point.
  Eigen::VectorXd beta;
  if (options.initial_model) {
    const AdditiveModel& given = *options.initial_model;
    bool fits = given.size() == layout.size();
    for (int i = 0; fits && i < given.size(); ++i) {
      const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
      fits = given[i].n() == o.n && given[i].integrators == o.integrators && given[i].m() <= o.m;
    }
    if (fits) {
      beta = parameters_for_orders(given, layout.orders);
    } else if (layout.size() == 1) {
      beta = unfactored_parameters(given.to_transfer_function().with_input_delay(0.0),
                                   layout.orders[0]);
    } else {
      beta = parameters_for_orders(
          group_into_submodels(given.to_transfer_function().with_input_delay(0.0), layout.orders,
                               data, delay_of(longest_index)),
          layout.orders);
    }
  } else {
    ScreenedStart own_start;
    InitializationOptions init;
    init.input_delay = delay_of(longest_index);
    init.method = options.start;
    init.screening_samples = options.start_screening_samples;
    // Closed loop: only starts the controller stabilises (decision 0011); an open-loop start
    // it does not stabilise would stop the iteration before its first step.
    if (closed_loop) init.controller = *problem.controller;
    ScreenedStart& start = shared != nullptr ? *shared : own_start;
    if (!start.g) {
      const SubmodelOrder total =
          layout.size() == 1 ? layout.orders[0] : unfactored_order(layout.orders);
      start.g = initial_transfer_function(data, total, init);
    }
    if (layout.size() == 1) {
      beta = unfactored_parameters(*start.g, layout.orders[0]);
    } else {
      beta = parameters_for_orders(additive_model_from_start(*start.g, data, layout.orders, init),
                                   layout.orders);
    }
  }
  require(beta.allFinite(), name, ": the initial model has a non-finite parameter");

  const double tau = (delay + layout.delay_fraction) * h;
  EstimationResult result{AdditiveModel::from_parameters(layout.orders, beta, tau),
                          TransferFunction(Polynomial{1.0}, Polynomial{1.0})};
  auto reflect_all = [&](Eigen::VectorXd& b) {
    for (int i = 0; i < layout.size(); ++i) {
      const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
      if (o.n < 1) continue;
      bool reflected = false;
      const Polynomial a = reflect_unstable_roots(denominator_of(layout, b, i), reflected);
      if (reflected) {
        ++result.unstable_reflections;
        for (int k = 1; k <= o.n; ++k) b(layout.offset[static_cast<size_t>(i)] + k - 1) = a[k];
      }
    }
  };
  reflect_all(beta);

  std::vector<RecordSignals> signals(records.size());
  Eigen::VectorXd y(n_samples);  // the records' outputs stacked
  {
    Eigen::Index at = 0;
    for (size_t r = 0; r < records.size(); ++r) {
      signals[r].u = delay_samples(records[r]->input(), delay_of(r));
      signals[r].y = &records[r]->output();
      signals[r].offset = at;
      y.segment(at, records[r]->size()) = records[r]->output();
      at += records[r]->size();
    }
  }
  // S_uo r of every record (closed loop); false when the loop is unstable.
  bool source = false;
  auto update_source = [&](const Eigen::VectorXd& b) -> bool {
    std::vector<Eigen::VectorXd> updated;  // all records or none: a failure keeps the last
    for (size_t r = 0; r < records.size(); ++r) {
      std::optional<Eigen::VectorXd> s = sensitivity_filtered_reference(
          layout, b, *problem.controller, records[r]->reference(), h, delay_of(r));
      if (!s) return false;
      updated.push_back(std::move(*s));
    }
    for (size_t r = 0; r < records.size(); ++r) {
      signals[r].source = delay_samples(updated[r], delay_of(r));
      signals[r].undelayed_source = std::move(updated[r]);
    }
    source = true;
    return true;
  };

  // Closed loop: the sum over the records of (y - G S_uo(G) r)^2 at b, from the S_uo r that
  // update_source last formed for b (the model's output from the reference alone).
  auto closed_loop_sse = [&](const Eigen::VectorXd& b) {
    const AdditiveModel model = AdditiveModel::from_parameters(layout.orders, b, tau);
    double sum = 0.0;
    for (size_t r = 0; r < records.size(); ++r) {
      const double own = (delay_of(r) - delay) * h;
      sum += (records[r]->output() - model_output(model.with_input_delay(tau + own),
                                                  signals[r].undelayed_source, h,
                                                  Hold::zero_order_hold))
                 .squaredNorm();
    }
    return sum;
  };
  double start_closed_loop_sse = std::numeric_limits<double>::quiet_NaN();
  double closed_loop_sse_at_end = std::numeric_limits<double>::quiet_NaN();

  Workspace workspace(layout);
  // Free-response coefficients (initial states of each submodel's 1/(p^l A_i) realisation at
  // the current iterate), taken from the last solution of (29); empty with `zero`.
  Eigen::VectorXd initial_states = Eigen::VectorXd::Zero(layout.augmented - p);
  Eigen::VectorXd states_at = beta;  // the iterate whose realisations they refer to
  result.termination = Termination::iteration_limit;
  bool stopped = false;
  if (closed_loop && update_source(beta)) {
    start_closed_loop_sse = closed_loop_sse(beta);
  } else if (closed_loop) {
    result.termination = Termination::closed_loop_unstable;
    result.message =
        options.initial_model
            ? name +
                  ": the controller does not stabilise the initial model, so S_uo r "
                  "(instrument (20)) cannot be formed; give a model the controller stabilises"
            : name + ": the controller does not stabilise any start found from the data (" +
                  (options.start == StartMethod::frf ? std::string("the FRF's resonance peaks")
                   : options.start == StartMethod::lssvf
                       ? std::string("LSSVF over a grid of filter bandwidths")
                       : std::string("LSSVF over a grid of filter bandwidths and the FRF's "
                                     "resonance peaks")) +
                  ", and open-loop SRIVC fits of them; each with its unstable poles reflected, "
                  "its gain halved up to " +
                  std::to_string(InitializationOptions::kStartGainHalvings) +
                  " times and refined by CLSRIVC), so S_uo r (instrument (20)) cannot be formed; "
                  "give a model the controller stabilises";
    stopped = true;
  }

  // Step control: a full step of (29) at which the equations are singular or non-finite is
  // halved toward the last accepted iterate instead of ending the iteration. Accepted steps
  // are the plain iteration, so every fixed point of (29) is still one of this iteration.
  const bool control = options.step_control;
  Eigen::VectorXd accepted;
  int halvings = 0;  // of the current step
  // The iterate with the lowest output error seen (the start included): returned instead of
  // the last one when the iteration did not converge and the last one fits worse.
  double start_sse = std::numeric_limits<double>::quiet_NaN();
  double best_sse = std::numeric_limits<double>::infinity();
  Eigen::VectorXd best_beta;
  int best_iteration = 0;
  int iteration = 1;
  while (!stopped && iteration <= options.max_iterations) {
    bool source_ok = true;
    if (closed_loop && iteration > 1) source_ok = update_source(beta);
    Moments sums;
    double sse = 0.0;
    evaluate(layout, beta, initial_states, signals, source, h, options.output_interpolation,
             workspace, &sums, nullptr, nullptr, &sse);
    if (std::isnan(start_sse)) start_sse = sse;
    if (std::isfinite(sse) && !(sse >= best_sse)) {
      best_sse = sse;
      best_beta = beta;
      best_iteration = iteration - 1;
    }
    const bool finite = sums.all_finite();
    Eigen::VectorXd sz;
    Eigen::VectorXd sp;
    Eigen::MatrixXd m;
    double rcond = 0.0;
    std::optional<Eigen::JacobiSVD<Eigen::MatrixXd>> svd;
    if (finite) {
      sz = norms_from_squares(sums.zz);
      sp = norms_from_squares(sums.pp);
      m = sz.cwiseInverse().asDiagonal() * sums.zp * sp.cwiseInverse().asDiagonal();
      svd.emplace(m);
      const Eigen::VectorXd& sv = svd->singularValues();
      rcond = sv(sv.size() - 1) / sv(0);
      result.reciprocal_condition = rcond;
    }
    if (control && accepted.size() > 0 && halvings < options.max_step_halvings &&
        (!finite || !(rcond > 1e-14))) {
      beta = 0.5 * (accepted + beta);
      ++halvings;
      ++result.step_halvings;
      continue;
    }
    if (!source_ok) ++result.sensitivity_fallbacks;
    if (!finite) {
      result.termination = Termination::non_finite;
      result.message = name + ": the filtered signals became non-finite at iteration " +
                       std::to_string(iteration) + "; the last finite iterate is returned";
      break;
    }
    const Eigen::MatrixXd rhs = sz.cwiseInverse().asDiagonal() * sums.zy;
    if (!(rcond > 1e-14)) {
      result.termination = Termination::singular_equations;
      result.message = name +
                       ": the instrument-regressor matrix of eq. (29) is numerically "
                       "singular at iteration " +
                       std::to_string(iteration) + " (reciprocal condition " +
                       format_significant(rcond, 3) +
                       "): the data do not excite the model enough or the orders are too high";
      break;
    }
    accepted = beta;
    halvings = 0;
    const Eigen::MatrixXd solution =
        sp.cwiseInverse().asDiagonal() * Eigen::MatrixXd(m.fullPivLu().solve(rhs));
    Eigen::VectorXd next(p);
    Eigen::MatrixXd off = solution.topRows(p);
    for (int i = 0; i < layout.size(); ++i) {
      const int o = layout.offset[static_cast<size_t>(i)];
      next.segment(o, layout.count(i)) = solution.block(o, i, layout.count(i), 1);
      off.block(o, i, layout.count(i), 1).setZero();
    }
    if (!next.allFinite()) {
      result.termination = Termination::non_finite;
      result.message = name + ": iteration " + std::to_string(iteration) +
                       " produced a non-finite parameter; the last finite iterate is returned";
      break;
    }
    reflect_all(next);
    const double change = relative_change(layout, beta, next);
    result.off_diagonal_norm = off.norm() / std::max(next.norm(), 1e-300);
    result.relative_change = change;
    result.iterations = iteration;
    initial_states = free_response_coefficients(layout, solution);
    states_at = beta;
    beta = next;
    if (options.record_history) {
      result.history.push_back({iteration, beta, change, result.off_diagonal_norm});
    }
    if (change < options.tolerance) {
      result.termination = Termination::converged;
      result.message = name + ": converged after " + std::to_string(iteration) +
                       " iterations (relative parameter change " + format_significant(change, 3) +
                       " < tolerance " + format_significant(options.tolerance, 3) + ")";
      break;
    }
    ++iteration;
  }
  if (result.termination == Termination::iteration_limit) {
    result.message = name + ": stopped at the iteration limit (" +
                     std::to_string(options.max_iterations) + ") with relative parameter change " +
                     format_significant(result.relative_change, 3) + ", above the tolerance " +
                     format_significant(options.tolerance, 3);
  }

  Eigen::VectorXd residual;
  double sse = 0.0;
  if (!result.converged() && best_beta.size() > 0) {
    evaluate(layout, beta, initial_states, signals, false, h, options.output_interpolation,
             workspace, nullptr, nullptr, nullptr, &sse);
    if (!(sse <= best_sse)) {
      beta = best_beta;
      result.message +=
          "; the iterate with the lowest output error (" +
          (best_iteration == 0 ? std::string("the start")
                               : "after " + std::to_string(best_iteration) +
                                     (best_iteration == 1 ? " iteration" : " iterations")) +
          ") is returned";
    }
  }
  if (!result.converged() && result.iterations == 0) {
    result.message += "; no step was completed, so the model is the start";
  }

  // The estimate and its statistics.
  result.parameters = beta;
  result.input_delay = delay;
  result.input_delay_fraction = layout.delay_fraction;
  result.model = AdditiveModel::from_parameters(layout.orders, beta, tau);
  result.transfer_function = result.model.to_transfer_function();
  if (problem.unfactored) {
    try {
      result.additive_view = AdditiveModel::from_transfer_function(result.transfer_function);
    } catch (const InvalidArgument&) {
      result.additive_view.reset();
    }
  } else {
    result.additive_view = result.model;
  }
  // Stopped before the first step because the controller does not stabilise the start: the
  // returned model is that start, which cannot describe the recorded loop.
  bool loop_unstable = closed_loop && result.termination == Termination::closed_loop_unstable &&
                       result.iterations == 0;
  if (closed_loop && result.termination != Termination::closed_loop_unstable) {
    if (update_source(beta)) {
      closed_loop_sse_at_end = closed_loop_sse(beta);
    } else {
      ++result.sensitivity_fallbacks;
      loop_unstable = true;
    }
  }
  if (layout.free_responses() && result.iterations > 0) {
    // The loop's free-response coefficients come from the solve at the previous iterate;
    // one more solve of (29) at the returned beta gives them in its own realisations.
    Moments sums;
    evaluate(layout, beta, initial_states, signals, source, h, options.output_interpolation,
             workspace, &sums, nullptr, nullptr);
    if (std::optional<Eigen::MatrixXd> solution = solve_scaled(sums)) {
      initial_states = free_response_coefficients(layout, *solution);
      states_at = beta;
    }
  }
  // The delay's column of the instrument: the sensitivity of the noise-free model output to
  // tau, as the other columns are theirs to the parameters (a central difference within the
  // sample interval, where the held input makes the output smooth in tau).
  Eigen::VectorXd delay_column;
  const bool delay_column_used =
      options.compute_covariance && options.delay_estimated && beta.allFinite();
  if (delay_column_used) {
    const Hold hold = closed_loop ? Hold::zero_order_hold : layout.input_hold;
    const double step = 1e-4;
    const double f = layout.delay_fraction;
    const double up = f + step < 1.0 ? step : 0.0;
    const double down = f - step >= 0.0 ? step : 0.0;
    auto output_at = [&](double shift) {
      Eigen::VectorXd out(n_samples);
      for (size_t r = 0; r < records.size(); ++r) {
        const Eigen::VectorXd& driven =
            closed_loop ? signals[r].undelayed_source : records[r]->input();
        const double own = (delay_of(r) - delay) * h;
        out.segment(signals[r].offset, records[r]->size()) =
            model_output(result.model.with_input_delay(tau + own + shift * h), driven, h, hold);
      }
      return out;
    };
    delay_column = (output_at(up) - output_at(-down)) / ((up + down) * h);
  }
  InstrumentPass instrument;
  instrument.extra = delay_column_used ? &delay_column : nullptr;
  instrument.keep_checkpoints =
      options.noise != NoiseAssumption::white && !problem.stored_instrument_covariance;
  Eigen::MatrixXd stored_psi;
  if (problem.stored_instrument_covariance) instrument.stored = &stored_psi;
  evaluate(layout, beta, initial_states, signals, source, h, options.output_interpolation,
           workspace, nullptr, &residual, options.compute_covariance ? &instrument : nullptr);
  sse = residual.squaredNorm();
  result.mean_squared_error = sse / n_samples;
  result.noise_variance = sse / std::max(n_samples - unknowns, 1);
  result.fit_percent = fit_percent(y, y - residual);
  if (layout.free_responses())
    result.initial_conditions = free_response_derivatives(layout, states_at, initial_states);
  {
    // The start's fit, from the same definition: 100 (1 - ||e|| / ||y - mean(y)||).
    const double spread = (y.array() - y.mean()).matrix().norm();
    result.start_fit_percent = std::isnan(start_sse) ? result.fit_percent
                               : spread > 0.0        ? 100.0 * (1.0 - std::sqrt(start_sse) / spread)
                                                     : std::numeric_limits<double>::quiet_NaN();
    if (spread > 0.0) {
      result.closed_loop_fit_percent = 100.0 * (1.0 - std::sqrt(closed_loop_sse_at_end) / spread);
      result.start_closed_loop_fit_percent =
          100.0 * (1.0 - std::sqrt(start_closed_loop_sse) / spread);
    }
  }

  if (options.compute_covariance && instrument.gram.allFinite() && residual.allFinite()) {
    // With free responses the joint covariance of beta and their coefficients; its beta
    // block is the covariance of beta with the nuisance coefficients estimated alongside.
    const int joint_unknowns = unknowns + (delay_column_used ? 1 : 0);
    const Eigen::MatrixXd joint =
        problem.stored_instrument_covariance
            ? instrumental_variable_covariance(stored_psi, residual, joint_unknowns, options.noise,
                                               options.noise_model_max_order)
            : covariance_from_gram(
                  instrument.gram, residual, joint_unknowns, options.noise,
                  options.noise_model_max_order,
                  [&](const AutoregressiveModel& ar, const Eigen::VectorXd& scales) {
                    return adjoint_instrument_sum(layout, beta, initial_states, signals, source, h,
                                                  options.output_interpolation, workspace,
                                                  instrument, ar, scales);
                  });
    result.covariance = joint.topLeftCorner(p, p);
    if (delay_column_used) {
      result.delay_standard_error = std::sqrt(std::max(joint(unknowns, unknowns), 0.0));
    }
    result.standard_errors = result.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
    result.modes = modal_estimates(result.model, result.covariance, problem.unfactored);
  }

  // Assumption 4.
  checks.nyquist_frequency = M_PI / h;
  checks.largest_pole_frequency = largest_pole_frequency(result.model);
  checks.sampling_rate_ok = checks.largest_pole_frequency < checks.nyquist_frequency;
  if (!checks.sampling_rate_ok) {
    checks.warnings.push_back("a pole's imaginary part " +
                              format_significant(checks.largest_pole_frequency, 3) +
                              " rad/s is not below the Nyquist frequency " +
                              format_significant(checks.nyquist_frequency, 3) +
                              " rad/s (Assumption 4): sample faster or lower the model order");
  }
  result.checks = std::move(checks);
  result.verdict = refined_iv_verdict(result, closed_loop, loop_unstable);
  return result;
}

namespace {

// The additive closed-loop estimator from the data alone (decision 0028). CLSRIVC can have
// several stationary points on one closed-loop record, and the output error y - G u it is
// started by leans toward -1/C_d, so one start is not enough: the additive iteration runs from
// the additive start of each start method and from the split of the unfactored CLSRIVC fit of
// each. Of the usable estimates (the verdict holds each to the loop the controller keeps
// stable and to its closed-loop fit from r), the one kept has the best output-error fit
// y - G u: with the noise fed back through the loop it tells the stationary points apart where
// the closed-loop fit from r, in which r explains little of y, cannot (measured in decision
// 0028).
EstimationResult closed_loop_additive_from_data(const RefinedIvProblem& problem,
                                                const RefinedIvOptions& options) {
  std::vector<StartMethod> methods;
  if (options.start == StartMethod::automatic) {
    methods = {StartMethod::lssvf, StartMethod::frf};
  } else {
    methods = {options.start};
  }
  std::vector<EstimationResult> candidates;
  for (StartMethod method : methods) {
    RefinedIvOptions own = options;
    own.start = method;
    ScreenedStart start;  // screened once for both fits from this method
    try {
      candidates.push_back(run_refined_iv_from_start(problem, own, &start));
    } catch (const InvalidArgument&) {
      // e.g. too few resonance peaks for the FRF start: the other candidates remain
    }
    RefinedIvProblem unfactored = problem;
    unfactored.orders = {unfactored_order(problem.orders)};
    unfactored.unfactored = true;
    RefinedIvOptions quick = own;
    quick.compute_covariance = false;
    quick.record_history = false;
    std::optional<AdditiveModel> whole;  // one submodel, grouped by the engine
    try {
      EstimationResult g = run_refined_iv_from_start(unfactored, quick, &start);
      if (g.parameters.allFinite() && g.iterations > 0) whole = std::move(g.model);
    } catch (const InvalidArgument&) {
    }
    if (!whole) continue;
    RefinedIvOptions split = options;
    split.initial_model = std::move(whole);
    try {
      candidates.push_back(run_refined_iv_from_start(problem, split));
    } catch (const InvalidArgument&) {
      // the unfactored fit's poles cannot be grouped into the submodels
    }
  }
  // No candidate at all: the plain run, which names what went wrong.
  if (candidates.empty()) return run_refined_iv_from_start(problem, options);
  // Usable first, by their output-error fit; if none is, the best closed-loop fit from r
  // (NaN, a loop the controller does not hold, last). Ties keep the earlier candidate.
  auto better = [](const EstimationResult& a, const EstimationResult& b) {
    if (a.verdict.usable != b.verdict.usable) return a.verdict.usable;
    auto score = [usable = a.verdict.usable](const EstimationResult& r) {
      const double f = usable ? r.fit_percent : r.closed_loop_fit_percent;
      return std::isnan(f) ? -HUGE_VAL : f;
    };
    return score(a) > score(b);
  };
  size_t best = 0;
  for (size_t k = 1; k < candidates.size(); ++k) {
    if (better(candidates[k], candidates[best])) best = k;
  }
  EstimationResult result = std::move(candidates[best]);
  result.message += "; of " + std::to_string(candidates.size()) +
                    " fits from different starts, the usable one with the best output-error fit "
                    "was kept (with none usable, the best closed-loop fit from r)";
  return result;
}

}  // namespace

EstimationResult run_refined_iv(const RefinedIvProblem& problem, const RefinedIvOptions& options) {
  if (problem.controller != nullptr && !problem.unfactored && problem.orders.size() > 1 &&
      !options.initial_model) {
    options.validate();
    return closed_loop_additive_from_data(problem, options);
  }
  return run_refined_iv_from_start(problem, options);
}

}  // namespace internal
}  // namespace ctid
