// The streamed passes of the refined IV iteration (29) behind SRIVC, CLSRIVC and the additive
// estimators: the augmented parameter layout, the per-record filter banks run block by block
// over the data, and the sums and instrument Gram matrix they leave. Split out of
// refined_iv.cc so that the driver there reads as the algorithm's phases; private to
// refined_iv.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/core/hold.h"
#include "ctid/core/parallel.h"
#include "ctid/core/polynomial.h"
#include "ctid/core/sampled_data.h"
#include "ctid/core/state_space.h"
#include "ctid/estimation/arma.h"
#include "ctid/filtering/filter_bank.h"
#include "ctid/refined_iv/covariance.h"
#include "ctid/refined_iv/refined_iv_options.h"

namespace ctid::internal::srivc_engine {

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

// Rows of the record filtered together by one call of a filter and summed together: the
// filters' scratch stays in cache, and the sums of eq. (29) are added block by block, so no
// N x p matrix is ever stored during the iteration.
constexpr Eigen::Index kBlock = 256;

// Rows between two checkpoints of the instrument pass.
constexpr Eigen::Index kSegment = 16 * kBlock;

// Rows of one step of a pass (decision 0068): the submodels' filters run over a step's rows as
// one task each, beside the residual-output banks of the step before and the sums of the step
// before that, each of the three steps in one of the workspace's three buffers. Every filter
// and every sum keeps its order of operations, so the bits do not depend on the number of
// threads.
constexpr Eigen::Index kStep = 4 * kBlock;

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

// RIVC's discrete prefilter D/C (RefinedIvOptions::noise_model) on the instrument, regressor
// and filtered-output columns of every block after the continuous filters, from rest at each
// record's first sample.
struct NoisePrefilter {
  InverseNoiseFilter instrument;
  InverseNoiseFilter regressor;
  InverseNoiseFilter filtered;

  NoisePrefilter(const ArmaModel& model, const Layout& layout)
      : instrument(model, layout.augmented),
        regressor(model, layout.augmented),
        filtered(model, layout.size()) {}
  void reset() {
    instrument.reset();
    regressor.reset();
    filtered.reset();
  }
};

// A step's rows of the signals the passes form (kStep rows each).
struct StepBuffers {
  Eigen::MatrixXd instrument;  // x p
  Eigen::MatrixXd regressor;   // x p
  Eigen::MatrixXd filtered;    // x K, Upsilon (26)
  Eigen::MatrixXd outputs;     // x K, G_i u
  Eigen::VectorXd total;

  explicit StepBuffers(const Layout& layout)
      : instrument(kStep, layout.augmented),
        regressor(kStep, layout.augmented),
        filtered(kStep, layout.size()),
        outputs(kStep, layout.size()),
        total(kStep) {}
};

// Buffers reused by every pass of one estimate: three steps' rows (kStep), each submodel's
// scratch, and the team of threads that runs the tasks of a step (none: one thread).
struct Workspace {
  std::array<StepBuffers, 3> steps;
  std::vector<Eigen::VectorXd> residual_output;  // per submodel, kBlock: y~_i (23)
  std::vector<Eigen::MatrixXd> source_out;
  std::vector<Eigen::MatrixXd> input_out;
  std::vector<Eigen::MatrixXd> output_out;
  // RIVC: the prefilter the passes apply after the continuous filters; none for SRIVC.
  std::optional<NoisePrefilter> prefilter;
  std::unique_ptr<ThreadTeam> team;

  Workspace(const Layout& layout, int threads)
      : steps{StepBuffers(layout), StepBuffers(layout), StepBuffers(layout)},
        residual_output(static_cast<size_t>(layout.size()), Eigen::VectorXd(kBlock)),
        source_out(static_cast<size_t>(layout.size())),
        input_out(static_cast<size_t>(layout.size())),
        output_out(static_cast<size_t>(layout.size())) {
    if (threads > 1) team = std::make_unique<ThreadTeam>(threads);
  }
};

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

// Where a record's filters are between two blocks: enough to run them on from there.
struct FilterCheckpoint {
  std::vector<SampledFilter::Stream> source;
  std::vector<SampledFilter::Stream> input;
  std::vector<SampledFilter::Stream> output;
  std::vector<Eigen::MatrixXd> free;
};

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

  // psi's rows [k0, k0 + len) of the record starting at `first`, from rows [row0, row0 + len)
  // of a step's buffers, into `to` (len x q).
  void copy_rows(const Layout& layout, const StepBuffers& b, Eigen::Index first, Eigen::Index k0,
                 Eigen::Index row0, Eigen::Index len, Eigen::Ref<Eigen::MatrixXd> to) const {
    to.leftCols(layout.augmented) = b.instrument.middleRows(row0, len);
    if (extra != nullptr) to.col(layout.augmented) = extra->segment(first + k0, len);
  }
};

/// The stopping rule's relative change, block by block (see the definition).
double relative_change(const Layout& layout, const Eigen::VectorXd& from,
                       const Eigen::VectorXd& to);
/// A_i and B_i of submodel i at beta.
Polynomial denominator_of(const Layout& layout, const Eigen::VectorXd& beta, int i);
Eigen::VectorXd numerator_of(const Layout& layout, const Eigen::VectorXd& beta, int i);

/// The model at beta as the loop's sampled plant: each submodel B_i/(p^l A_i) realised and
/// discretised under ZOH with the fraction of the delay. None when a submodel is degenerate (a
/// parameter not finite, no poles left, or A_i lost its leading coefficient so that its
/// realisation overflows): the value controller_stabilises and the engine steer on (decision
/// 0045).
std::optional<std::vector<StateSpace>> sampled_loop_plant(const Layout& layout,
                                                          const Eigen::VectorXd& beta, double h);

/// Whether the passes can filter at beta (decision 0050): every submodel's bank of 1/(p^l A_i),
/// and of 1/A_i when it has poles, has a finite realisation, and in closed loop the loop's
/// sampled plant exists. These are the conditions under which evaluate and the closed-loop
/// source used to throw InvalidArgument; a degenerate beta (A_i lost its leading coefficient)
/// fails them, and the engine never steps onto such a beta.
bool realisable(const Layout& layout, bool closed_loop, double h, const Eigen::VectorXd& beta);

/// S_uo(q) r with S_uo = C_d / (1 + G_d C_d), G_d the plant of sampled_loop_plant followed by
/// `delay` whole samples; std::nullopt when the loop is unstable or ill-posed.
std::optional<Eigen::VectorXd> sensitivity_filtered_reference(
    const std::vector<StateSpace>& plant, const DiscreteTransferFunction& controller,
    const Eigen::VectorXd& r, int delay);

/// One pass over the records at beta: the sums of eq. (29), the stacked residual, the
/// instrument's sums for the covariance and the output error's sum of squares, each when asked.
void evaluate(const Layout& layout, const Eigen::VectorXd& beta,
              const Eigen::VectorXd& initial_states, const std::vector<RecordSignals>& records,
              bool with_source, double h, Hold output_interpolation, Workspace& w, Moments* moments,
              Eigen::VectorXd* residual, InstrumentPass* instrument, double* sse = nullptr);

/// The coloured-noise middle factor's sum over the instrument of a pass that kept its
/// checkpoints.
Eigen::MatrixXd adjoint_instrument_sum(const Layout& layout, const Eigen::VectorXd& beta,
                                       const Eigen::VectorXd& initial_states,
                                       const std::vector<RecordSignals>& records, bool with_source,
                                       double h, Hold output_interpolation, Workspace& w,
                                       const InstrumentPass& pass, const AutoregressiveModel& ar,
                                       const Eigen::VectorXd& scales);

/// The free-response coefficients from the solution of (29), and their realisation-independent
/// form.
Eigen::VectorXd free_response_coefficients(const Layout& layout, const Eigen::MatrixXd& solution);
Eigen::VectorXd free_response_derivatives(const Layout& layout, const Eigen::VectorXd& beta,
                                          const Eigen::VectorXd& initial_states);

/// Column norms from their squares, 1 where a norm is zero or not finite.
Eigen::VectorXd norms_from_squares(const Eigen::VectorXd& squares);
/// The solution of (29) from its sums with unit-norm columns, or nothing.
/// Coefficients held at known values: (index in the augmented vector, value).
using HeldCoefficients = std::vector<std::pair<Eigen::Index, double>>;

/// Coefficients kept within bounds: (index in the augmented vector, lower, upper).
using CoefficientBounds = std::vector<std::tuple<Eigen::Index, double, double>>;

std::optional<Eigen::MatrixXd> solve_scaled(const Moments& sums, const Layout& layout,
                                            const HeldCoefficients& held = {},
                                            const CoefficientBounds& bounds = {});

/// The solution of the scaled equations m v = rhs (v = sp w) with the held entries known
/// (held_solution; none held: m's LU) and every bounded coefficient within its bounds: those
/// whose value in their own column leaves a bound are held at the bound they cross and the
/// equations solved again, until none leaves (decision 0058). `at_bounds` receives them.
Eigen::MatrixXd constrained_solution(const Eigen::MatrixXd& m, const Eigen::VectorXd& sp,
                                     const Eigen::MatrixXd& rhs, const Layout& layout,
                                     const HeldCoefficients& held, const CoefficientBounds& bounds,
                                     HeldCoefficients& at_bounds);

/// The solution of the scaled equations m v = rhs (v = sp w, a column per submodel of (29))
/// with the held entries of w known: the equations of the free entries only,
/// m_ff v_f = rhs_f - m_fh v_h (decision 0057). A held coefficient of submodel i is its value
/// in column i and 0 in the others, as at a stationary point of (29) the solution is
/// block-diagonal (Lemma 4.4).
Eigen::MatrixXd held_solution(const Eigen::MatrixXd& m, const Eigen::VectorXd& sp,
                              const Eigen::MatrixXd& rhs, const Layout& layout,
                              const HeldCoefficients& held);

/// The bounded coefficients of beta that sit at a bound, with their values (decision 0058).
HeldCoefficients coefficients_at_bounds(const Eigen::VectorXd& beta,
                                        const CoefficientBounds& bounds);
/// The verdict's sentences on the constraints that acted (decision 0058): the reflections of
/// unstable iterates, and the coefficients at a bound by their `names`.
std::vector<std::string> active_constraint_notes(int reflections, const HeldCoefficients& at_bounds,
                                                 const std::vector<std::string>& names);

/// The covariance of the free entries given the held ones, P_ff - P_fh P_hh^-1 P_hf (for the
/// white-noise instrument covariance this is (I_ff)^-1, the covariance of the estimator that
/// knows them); the held rows and columns are zero.
Eigen::MatrixXd covariance_given_held(const Eigen::MatrixXd& p, const HeldCoefficients& held);

}  // namespace ctid::internal::srivc_engine
