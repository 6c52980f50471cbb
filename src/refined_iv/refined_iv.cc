// The refined IV iteration (29) shared by every estimator of González et al., as a driver
// (run_refined_iv_from_start) over named phases: the data and structure checks, the start, the
// iteration with step control, the estimate, its statistics and the verdict. The streamed
// passes over the data that each phase calls are in refined_iv_passes.cc. Columns are scaled to
// unit norm before solving.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include "core/internal/polynomial_if_finite.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/core/parallel.h"
#include "ctid/estimation/arma.h"
#include "ctid/estimation/validation.h"
#include "ctid/estimation/verdict.h"
#include "ctid/filtering/filter_bank.h"
#include "ctid/refined_iv/covariance.h"
#include "ctid/refined_iv/initialization.h"
#include "ctid/simulation/discretization.h"
#include "refined_iv/internal/covariance_sums.h"
#include "refined_iv/internal/refined_iv_engine.h"
#include "refined_iv/internal/refined_iv_passes.h"

namespace ctid {

namespace internal {

void note_excitation(DataChecks& checks, const std::string& signal) {
  checks.persistently_exciting = checks.excitation_order >= checks.excitation_order_required;
  if (!checks.persistently_exciting) {
    checks.warnings.push_back("the " + signal + " is persistently exciting of order " +
                              std::to_string(checks.excitation_order) + ", below the " +
                              std::to_string(checks.excitation_order_required) +
                              " of Assumption 1; consistency is not guaranteed");
  }
}

void note_sampling_rate(DataChecks& checks, const AdditiveModel& model, double step,
                        const std::string& limit) {
  checks.nyquist_frequency = M_PI / step;
  checks.largest_pole_frequency = largest_pole_frequency(model);
  checks.sampling_rate_ok = checks.largest_pole_frequency < checks.nyquist_frequency;
  if (!checks.sampling_rate_ok) {
    checks.warnings.push_back(
        "a pole's imaginary part " + format_significant(checks.largest_pole_frequency, 3) +
        " rad/s is not below " + limit + " " + format_significant(checks.nyquist_frequency, 3) +
        " rad/s (Assumption 4): sample faster or lower the model order");
  }
}

std::optional<Polynomial> reflect_unstable_roots_if_finite(const Polynomial& a, bool& reflected,
                                                           std::string* failure) {
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
  const std::optional<Polynomial> moved = polynomial_from_roots(roots, 1.0, failure);
  if (!moved) return std::nullopt;
  return anti_monic_if_finite(*moved, failure);
}

Polynomial reflect_unstable_roots(const Polynomial& a, bool& reflected) {
  std::string failure;
  std::optional<Polynomial> r = reflect_unstable_roots_if_finite(a, reflected, &failure);
  if (!r) throw InvalidArgument(failure);
  return std::move(*r);
}

bool controller_stabilises(const std::vector<SubmodelOrder>& orders, const Eigen::VectorXd& beta,
                           const DiscreteTransferFunction& controller, double h, int input_delay) {
  const std::optional<std::vector<StateSpace>> plant =
      srivc_engine::sampled_loop_plant(srivc_engine::Layout(orders), beta, h);
  if (!plant) return false;  // a degenerate model (e.g. A lost its leading coefficient) has no loop
  // An empty reference: only the loop's poles are checked, nothing is filtered.
  return srivc_engine::sensitivity_filtered_reference(*plant, controller, Eigen::VectorXd(),
                                                      input_delay)
      .has_value();
}

namespace srivc_engine {
namespace {

// Whole samples by which record r's input is delayed: the model's delay plus the record's own
// (an acquisition that lags its input).
int record_delay(const RefinedIvOptions& options, size_t r) {
  return options.input_delay_samples +
         (options.record_delay_samples.empty() ? 0 : options.record_delay_samples[r]);
}

int total_samples(const std::vector<const SampledData*>& records) {
  int n_samples = 0;
  for (const SampledData* record : records) n_samples += record->size();
  return n_samples;
}

// The records share their sample time, input hold and signals; the start (and the data
// checks) use the longest, whose index is returned.
size_t check_records(const std::vector<const SampledData*>& records, const std::string& name) {
  require(!records.empty(), name, ": no data record was given");
  size_t longest_index = 0;
  for (size_t r = 1; r < records.size(); ++r) {
    if (records[r]->size() > records[longest_index]->size()) longest_index = r;
  }
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
  return longest_index;
}

// The structure: every submodel proper with at least one pole, at most one biproper and at
// most one with integrators.
void check_orders(const Layout& layout, const std::string& name) {
  require(layout.size() >= 1, name, ": the model structure has no submodels");
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

// Enough samples for the unknowns once the delays are taken off, and in closed loop a
// reference and a controller at the data's sample time.
void check_samples(const RefinedIvProblem& problem, const RefinedIvOptions& options,
                   const Layout& layout, const SampledData& data, const std::string& name) {
  const std::vector<const SampledData*>& records = problem.records;
  const int delay = options.input_delay_samples;
  require(
      options.record_delay_samples.empty() || options.record_delay_samples.size() == records.size(),
      name, ": record_delay_samples has ", options.record_delay_samples.size(), " entries for ",
      records.size(), " records; give one per record or none");
  const int n_samples = total_samples(records);
  const int unknowns = layout.augmented;  // with the free-response coefficients
  int lost = 0;
  for (size_t r = 0; r < records.size(); ++r) lost += record_delay(options, r);
  require(n_samples - lost >= std::max(3 * unknowns, unknowns + 20), name, ": ", n_samples,
          " samples (input delay ", delay, ") are too few for ", unknowns,
          " parameters and initial conditions; at least ",
          std::max(3 * unknowns, unknowns + 20) + lost, " are needed");
  if (options.noise_model) {
    const NoiseModelOrders& o = *options.noise_model;
    const int orders = o.automatic ? 0 : o.ar + o.ma;
    const int needed = 10 * orders + 20;
    require(n_samples >= needed, name, ": ", n_samples, " samples cannot hold an ARMA(", o.ar, ", ",
            o.ma, ") noise model; it needs at least ", needed, " (lower noise_model's orders)");
  }
  const double h = data.sample_time();
  if (problem.controller != nullptr) {
    require(data.has_reference(), name, ": closed-loop estimation needs a measured reference r");
    require(std::abs(problem.controller->sample_time() - h) <= 1e-9 * h, name,
            ": the controller's sample time ", problem.controller->sample_time(),
            " differs from the data's ", h);
  }
}

// Assumption 1: persistency of excitation (of the best-excited record when there are several).
DataChecks check_excitation(const RefinedIvProblem& problem, const Layout& layout,
                            const std::string& name) {
  const bool closed_loop = problem.controller != nullptr;
  const int p = layout.parameters;
  DataChecks checks;
  const int nc = closed_loop ? problem.controller->denominator().degree() : 0;
  checks.excitation_order_required = 2 * layout.poles + nc;
  for (const SampledData* record : problem.records) {
    const Eigen::VectorXd& excitation = closed_loop ? record->reference() : record->input();
    checks.excitation_order = std::max(
        checks.excitation_order,
        persistent_excitation_order(excitation, std::max(checks.excitation_order_required, p)));
  }
  require(checks.excitation_order >= p, name, ": the ", closed_loop ? "reference" : "input",
          " is persistently exciting of order ", checks.excitation_order, " only; the ", p,
          " parameters need at least order ", p, " (e.g. a constant or a single sine cannot)");
  note_excitation(checks, closed_loop ? "reference" : "input");
  return checks;
}

// The starting point: options.initial_model laid out for the structure (grouped into its
// submodels when it is not of that structure), or the start screened from the longest record;
// none, with the reason in `failure`, when no start can be formed.
std::optional<Eigen::VectorXd> starting_point(const RefinedIvProblem& problem,
                                              const RefinedIvOptions& options, const Layout& layout,
                                              size_t longest_index, ScreenedStart* shared,
                                              std::string* failure) {
  const SampledData& data = *problem.records[longest_index];
  if (options.initial_model) {
    const AdditiveModel& given = *options.initial_model;
    bool fits = given.size() == layout.size();
    for (int i = 0; fits && i < given.size(); ++i) {
      const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
      fits = given[i].n() == o.n && given[i].integrators == o.integrators && given[i].m() <= o.m;
    }
    if (fits) return parameters_for_orders(given, layout.orders);
    if (layout.size() == 1) {
      return unfactored_parameters(given.to_transfer_function().with_input_delay(0.0),
                                   layout.orders[0]);
    }
    const std::optional<AdditiveModel> grouped =
        grouped_submodels(given.to_transfer_function().with_input_delay(0.0), layout.orders, data,
                          record_delay(options, longest_index), failure);
    if (!grouped) return std::nullopt;
    return parameters_for_orders(*grouped, layout.orders);
  }
  ScreenedStart own_start;
  InitializationOptions init;
  init.input_delay_samples = record_delay(options, longest_index);
  init.method = options.start;
  init.screening_samples = options.start_screening_samples;
  // Closed loop: only starts the controller stabilises (decision 0011); an open-loop start
  // it does not stabilise would stop the iteration before its first step.
  if (problem.controller != nullptr) init.controller = *problem.controller;
  ScreenedStart& start = shared != nullptr ? *shared : own_start;
  if (!start.g) {
    const SubmodelOrder total =
        layout.size() == 1 ? layout.orders[0] : unfactored_order(layout.orders);
    start.g = initial_transfer_function_if_formed(data, total, init, failure);
    if (!start.g) return std::nullopt;
  }
  if (layout.size() == 1) return unfactored_parameters(*start.g, layout.orders[0]);
  const std::optional<AdditiveModel> grouped =
      additive_model_from_start_if_formed(*start.g, data, layout.orders, init, failure);
  if (!grouped) return std::nullopt;
  return parameters_for_orders(*grouped, layout.orders);
}

// The threads of one estimate's passes (RefinedIvOptions::threads): at most one per submodel,
// and when automatic, the idle cores for a long record outside a parallel loop.
int pass_threads(int requested, int samples, int submodels) {
  constexpr int kLongRecord = 100000;
  if (submodels < 2) return 1;
  if (requested > 0) return std::min(requested, submodels);
  if (inside_parallel_loop() || samples < kLongRecord) return 1;
  return std::min(idle_thread_count(), submodels);
}

// What the phases of one estimate share: the problem, the layout, the stacked signals, the
// current iterate and its free-response coefficients, and the result being filled in.
struct Run {
  const RefinedIvProblem& problem;
  const RefinedIvOptions& options;
  const std::string& name;
  const std::vector<const SampledData*>& records;
  Layout layout;
  DataChecks checks;
  int delay;
  int n_samples;
  int p;
  int unknowns;  // with the free-response coefficients
  bool closed_loop;
  double h;
  double tau;
  EstimationResult result;
  Eigen::VectorXd beta;
  std::vector<RecordSignals> signals;
  Eigen::VectorXd y;    // the records' outputs stacked
  bool source = false;  // S_uo r of every record formed (closed loop)
  double start_closed_loop_sse = std::numeric_limits<double>::quiet_NaN();
  double closed_loop_sse_at_end = std::numeric_limits<double>::quiet_NaN();
  double start_sse = std::numeric_limits<double>::quiet_NaN();
  Workspace workspace;
  // Free-response coefficients (initial states of each submodel's 1/(p^l A_i) realisation at
  // the current iterate), taken from the last solution of (29); empty with `zero`.
  Eigen::VectorXd initial_states;
  Eigen::VectorXd states_at;  // the iterate whose realisations they refer to
  bool loop_unstable = false;
  bool degenerate = false;  // stopped before a degenerate iterate (decision 0050)
  // RIVC (options.noise_model): the ARMA model of the output error at the current iterate,
  // whose D/C the passes apply (workspace.prefilter).
  std::optional<ArmaModel> noise;

  Run(const RefinedIvProblem& pr, const RefinedIvOptions& op, const std::string& n, Layout l,
      DataChecks c, const Eigen::VectorXd& start, double sample_time)
      : problem(pr),
        options(op),
        name(n),
        records(pr.records),
        layout(std::move(l)),
        checks(std::move(c)),
        delay(op.input_delay_samples),
        n_samples(total_samples(pr.records)),
        p(layout.parameters),
        unknowns(layout.augmented),
        closed_loop(pr.controller != nullptr),
        h(sample_time),
        tau((delay + layout.delay_fraction) * h),
        result{AdditiveModel::from_parameters(layout.orders, start, tau),
               TransferFunction(Polynomial{1.0}, Polynomial{1.0})},
        beta(start),
        signals(pr.records.size()),
        y(n_samples),
        workspace(layout, pass_threads(op.threads, n_samples, layout.size())) {}

  int delay_of(size_t r) const { return record_delay(options, r); }
  // The held coefficients and those at a bound: what the covariance takes as known.
  HeldCoefficients known() const {
    HeldCoefficients all = problem.held_coefficients;
    const HeldCoefficients at = coefficients_at_bounds(beta, problem.bounded_coefficients);
    all.insert(all.end(), at.begin(), at.end());
    return all;
  }
};

// Right-half-plane roots of every A_i in b reflected, counted in the result; false, with b
// partly changed, when a mirrored A is not finite (a degenerate iterate, decision 0050).
bool reflect_all(Run& run, Eigen::VectorXd& b) {
  const Layout& layout = run.layout;
  for (int i = 0; i < layout.size(); ++i) {
    const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
    if (o.n < 1) continue;
    bool reflected = false;
    const std::optional<Polynomial> a =
        reflect_unstable_roots_if_finite(denominator_of(layout, b, i), reflected);
    if (!a) return false;
    if (reflected) {
      ++run.result.unstable_reflections;
      for (int k = 1; k <= o.n; ++k) b(layout.offset[static_cast<size_t>(i)] + k - 1) = (*a)[k];
    }
  }
  return true;
}

// The stop at a degenerate iterate: the run keeps its last iterate (decision 0050).
void stop_degenerate(Run& run, const std::string& where) {
  run.degenerate = true;
  run.result.termination = Termination::non_finite;
  run.result.message = run.name + ": " + where +
                       " is degenerate (A lost its leading coefficient or its filters have no "
                       "finite realisation); the last finite iterate is returned";
}

// Each record's delayed input and its output, and the outputs stacked.
void stack_signals(Run& run) {
  Eigen::Index at = 0;
  for (size_t r = 0; r < run.records.size(); ++r) {
    run.signals[r].u = delay_samples(run.records[r]->input(), run.delay_of(r));
    run.signals[r].y = &run.records[r]->output();
    run.signals[r].offset = at;
    run.y.segment(at, run.records[r]->size()) = run.records[r]->output();
    at += run.records[r]->size();
  }
}

// The first sample of each record after the first in the stacked residual.
std::vector<Eigen::Index> record_starts(const Run& run) {
  std::vector<Eigen::Index> starts;
  for (size_t r = 1; r < run.signals.size(); ++r) starts.push_back(run.signals[r].offset);
  return starts;
}

// RIVC: the ARMA model of the output error y - G u at the current iterate (orders chosen by
// the criterion at the first iterate when automatic, then kept), and its D/C as the passes'
// prefilter. An output error below rounding (noise-free data) has no noise to model: D = C = 1.
void update_noise_model(Run& run) {
  const NoiseModelOrders& orders = *run.options.noise_model;
  Eigen::VectorXd residual;
  evaluate(run.layout, run.beta, run.initial_states, run.signals, run.source, run.h,
           run.options.output_interpolation, run.workspace, nullptr, &residual, nullptr);
  if (!residual.allFinite()) return;  // the pass that follows reports the iterate
  const std::vector<Eigen::Index> starts = record_starts(run);
  // The orders in use: those chosen or given, none yet when they are still to be chosen.
  const int ar = run.noise ? run.noise->ar_order() : orders.automatic ? 0 : orders.ar;
  const int ma = run.noise ? run.noise->ma_order() : orders.automatic ? 0 : orders.ma;
  if (!(residual.norm() > 1e-12 * run.y.norm())) {
    run.noise = fit_arma(Eigen::VectorXd::Zero(residual.size()), ar, ma, starts);
  } else if (orders.automatic && !run.noise) {
    run.noise = fit_arma_by_criterion(residual, orders.max_order, starts);
  } else {
    run.noise = fit_arma(residual, ar, ma, starts);
  }
  run.workspace.prefilter.emplace(*run.noise, run.layout);
}

// S_uo r of every record (closed loop) at b; false when the loop is unstable. The engine holds
// only iterates that are realisable, so the loop's plant exists at every b it is given.
bool update_source(Run& run, const Eigen::VectorXd& b) {
  const std::optional<std::vector<StateSpace>> plant = sampled_loop_plant(run.layout, b, run.h);
  if (!plant) return false;
  std::vector<Eigen::VectorXd> updated;  // all records or none: a failure keeps the last
  for (size_t r = 0; r < run.records.size(); ++r) {
    std::optional<Eigen::VectorXd> s = sensitivity_filtered_reference(
        *plant, *run.problem.controller, run.records[r]->reference(), run.delay_of(r));
    if (!s) return false;
    updated.push_back(std::move(*s));
  }
  for (size_t r = 0; r < run.records.size(); ++r) {
    run.signals[r].source = delay_samples(updated[r], run.delay_of(r));
    run.signals[r].undelayed_source = std::move(updated[r]);
  }
  run.source = true;
  return true;
}

// Closed loop: the sum over the records of (y - G S_uo(G) r)^2 at b, from the S_uo r that
// update_source last formed for b (the model's output from the reference alone).
double closed_loop_sse(const Run& run, const Eigen::VectorXd& b) {
  const AdditiveModel model = AdditiveModel::from_parameters(run.layout.orders, b, run.tau);
  double sum = 0.0;
  for (size_t r = 0; r < run.records.size(); ++r) {
    const double own = (run.delay_of(r) - run.delay) * run.h;
    sum += (run.records[r]->output() - model_output(model.with_input_delay(run.tau + own),
                                                    run.signals[r].undelayed_source, run.h,
                                                    Hold::zero_order_hold))
               .squaredNorm();
  }
  return sum;
}

// Closed loop: S_uo r at the start, or the reason the iteration cannot begin. Returns whether
// the iteration is stopped before its first step.
bool start_loop(Run& run) {
  if (run.closed_loop && update_source(run, run.beta)) {
    run.start_closed_loop_sse = closed_loop_sse(run, run.beta);
  } else if (run.closed_loop) {
    const RefinedIvOptions& options = run.options;
    const std::string& name = run.name;
    run.result.termination = Termination::closed_loop_unstable;
    run.result.message =
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
    return true;
  }
  return false;
}

// Step control: a full step of (29) at which the equations are singular or non-finite is
// halved toward the last accepted iterate instead of ending the iteration. Accepted steps
// are the plain iteration, so every fixed point of (29) is still one of this iteration.
// The iterate with the lowest output error seen (the start included) is returned instead of
// the last one when the iteration did not converge and the last one fits worse.
struct StepControl {
  Eigen::VectorXd accepted;
  int halvings = 0;  // of the current step
  double best_sse = std::numeric_limits<double>::infinity();
  Eigen::VectorXd best_beta;
  int best_iteration = 0;
};

// The equations of (29) at the iterate with unit-norm columns, and their reciprocal condition.
struct ScaledEquations {
  bool finite = false;
  Eigen::VectorXd sz;
  Eigen::VectorXd sp;
  Eigen::MatrixXd m;
  double rcond = 0.0;
};

ScaledEquations scaled_equations(const Moments& sums, EstimationResult& result) {
  ScaledEquations e;
  e.finite = sums.all_finite();
  std::optional<Eigen::JacobiSVD<Eigen::MatrixXd>> svd;
  if (e.finite) {
    e.sz = norms_from_squares(sums.zz);
    e.sp = norms_from_squares(sums.pp);
    e.m = e.sz.cwiseInverse().asDiagonal() * sums.zp * e.sp.cwiseInverse().asDiagonal();
    svd.emplace(e.m);
    const Eigen::VectorXd& sv = svd->singularValues();
    e.rcond = sv(sv.size() - 1) / sv(0);
    result.reciprocal_condition = e.rcond;
  }
  return e;
}

enum class StepOutcome { halved, stopped, taken };

// The step from the solution of (29): each submodel's block of its own column, the
// off-block-diagonal remainder (Lemma 4.4), and the stopping rule.
StepOutcome take_step(Run& run, const ScaledEquations& e, const Eigen::MatrixXd& rhs,
                      int iteration) {
  const Layout& layout = run.layout;
  EstimationResult& result = run.result;
  HeldCoefficients known = run.problem.held_coefficients;
  HeldCoefficients at_bounds;
  const Eigen::MatrixXd solution = constrained_solution(
      e.m, e.sp, rhs, layout, known, run.problem.bounded_coefficients, at_bounds);
  known.insert(known.end(), at_bounds.begin(), at_bounds.end());
  Eigen::VectorXd next(run.p);
  Eigen::MatrixXd off = solution.topRows(run.p);
  for (int i = 0; i < layout.size(); ++i) {
    const int o = layout.offset[static_cast<size_t>(i)];
    next.segment(o, layout.count(i)) = solution.block(o, i, layout.count(i), 1);
    off.block(o, i, layout.count(i), 1).setZero();
  }
  if (!next.allFinite()) {
    result.termination = Termination::non_finite;
    result.message = run.name + ": iteration " + std::to_string(iteration) +
                     " produced a non-finite parameter; the last finite iterate is returned";
    return StepOutcome::stopped;
  }
  const bool reflected = reflect_all(run, next);
  for (const auto& [j, value] : known) next(j) = value;  // a reflection keeps them
  if (!reflected || !realisable(run.layout, run.closed_loop, run.h, next)) {
    stop_degenerate(run, "the model at iteration " + std::to_string(iteration));
    return StepOutcome::stopped;
  }
  const double change = relative_change(layout, run.beta, next);
  result.off_diagonal_norm = off.norm() / std::max(next.norm(), 1e-300);
  result.relative_change = change;
  result.iterations = iteration;
  run.initial_states = free_response_coefficients(layout, solution);
  run.states_at = run.beta;
  run.beta = next;
  if (run.options.record_history) {
    result.history.push_back({iteration, run.beta, change, result.off_diagonal_norm});
  }
  if (change < run.options.tolerance) {
    result.termination = Termination::converged;
    result.message = run.name + ": converged after " + std::to_string(iteration) +
                     " iterations (relative parameter change " + format_significant(change, 3) +
                     " < tolerance " + format_significant(run.options.tolerance, 3) + ")";
    return StepOutcome::stopped;
  }
  return StepOutcome::taken;
}

// One pass of (29) at the current iterate: its sums and output error, then a halved step, a
// stop (non-finite or singular equations, convergence) or the next iterate.
StepOutcome iteration_step(Run& run, StepControl& control, int iteration) {
  EstimationResult& result = run.result;
  const RefinedIvOptions& options = run.options;
  bool source_ok = true;
  if (run.closed_loop && iteration > 1) source_ok = update_source(run, run.beta);
  if (options.noise_model) update_noise_model(run);
  Moments sums;
  double sse = 0.0;
  evaluate(run.layout, run.beta, run.initial_states, run.signals, run.source, run.h,
           options.output_interpolation, run.workspace, &sums, nullptr, nullptr, &sse);
  if (std::isnan(run.start_sse)) run.start_sse = sse;
  if (std::isfinite(sse) && !(sse >= control.best_sse)) {
    control.best_sse = sse;
    control.best_beta = run.beta;
    control.best_iteration = iteration - 1;
  }
  const ScaledEquations e = scaled_equations(sums, result);
  if (options.step_control && control.accepted.size() > 0 &&
      control.halvings < options.max_step_halvings && (!e.finite || !(e.rcond > 1e-14))) {
    const Eigen::VectorXd halved = 0.5 * (control.accepted + run.beta);
    if (!realisable(run.layout, run.closed_loop, run.h, halved)) {
      stop_degenerate(run, "the halved step at iteration " + std::to_string(iteration));
      return StepOutcome::stopped;
    }
    run.beta = halved;
    ++control.halvings;
    ++result.step_halvings;
    return StepOutcome::halved;
  }
  if (!source_ok) ++result.sensitivity_fallbacks;
  if (!e.finite) {
    result.termination = Termination::non_finite;
    result.message = run.name + ": the filtered signals became non-finite at iteration " +
                     std::to_string(iteration) + "; the last finite iterate is returned";
    return StepOutcome::stopped;
  }
  const Eigen::MatrixXd rhs = e.sz.cwiseInverse().asDiagonal() * sums.zy;
  if (!(e.rcond > 1e-14)) {
    result.termination = Termination::singular_equations;
    result.message = run.name +
                     ": the instrument-regressor matrix of eq. (29) is numerically "
                     "singular at iteration " +
                     std::to_string(iteration) + " (reciprocal condition " +
                     format_significant(e.rcond, 3) +
                     "): the data do not excite the model enough or the orders are too high";
    return StepOutcome::stopped;
  }
  control.accepted = run.beta;
  control.halvings = 0;
  return take_step(run, e, rhs, iteration);
}

// Not converged: the last iterate, or the best one seen when the last fits worse.
void keep_best_iterate(Run& run, const StepControl& control) {
  EstimationResult& result = run.result;
  if (result.termination == Termination::iteration_limit) {
    result.message = run.name + ": stopped at the iteration limit (" +
                     std::to_string(run.options.max_iterations) +
                     ") with relative parameter change " +
                     format_significant(result.relative_change, 3) + ", above the tolerance " +
                     format_significant(run.options.tolerance, 3);
  }
  double sse = 0.0;
  if (!result.converged() && control.best_beta.size() > 0) {
    evaluate(run.layout, run.beta, run.initial_states, run.signals, false, run.h,
             run.options.output_interpolation, run.workspace, nullptr, nullptr, nullptr, &sse);
    if (!(sse <= control.best_sse)) {
      run.beta = control.best_beta;
      const int best_iteration = control.best_iteration;
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
}

// The iteration (29) from the start, with step control, up to convergence or a stop.
void iterate(Run& run, bool stopped) {
  StepControl control;
  int iteration = 1;
  while (!stopped && iteration <= run.options.max_iterations) {
    const StepOutcome outcome = iteration_step(run, control, iteration);
    if (outcome == StepOutcome::halved) continue;
    if (outcome == StepOutcome::stopped) break;
    ++iteration;
  }
  keep_best_iterate(run, control);
}

// The estimate in every form the result holds, and in closed loop whether the controller
// holds it and its closed-loop output error.
void set_estimate(Run& run) {
  EstimationResult& result = run.result;
  result.parameters = run.beta;
  result.input_delay_samples = run.delay;
  result.input_delay_fraction = run.layout.delay_fraction;
  result.model = AdditiveModel::from_parameters(run.layout.orders, run.beta, run.tau);
  result.transfer_function = result.model.to_transfer_function();
  if (run.problem.unfactored) {
    // None when the poles do not split (e.g. a repeated pole).
    result.additive_view = AdditiveModel::split_transfer_function(result.transfer_function);
  } else {
    result.additive_view = result.model;
  }
  // Stopped before the first step because the controller does not stabilise the start: the
  // returned model is that start, which cannot describe the recorded loop.
  run.loop_unstable = run.closed_loop && result.termination == Termination::closed_loop_unstable &&
                      result.iterations == 0;
  if (run.closed_loop && result.termination != Termination::closed_loop_unstable) {
    if (update_source(run, run.beta)) {
      run.closed_loop_sse_at_end = closed_loop_sse(run, run.beta);
    } else {
      ++result.sensitivity_fallbacks;
      run.loop_unstable = true;
    }
  }
}

// The loop's free-response coefficients come from the solve at the previous iterate; one more
// solve of (29) at the returned beta gives them in its own realisations.
void refresh_free_responses(Run& run) {
  if (!(run.layout.free_responses() && run.result.iterations > 0)) return;
  Moments sums;
  evaluate(run.layout, run.beta, run.initial_states, run.signals, run.source, run.h,
           run.options.output_interpolation, run.workspace, &sums, nullptr, nullptr);
  if (std::optional<Eigen::MatrixXd> solution = solve_scaled(
          sums, run.layout, run.problem.held_coefficients, run.problem.bounded_coefficients)) {
    run.initial_states = free_response_coefficients(run.layout, *solution);
    run.states_at = run.beta;
  }
}

// The delay's column of the instrument: the sensitivity of the noise-free model output to
// tau, as the other columns are theirs to the parameters (a central difference within the
// sample interval, where the held input makes the output smooth in tau).
Eigen::VectorXd delay_column(const Run& run) {
  const Hold hold = run.closed_loop ? Hold::zero_order_hold : run.layout.input_hold;
  const double h = run.h;
  const double step = 1e-4;
  const double f = run.layout.delay_fraction;
  const double up = f + step < 1.0 ? step : 0.0;
  const double down = f - step >= 0.0 ? step : 0.0;
  auto output_at = [&](double shift) {
    Eigen::VectorXd out(run.n_samples);
    for (size_t r = 0; r < run.records.size(); ++r) {
      const Eigen::VectorXd& driven =
          run.closed_loop ? run.signals[r].undelayed_source : run.records[r]->input();
      const double own = (run.delay_of(r) - run.delay) * h;
      out.segment(run.signals[r].offset, run.records[r]->size()) = model_output(
          run.result.model.with_input_delay(run.tau + own + shift * h), driven, h, hold);
    }
    return out;
  };
  return (output_at(up) - output_at(-down)) / ((up + down) * h);
}

// The start's fit and, in closed loop, the closed-loop fits from r, from the same definition
// as the estimate's: 100 (1 - ||e|| / ||y - mean(y)||).
void set_start_fits(Run& run) {
  EstimationResult& result = run.result;
  const Eigen::VectorXd& y = run.y;
  const double spread = (y.array() - y.mean()).matrix().norm();
  result.start_fit_percent = std::isnan(run.start_sse) ? result.fit_percent
                             : spread > 0.0 ? 100.0 * (1.0 - std::sqrt(run.start_sse) / spread)
                                            : std::numeric_limits<double>::quiet_NaN();
  if (spread > 0.0) {
    result.closed_loop_fit_percent = 100.0 * (1.0 - std::sqrt(run.closed_loop_sse_at_end) / spread);
    result.start_closed_loop_fit_percent =
        100.0 * (1.0 - std::sqrt(run.start_closed_loop_sse) / spread);
  }
}

// The residual pass at the estimate (with the instrument's sums when the covariance is asked)
// and the statistics of the fit; then the covariance of beta (and of the delay when it is
// estimated) and the modal estimates.
void set_statistics(Run& run) {
  const RefinedIvOptions& options = run.options;
  const Layout& layout = run.layout;
  EstimationResult& result = run.result;
  // RIVC: the noise model at the estimate; the instrument (and the delay's column) are
  // prefiltered by its D/C, and the covariance is the white one of the innovations.
  const bool rivc = options.noise_model.has_value();
  if (rivc && run.beta.allFinite()) update_noise_model(run);
  const NoiseAssumption noise = rivc ? NoiseAssumption::white : options.noise;
  Eigen::VectorXd delay_col;
  const bool delay_column_used =
      options.compute_covariance && options.delay_estimated && run.beta.allFinite();
  if (delay_column_used) delay_col = delay_column(run);
  if (delay_column_used && run.noise) {
    delay_col = arma_innovations(*run.noise, delay_col, record_starts(run));
  }
  InstrumentPass instrument;
  instrument.extra = delay_column_used ? &delay_col : nullptr;
  instrument.keep_checkpoints =
      noise != NoiseAssumption::white && !run.problem.stored_instrument_covariance;
  Eigen::MatrixXd stored_psi;
  if (run.problem.stored_instrument_covariance) instrument.stored = &stored_psi;
  Eigen::VectorXd residual;
  evaluate(layout, run.beta, run.initial_states, run.signals, run.source, run.h,
           options.output_interpolation, run.workspace, nullptr, &residual,
           options.compute_covariance ? &instrument : nullptr);
  const double sse = residual.squaredNorm();
  result.mean_squared_error = sse / run.n_samples;
  result.noise_variance = sse / std::max(run.n_samples - run.unknowns, 1);
  result.fit_percent = fit_percent(run.y, run.y - residual);
  if (layout.free_responses())
    result.initial_conditions =
        free_response_derivatives(layout, run.states_at, run.initial_states);
  set_start_fits(run);
  if (run.noise) {
    result.noise_model = *run.noise;
    arma_spectrum(*result.noise_model, run.h);
  }
  if (!(options.compute_covariance && instrument.gram.allFinite() && residual.allFinite())) return;
  const Eigen::VectorXd noise_residual =
      run.noise ? arma_innovations(*run.noise, residual, record_starts(run)) : residual;
  // With free responses the joint covariance of beta and their coefficients; its beta
  // block is the covariance of beta with the nuisance coefficients estimated alongside.
  const int joint_unknowns = run.unknowns + (delay_column_used ? 1 : 0);
  const Eigen::MatrixXd joint =
      run.problem.stored_instrument_covariance
          ? instrumental_variable_covariance(stored_psi, noise_residual, joint_unknowns, noise,
                                             options.noise_model_max_order)
          : covariance_from_gram(instrument.gram, noise_residual, joint_unknowns, noise,
                                 options.noise_model_max_order,
                                 [&](const AutoregressiveModel& ar, const Eigen::VectorXd& scales) {
                                   return adjoint_instrument_sum(
                                       layout, run.beta, run.initial_states, run.signals,
                                       run.source, run.h, options.output_interpolation,
                                       run.workspace, instrument, ar, scales);
                                 });
  const HeldCoefficients known = run.known();
  result.covariance = known.empty()
                          ? Eigen::MatrixXd(joint.topLeftCorner(run.p, run.p))
                          : covariance_given_held(joint, known).topLeftCorner(run.p, run.p);
  if (delay_column_used) {
    result.delay_standard_error = std::sqrt(std::max(joint(run.unknowns, run.unknowns), 0.0));
  }
  result.standard_errors = result.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  result.modes = modal_estimates(result.model, result.covariance, run.problem.unfactored);
}

// Assumption 4 on the estimate, then the verdict.
void judge(Run& run) {
  DataChecks& checks = run.checks;
  EstimationResult& result = run.result;
  note_sampling_rate(checks, result.model, run.h, "the Nyquist frequency");
  result.checks = std::move(checks);
  result.verdict = refined_iv_verdict(result, run.closed_loop, run.loop_unstable);
  result.verdict.active_constraints =
      active_constraint_notes(result.unstable_reflections,
                              coefficients_at_bounds(run.beta, run.problem.bounded_coefficients),
                              result.model.parameter_names());
  if (run.degenerate) {
    result.verdict.fail(
        "the iteration stopped before a degenerate model (A lost its leading "
        "coefficient), so the estimate is an iterate that did not converge",
        {verdict_advice::better_start, verdict_advice::lower_order});
  }
}

}  // namespace
}  // namespace srivc_engine

namespace {

std::optional<EstimationResult> run_from_start(const RefinedIvProblem& problem,
                                               const RefinedIvOptions& options,
                                               ScreenedStart* shared, std::string* failure) {
  namespace se = srivc_engine;
  options.validate();
  const std::string name = problem.name;
  const size_t longest_index = se::check_records(problem.records, name);
  const SampledData& data = *problem.records[longest_index];
  se::Layout layout(problem.orders, options.initial_conditions == InitialConditions::estimate,
                    static_cast<int>(problem.records.size()));
  layout.input_hold = data.input_hold();
  layout.delay_fraction = options.input_delay_fraction;
  se::check_orders(layout, name);
  se::check_samples(problem, options, layout, data, name);
  DataChecks checks = se::check_excitation(problem, layout, name);
  const std::optional<Eigen::VectorXd> beta =
      se::starting_point(problem, options, layout, longest_index, shared, failure);
  if (!beta) return std::nullopt;
  require(beta->allFinite(), name, ": the initial model has a non-finite parameter");
  Eigen::VectorXd start = *beta;
  for (const auto& [j, value] : problem.held_coefficients) {
    require(j >= 0 && j < start.size(), name, ": held coefficient ", j, " is not in beta (",
            start.size(), " coefficients)");
    start(j) = value;
  }
  for (const auto& [j, lower, upper] : problem.bounded_coefficients) {
    require(j >= 0 && j < start.size() && lower <= upper, name, ": bounded coefficient ", j,
            " is not in beta (", start.size(), " coefficients) or its bounds [", lower, ", ", upper,
            "] are empty");
    start(j) = std::clamp(start(j), lower, upper);
  }

  se::Run run(problem, options, name, std::move(layout), std::move(checks), start,
              data.sample_time());
  if (!se::reflect_all(run, run.beta) ||
      !se::realisable(run.layout, run.closed_loop, run.h, run.beta)) {
    if (failure != nullptr) {
      *failure = name +
                 ": the start is degenerate (A lost its leading coefficient or its filters have "
                 "no finite realisation); give a start or another structure";
    }
    return std::nullopt;
  }
  se::stack_signals(run);
  run.initial_states = Eigen::VectorXd::Zero(run.layout.augmented - run.p);
  run.states_at = run.beta;
  run.result.termination = Termination::iteration_limit;
  const bool stopped = se::start_loop(run);
  se::iterate(run, stopped);
  se::set_estimate(run);
  se::refresh_free_responses(run);
  se::set_statistics(run);
  se::judge(run);
  return std::move(run.result);
}

// RIVC and CLRIVC (options.noise_model): the simplified estimator from the start the options
// give, then the iteration with the noise model from its estimate, as Young's RIVC is started
// from SRIVC; the message says how many iterations the first stage took.
std::optional<EstimationResult> run_with_noise_model(const RefinedIvProblem& problem,
                                                     const RefinedIvOptions& options,
                                                     ScreenedStart* shared, std::string* failure) {
  options.validate();
  RefinedIvOptions simplified = options;
  simplified.noise_model.reset();
  simplified.compute_covariance = false;
  simplified.record_history = false;
  simplified.delay_estimated = false;
  std::optional<EstimationResult> first = run_from_start(problem, simplified, shared, failure);
  if (!first) return std::nullopt;
  RefinedIvOptions refined = options;
  if (first->parameters.allFinite()) refined.initial_model = first->model;
  std::optional<EstimationResult> result = run_from_start(problem, refined, nullptr, failure);
  if (result) {
    result->message += "; started from the estimate without a noise model (" +
                       std::to_string(first->iterations) + " iterations, " +
                       std::string(enum_name(first->termination)) + ")";
  }
  return result;
}

}  // namespace

std::optional<EstimationResult> run_refined_iv_if_started(const RefinedIvProblem& problem,
                                                          const RefinedIvOptions& options,
                                                          ScreenedStart* shared,
                                                          std::string* failure) {
  if (options.noise_model) return run_with_noise_model(problem, options, shared, failure);
  return run_from_start(problem, options, shared, failure);
}

EstimationResult run_refined_iv_from_start(const RefinedIvProblem& problem,
                                           const RefinedIvOptions& options, ScreenedStart* shared) {
  std::string failure;
  std::optional<EstimationResult> result =
      run_refined_iv_if_started(problem, options, shared, &failure);
  if (!result) throw InvalidArgument(failure);
  return std::move(*result);
}

}  // namespace internal

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
  } else if (r.noise_model) {
    // RIVC starts from the estimate without a noise model, whose output error is about the
    // best the structure gives: a fit well below it is the noise model taking up what the
    // plant misses (decision 0056), not a bad start.
    check_fit(verdict, r.fit_percent, std::numeric_limits<double>::quiet_NaN());
    if (std::isfinite(r.start_fit_percent) &&
        r.fit_percent < r.start_fit_percent - verdict_thresholds::fit_tolerance_points) {
      verdict.fail("the output-error fit " + format_brief(r.fit_percent) + " % is worse than " +
                       format_brief(r.start_fit_percent) +
                       " % without a noise model: the plant structure is likely too simple, and "
                       "the noise model takes up what it misses",
                   {verdict_advice::other_structure});
    }
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
}  // namespace ctid
