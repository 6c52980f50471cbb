// The streamed passes of the refined IV iteration (29) (internal/refined_iv_passes.h): per
// iteration and submodel, one filter bank of u through 1/(p^l A_i) (regressor B-part, model
// output), one cascade p^k B_i/(p^l A_i^2) of the instrument source (u or S_uo r), and one bank
// of the residual output y~_i (23) through 1/A_i, run block by block over every record.
#include <algorithm>
#include <cmath>
#include <functional>
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
#include "ctid/filtering/filter_bank.h"
#include "ctid/refined_iv/covariance.h"
#include "ctid/simulation/discretization.h"
#include "refined_iv/internal/covariance_sums.h"
#include "refined_iv/internal/refined_iv_engine.h"
#include "refined_iv/internal/refined_iv_passes.h"

namespace ctid::internal {

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

namespace srivc_engine {

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

namespace {

// B/(p^l A) of submodel i at beta realised (the bank of 1/(p^l A) with its outputs combined by
// b) and discretised under ZOH with the fraction of the delay (one more state); none when the
// submodel is degenerate: a parameter that is not finite, no poles left, more numerator
// coefficients than the bank has outputs, or an entry of the realisation that is not finite
// (A lost its leading coefficient, so the realisation overflows).
std::optional<StateSpace> sampled_loop_submodel(const Layout& layout, const Eigen::VectorXd& beta,
                                                int i, double h) {
  const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
  if (!beta.segment(layout.offset[static_cast<size_t>(i)], o.n + o.m + 1).allFinite()) {
    return std::nullopt;
  }
  const Eigen::VectorXd b = numerator_of(layout, beta, i);
  const std::optional<FilterRealization> bank = finite_derivative_filters(
      Polynomial::monomial(o.integrators) * denominator_of(layout, beta, i));
  if (!bank || b.size() > bank->outputs()) return std::nullopt;
  Eigen::VectorXd w = Eigen::VectorXd::Zero(bank->outputs());
  w.head(b.size()) = b;
  const FilterRealization f = combine_outputs(*bank, w);
  if (!f.finite()) return std::nullopt;
  return discretize_zoh(StateSpace{f.a, f.b, f.c.row(0), f.d(0)}, h, layout.delay_fraction);
}

}  // namespace

std::optional<std::vector<StateSpace>> sampled_loop_plant(const Layout& layout,
                                                          const Eigen::VectorXd& beta, double h) {
  std::vector<StateSpace> parts;
  for (int i = 0; i < layout.size(); ++i) {
    std::optional<StateSpace> part = sampled_loop_submodel(layout, beta, i, h);
    if (!part) return std::nullopt;
    parts.push_back(std::move(*part));
  }
  return parts;
}

bool realisable(const Layout& layout, bool closed_loop, double h, const Eigen::VectorXd& beta) {
  for (int i = 0; i < layout.size(); ++i) {
    const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
    const Polynomial a = denominator_of(layout, beta, i);
    if (!finite_derivative_filters(Polynomial::monomial(o.integrators) * a)) return false;
    if (o.n > 0 && !finite_derivative_filters(a)) return false;
  }
  return !closed_loop || sampled_loop_plant(layout, beta, h).has_value();
}

std::optional<Eigen::VectorXd> sensitivity_filtered_reference(
    const std::vector<StateSpace>& parts, const DiscreteTransferFunction& controller,
    const Eigen::VectorXd& r, int delay) {
  // Plant: the submodels side by side.
  double dg = 0.0;
  int ng = 0;
  for (const StateSpace& part : parts) {
    dg += part.d;
    ng += part.order();
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

namespace {

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
    for (StepBuffers& b : w.steps) {
      b.instrument.rightCols(free).setZero();
      b.regressor.rightCols(free).setZero();
    }
  }
  return filters;
}

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

// Submodel i's filters of the instrument source and of the input, and its free response, on
// rows [k0, k0 + len) of one record, continuing from row k0, into rows [row0, row0 + len) of
// a step's buffers `to`: the submodel's instrument columns, the B-part of its regressor columns and
// its output G_i u.
void filter_inputs(const Layout& layout, int record, const RecordSignals& signals,
                   const Eigen::VectorXd* source, int i, Eigen::Index k0, Eigen::Index len,
                   Eigen::Index row0, bool need_instrument, bool need_regressor, SubmodelFilters& f,
                   Workspace& w, StepBuffers& to) {
  const Eigen::VectorXd& u = signals.u;
  const bool closed_loop = source != nullptr;
  const auto at = static_cast<size_t>(i);
  const SubmodelOrder& o = layout.orders[at];
  const int off = layout.offset[at];
  if (f.source) {
    Eigen::MatrixXd& out = w.source_out[at];
    out.resize(len, f.source->outputs());
    f.source->run((closed_loop ? *source : u).segment(k0, len), f.source_stream, out);
    to.instrument.block(row0, off + o.n, len, o.m + 1) = out.leftCols(o.m + 1);
    if (o.n > 0) to.instrument.block(row0, off, len, o.n) = -out.middleCols(o.m + 1, o.n);
    if (!closed_loop) {
      to.outputs.col(i).segment(row0, len) = out.col(o.m + o.n + 1);
      if (need_regressor) {
        to.regressor.block(row0, off + o.n, len, o.m + 1) = out.leftCols(o.m + 1);
      }
    }
  }
  if (f.input) {
    Eigen::MatrixXd& out = w.input_out[at];
    out.resize(len, f.input->outputs());
    f.input->run(u.segment(k0, len), f.input_stream, out);
    to.outputs.col(i).segment(row0, len) = out.col(o.m + 1);
    if (need_regressor) to.regressor.block(row0, off + o.n, len, o.m + 1) = out.leftCols(o.m + 1);
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
    to.outputs.col(i).segment(row0, len) += r.value.head(len);
    if (need_instrument) {
      to.instrument.block(row0, free_off, len, s) = r.basis.topRows(len);
      if (!closed_loop && o.n > 0) {
        to.instrument.block(row0, off, len, o.n) -= r.filtered.topRows(len);
      }
    }
    if (need_regressor) to.regressor.block(row0, free_off, len, s) = r.basis.topRows(len);
  }
}

// Submodel i's residual output y~_i (23) on rows [k0, k0 + len) of record output y through its
// bank of 1/A_i, into rows [row0, row0 + len) of `to`: its column of Upsilon (22) and
// the a-part of its regressor columns (24). Needs every submodel's output on those rows.
void filter_output(const Layout& layout, const Eigen::VectorXd& y, int i, Eigen::Index k0,
                   Eigen::Index len, Eigen::Index row0, SubmodelFilters& f, Workspace& w,
                   StepBuffers& to) {
  const auto at = static_cast<size_t>(i);
  const SubmodelOrder& o = layout.orders[at];
  Eigen::VectorXd& residual_output = w.residual_output[at];
  residual_output.head(len) = y.segment(k0, len) - to.total.segment(row0, len) +
                              to.outputs.col(i).segment(row0, len);  // (23)
  if (f.output) {
    Eigen::MatrixXd& out = w.output_out[at];
    out.resize(len, f.output->outputs());
    f.output->run(residual_output.head(len), f.output_stream, out);
    to.filtered.col(i).segment(row0, len) = out.col(0);                               // (22)
    to.regressor.block(row0, layout.offset[at], len, o.n) = -out.middleCols(1, o.n);  // (24)
  } else {
    to.filtered.col(i).segment(row0, len) = residual_output.head(len);
  }
}

// Rows [k0, k0 + len) of one record's instrument, its filters continuing from row k0, into the
// first len rows of `to` (the covariance's backward pass, which needs nothing else).
void instrument_block(const Layout& layout, int record, const RecordSignals& signals,
                      const Eigen::VectorXd* source, Eigen::Index k0, Eigen::Index len,
                      std::vector<SubmodelFilters>& filters, Workspace& w, StepBuffers& to) {
  for (int i = 0; i < layout.size(); ++i) {
    filter_inputs(layout, record, signals, source, i, k0, len, 0, true, false,
                  filters[static_cast<size_t>(i)], w, to);
  }
}

// Calls body(b0, len) for the kBlock-row blocks of `rows` rows, in order.
template <typename Body>
void for_blocks(Eigen::Index rows, Body&& body) {
  for (Eigen::Index b0 = 0; b0 < rows; b0 += kBlock) body(b0, std::min(kBlock, rows - b0));
}

// Runs body(task) for every task in [0, count), on the workspace's team when it has one.
void run_tasks(int count, Workspace& w, const std::function<void(int)>& body) {
  if (w.team) {
    w.team->run(count, body);
  } else {
    for (int task = 0; task < count; ++task) body(task);
  }
}

// What a pass does with rows [k0, k0 + len) of a record once they are filtered into buffer `b`,
// in row order, block by block: RIVC's prefilter, the sums of eq. (29), the residual, the sum
// of squares and the instrument's sums.
struct StepTail {
  const Layout& layout;
  const RecordSignals& signals;
  bool need_instrument;
  bool need_regressor;
  Workspace& w;
  Moments* moments;
  Eigen::VectorXd* residual;
  InstrumentPass* instrument;
  double* sse;

  void operator()(Eigen::Index k0, Eigen::Index len, StepBuffers& b) const {
    const Eigen::VectorXd& y = *signals.y;
    const Eigen::Index first = signals.offset;
    for_blocks(len, [&](Eigen::Index b0, Eigen::Index bl) {
      if (w.prefilter && need_instrument)
        w.prefilter->instrument.apply(b.instrument.middleRows(b0, bl));
      if (w.prefilter && need_regressor) {
        w.prefilter->regressor.apply(b.regressor.middleRows(b0, bl));
        w.prefilter->filtered.apply(b.filtered.middleRows(b0, bl));
      }
      if (moments != nullptr) {
        const auto z = b.instrument.middleRows(b0, bl);
        const auto phi = b.regressor.middleRows(b0, bl);
        moments->zp.noalias() += z.transpose() * phi;
        moments->zy.noalias() += z.transpose() * b.filtered.middleRows(b0, bl);
        moments->zz += z.colwise().squaredNorm().transpose();
        moments->pp += phi.colwise().squaredNorm().transpose();
      }
      const auto error = y.segment(k0 + b0, bl) - b.total.segment(b0, bl);
      if (residual != nullptr) residual->segment(first + k0 + b0, bl) = error;
      if (sse != nullptr) *sse += error.squaredNorm();
      if (instrument != nullptr) {
        auto z = instrument->rows.topRows(bl);
        instrument->copy_rows(layout, b, first, k0 + b0, b0, bl, z);
        instrument->gram.noalias() += z.transpose() * z;
        if (instrument->stored != nullptr) instrument->stored->middleRows(first + k0 + b0, bl) = z;
      }
    });
  }
};

// evaluate() on one record: its filters from rest, its free responses, its rows of the
// stacked residual and instrument; the sums are added to. A pipeline of three stages over the
// steps, one buffer each: at step t, one task per submodel runs its input filters over step t,
// one per submodel its residual-output bank over step t - 1 (whose outputs are all known), and
// one task adds the tail of step t - 2. Each filter and each sum still sees its rows in order.
void evaluate_record(const Layout& layout, const Eigen::VectorXd& beta,
                     const Eigen::VectorXd& initial_states, int record,
                     const RecordSignals& signals, const Eigen::VectorXd* source, double h,
                     Hold output_interpolation, Workspace& w, Moments* moments,
                     Eigen::VectorXd* residual, InstrumentPass* instrument, double* sse) {
  const Eigen::Index n = signals.u.size();
  const bool need_instrument = moments != nullptr || instrument != nullptr;
  const bool need_regressor = moments != nullptr;
  const int k_count = layout.size();
  std::vector<SubmodelFilters> filters =
      record_filters(layout, beta, initial_states, record, h, output_interpolation,
                     source != nullptr, need_instrument, need_regressor, w);
  if (w.prefilter) w.prefilter->reset();
  const StepTail tail{layout,     signals, need_instrument, need_regressor, w, moments, residual,
                      instrument, sse};
  const Eigen::Index steps = (n + kStep - 1) / kStep;
  const auto first_row = [](Eigen::Index step) { return step * kStep; };
  const auto rows = [&](Eigen::Index step) { return std::min(kStep, n - step * kStep); };
  const auto buffer = [&](Eigen::Index step) -> StepBuffers& {
    return w.steps[static_cast<size_t>(step % 3)];
  };
  for (Eigen::Index t = 0; t < steps + 2; ++t) {
    const bool filtering = t < steps;
    const bool previous = t >= 1 && t - 1 < steps;  // step t - 1 exists
    const bool banking = need_regressor && previous;
    const bool finishing = t >= 2;
    if (filtering && instrument != nullptr && instrument->keep_checkpoints &&
        first_row(t) % kSegment == 0) {
      instrument->saved[static_cast<size_t>(record)].push_back(checkpoint(filters));
    }
    if (previous) {
      StepBuffers& b = buffer(t - 1);
      b.total.head(rows(t - 1)) = b.outputs.topRows(rows(t - 1)).rowwise().sum();
    }
    run_tasks(1 + 2 * k_count, w, [&](int task) {
      if (task == 0) {
        if (finishing) tail(first_row(t - 2), rows(t - 2), buffer(t - 2));
      } else if (task <= k_count) {
        if (!filtering) return;
        const int i = task - 1;
        for_blocks(rows(t), [&](Eigen::Index b0, Eigen::Index bl) {
          filter_inputs(layout, record, signals, source, i, first_row(t) + b0, bl, b0,
                        need_instrument, need_regressor, filters[static_cast<size_t>(i)], w,
                        buffer(t));
        });
      } else {
        if (!banking) return;
        const int i = task - 1 - k_count;
        for_blocks(rows(t - 1), [&](Eigen::Index b0, Eigen::Index bl) {
          filter_output(layout, *signals.y, i, first_row(t - 1) + b0, bl, b0,
                        filters[static_cast<size_t>(i)], w, buffer(t - 1));
        });
      }
    });
  }
}

}  // namespace

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
              Eigen::VectorXd* residual, InstrumentPass* instrument, double* sse) {
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
        instrument_block(layout, record, signals, source, k0, len, filters, w, w.steps[0]);
        pass.copy_rows(layout, w.steps[0], signals.offset, k0, 0, len,
                       segment.middleRows(k0 - start, len));
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
std::optional<Eigen::MatrixXd> solve_scaled(const Moments& sums, const Layout& layout,
                                            const HeldCoefficients& held,
                                            const CoefficientBounds& bounds) {
  if (!sums.all_finite()) return std::nullopt;
  const Eigen::VectorXd sz = norms_from_squares(sums.zz);
  const Eigen::VectorXd sp = norms_from_squares(sums.pp);
  const Eigen::MatrixXd m =
      sz.cwiseInverse().asDiagonal() * sums.zp * sp.cwiseInverse().asDiagonal();
  if (!(Eigen::FullPivLU<Eigen::MatrixXd>(m).rcond() > 1e-14)) return std::nullopt;
  const Eigen::MatrixXd rhs = sz.cwiseInverse().asDiagonal() * sums.zy;
  HeldCoefficients at_bounds;
  Eigen::MatrixXd solution = constrained_solution(m, sp, rhs, layout, held, bounds, at_bounds);
  if (!solution.allFinite()) return std::nullopt;
  return solution;
}

namespace {

// The free and held indices of an n-vector.
std::pair<std::vector<Eigen::Index>, std::vector<Eigen::Index>> free_and_held(
    Eigen::Index n, const HeldCoefficients& held) {
  std::vector<bool> is_held(static_cast<std::size_t>(n), false);
  std::vector<Eigen::Index> h;
  for (const auto& [j, value] : held) {
    is_held[static_cast<std::size_t>(j)] = true;
    h.push_back(j);
  }
  std::vector<Eigen::Index> f;
  for (Eigen::Index j = 0; j < n; ++j) {
    if (!is_held[static_cast<std::size_t>(j)]) f.push_back(j);
  }
  return {f, h};
}

// The column of (29) that holds coefficient j: its submodel's (the one column of a solution
// with one).
Eigen::Index own_column(const Layout& layout, Eigen::Index j, Eigen::Index columns) {
  int owner = 0;
  while (owner + 1 < layout.size() && j >= layout.offset[owner + 1]) ++owner;
  return std::min<Eigen::Index>(owner, columns - 1);
}

}  // namespace

Eigen::MatrixXd held_solution(const Eigen::MatrixXd& m, const Eigen::VectorXd& sp,
                              const Eigen::MatrixXd& rhs, const Layout& layout,
                              const HeldCoefficients& held) {
  const auto [f, h] = free_and_held(m.rows(), held);
  // wh(k, c): held coefficient k in column c, its value in its own submodel's column.
  Eigen::MatrixXd wh = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(h.size()), rhs.cols());
  for (std::size_t k = 0; k < held.size(); ++k) {
    wh(static_cast<Eigen::Index>(k), own_column(layout, held[k].first, rhs.cols())) =
        held[k].second;
  }
  const Eigen::MatrixXd vh = sp(h).asDiagonal() * wh;
  const Eigen::MatrixXd vf = m(f, f).fullPivLu().solve(rhs(f, Eigen::all) - m(f, h) * vh);
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(m.rows(), rhs.cols());
  for (std::size_t k = 0; k < f.size(); ++k) {
    w.row(f[k]) = vf.row(static_cast<Eigen::Index>(k)) / sp(f[k]);
  }
  for (std::size_t k = 0; k < h.size(); ++k) w.row(h[k]) = wh.row(static_cast<Eigen::Index>(k));
  return w;
}

Eigen::MatrixXd constrained_solution(const Eigen::MatrixXd& m, const Eigen::VectorXd& sp,
                                     const Eigen::MatrixXd& rhs, const Layout& layout,
                                     const HeldCoefficients& held, const CoefficientBounds& bounds,
                                     HeldCoefficients& at_bounds) {
  at_bounds.clear();
  Eigen::MatrixXd w = held.empty() ? Eigen::MatrixXd(sp.cwiseInverse().asDiagonal() *
                                                     Eigen::MatrixXd(m.fullPivLu().solve(rhs)))
                                   : held_solution(m, sp, rhs, layout, held);
  // Each pass holds at least one more coefficient, so there are at most as many as bounds.
  for (std::size_t pass = 0; pass < bounds.size(); ++pass) {
    const std::size_t before = at_bounds.size();
    for (const auto& [j, lower, upper] : bounds) {
      const bool held_already = std::any_of(at_bounds.begin(), at_bounds.end(),
                                            [&](const auto& a) { return a.first == j; });
      const double value = w(j, own_column(layout, j, w.cols()));
      if (held_already) continue;
      if (value < lower) at_bounds.emplace_back(j, lower);
      if (value > upper) at_bounds.emplace_back(j, upper);
    }
    if (at_bounds.size() == before) break;
    HeldCoefficients fixed = held;
    fixed.insert(fixed.end(), at_bounds.begin(), at_bounds.end());
    std::sort(fixed.begin(), fixed.end());
    w = held_solution(m, sp, rhs, layout, fixed);
  }
  std::sort(at_bounds.begin(), at_bounds.end());
  return w;
}

HeldCoefficients coefficients_at_bounds(const Eigen::VectorXd& beta,
                                        const CoefficientBounds& bounds) {
  HeldCoefficients at;
  for (const auto& [j, lower, upper] : bounds) {
    if (beta(j) == lower || beta(j) == upper) at.emplace_back(j, beta(j));
  }
  return at;
}

std::vector<std::string> active_constraint_notes(int reflections, const HeldCoefficients& at_bounds,
                                                 const std::vector<std::string>& names) {
  std::vector<std::string> notes;
  if (reflections > 0) {
    notes.push_back("stability: right-half-plane poles were reflected into the left half-plane (" +
                    std::to_string(reflections) + " times in the iteration)");
  }
  for (const auto& [j, value] : at_bounds) {
    notes.push_back(names[static_cast<std::size_t>(j)] + " is at its bound " +
                    format_significant(value, 6));
  }
  return notes;
}

Eigen::MatrixXd covariance_given_held(const Eigen::MatrixXd& p, const HeldCoefficients& held) {
  const auto [f, h] = free_and_held(p.rows(), held);
  const Eigen::MatrixXd phh = p(h, h);
  const Eigen::MatrixXd pfh = p(f, h);
  const Eigen::MatrixXd given = p(f, f) - pfh * phh.ldlt().solve(pfh.transpose());
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(p.rows(), p.cols());
  out(f, f) = given;
  return out;
}

}  // namespace srivc_engine
}  // namespace ctid::internal
