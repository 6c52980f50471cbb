// Mode relocation for additive estimates: residual periodogram peaks in the excited band, a
// least-squares search for a start at each peak, the refined IV iteration from the best
// starts, a move kept only if the poles fit better.
#include "ctid/refined_iv/mode_relocation.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <optional>
#include <sstream>

#include <Eigen/Dense>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/filtering/filter_bank.h"
#include "ctid/frequency/peaks.h"
#include "ctid/frequency/periodogram.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "estimation/internal/scaled_least_squares.h"

namespace ctid {

void ModeRelocationOptions::check_relations(const std::string& path) const {
  require(!damping_ratios.empty(), path, ".damping_ratios is empty; it must hold at least one");
}

namespace {

// Anti-monic second-order denominator with natural frequency w and damping ratio z.
Polynomial mode_denominator(double w, double z) {
  return Polynomial{1.0, 2.0 * z / w, 1.0 / (w * w)};
}

// Columns p^k / (p^l A) u, k = 0..m: the numerator regressors of one submodel.
Eigen::MatrixXd numerator_columns(const Polynomial& a, int integrators, int m,
                                  const Eigen::VectorXd& u, double h, Hold hold) {
  const Polynomial d = Polynomial::monomial(integrators) * a;
  return filter_derivatives(d, u, h, hold).leftCols(m + 1);
}

// The residual's periodogram peaks as ModeRelocationOptions asks for them.
std::vector<PeriodogramPeak> residual_peaks(const Eigen::VectorXd& r,
                                            const std::vector<bool>& excited, double h,
                                            const ModeRelocationOptions& o) {
  PeriodogramPeakOptions peaks;
  peaks.zero_padding = o.zero_padding;
  peaks.floor_half_width = o.floor_half_width;
  peaks.min_peak_to_floor = o.min_peak_to_floor;
  peaks.min_separation = o.search_half_width;
  peaks.max_peaks = o.peaks_per_round;
  return periodogram_peaks(r, h, peaks, excited);
}

// A second-order mode (w, z) with numerator degree m that explains most of the residual r once
// the span of q (an orthonormal basis of the current regressors) is projected out.
struct ModeStart {
  double frequency = 0.0;
  double damping = 0.0;
  double reduction = -1.0;
};

ModeStart search_mode(const PeriodogramPeak& peak, const Eigen::MatrixXd& q,
                      const Eigen::VectorXd& r, const Eigen::VectorXd& u, double h, Hold hold,
                      int m, const ModeRelocationOptions& o) {
  const double line = 2.0 * M_PI / (static_cast<double>(u.size()) * h);
  const double lo = std::max(peak.frequency - o.search_half_width * line, 0.25 * line);
  const double hi = std::min(peak.frequency + o.search_half_width * line, M_PI / h * 0.999);
  ModeStart best;
  if (!(hi > lo)) return best;
  for (double z : o.damping_ratios) {
    for (int s = 0; s < o.search_points; ++s) {
      const double w = lo + (hi - lo) * s / (o.search_points - 1);
      Eigen::MatrixXd c = numerator_columns(mode_denominator(w, z), 0, m, u, h, hold);
      c -= q * (q.transpose() * c);
      for (Eigen::Index j = 0; j < c.cols(); ++j) {
        const double norm = c.col(j).norm();
        if (norm > 0.0) c.col(j) /= norm;
      }
      const Eigen::MatrixXd gram = c.transpose() * c;
      const Eigen::VectorXd cr = c.transpose() * r;
      const Eigen::LDLT<Eigen::MatrixXd> ldlt(gram);
      if (ldlt.info() != Eigen::Success) continue;
      const double reduction = cr.dot(ldlt.solve(cr));
      if (std::isfinite(reduction) && reduction > best.reduction) best = {w, z, reduction};
    }
  }
  return best;
}

bool movable(const SubmodelOrder& o) { return o.n == 2 && o.integrators == 0; }

// The numerator regressors of every submodel for given denominators, side by side, and the
// output-error least-squares fit of the numerators.
struct ProjectedFit {
  Eigen::MatrixXd x;
  std::vector<Eigen::Index> first_column;  // of each submodel
  internal::ScaledLeastSquares fit;
  double mean_squared_error = 0.0;
};

ProjectedFit projected_fit(const std::vector<Polynomial>& denominators,
                           const std::vector<SubmodelOrder>& orders, const Eigen::VectorXd& u,
                           const Eigen::VectorXd& y, double h, Hold hold) {
  ProjectedFit out;
  Eigen::Index total = 0;
  for (const SubmodelOrder& o : orders) {
    out.first_column.push_back(total);
    total += o.m + 1;
  }
  out.x.resize(y.size(), total);
  for (size_t i = 0; i < orders.size(); ++i) {
    out.x.middleCols(out.first_column[i], orders[i].m + 1) =
        numerator_columns(denominators[i], orders[i].integrators, orders[i].m, u, h, hold);
  }
  out.fit = internal::scaled_least_squares(out.x, y);
  out.mean_squared_error = out.fit.residual.squaredNorm() / static_cast<double>(y.size());
  return out;
}

std::vector<Polynomial> denominators_of(const AdditiveModel& model) {
  std::vector<Polynomial> out;
  for (int i = 0; i < model.size(); ++i) out.push_back(model[i].a);
  return out;
}

double projected_mse(const EstimationResult& r, const std::vector<SubmodelOrder>& orders,
                     const SampledData& data) {
  if (!r.parameters.allFinite()) return std::numeric_limits<double>::infinity();
  const Eigen::VectorXd u = delay_samples(data.input(), r.input_delay_samples);
  const double mse = projected_fit(denominators_of(r.model), orders, u, data.output(),
                                   data.sample_time(), data.input_hold())
                         .mean_squared_error;
  return std::isfinite(mse) ? mse : std::numeric_limits<double>::infinity();
}

struct Candidate {
  int submodel = 0;
  PeriodogramPeak peak;
  ModeStart start;
  double mean_squared_error = 0.0;
  Eigen::VectorXd beta;
};

// One round's candidates (at most trials_per_round, best first): for every residual peak at no
// mode the model already has, the searched mode put in place of each movable submodel, the
// numerators refitted by least squares and scored by their output error.
std::vector<Candidate> relocation_candidates(
    const SampledData& data, const std::vector<SubmodelOrder>& orders, const AdditiveModel& model,
    const Eigen::VectorXd& u, const ModeRelocationOptions& relocation,
    const std::vector<bool>& excited, const std::vector<int>& movable_submodels, int search_m) {
  const double h = data.sample_time();
  const Eigen::VectorXd& y = data.output();
  const std::vector<Polynomial> denominators = denominators_of(model);
  const ProjectedFit base = projected_fit(denominators, orders, u, y, h, data.input_hold());
  // Orthonormal basis of the current regressors (columns scaled first for the rank).
  const Eigen::VectorXd norms = internal::column_scales(base.x);
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(base.x * norms.cwiseInverse().asDiagonal());
  const Eigen::MatrixXd q =
      (qr.householderQ() * Eigen::MatrixXd::Identity(base.x.rows(), base.x.cols()))
          .leftCols(qr.rank());

  std::vector<Candidate> candidates;
  // A peak at a mode the model already has is that mode's misfit, for the iteration to fix;
  // a second submodel there would make the equations of (29) nearly singular.
  const double line = 2.0 * M_PI / (static_cast<double>(data.size()) * h);
  std::vector<double> present;
  for (int i = 0; i < model.size(); ++i) {
    if (const std::optional<ModalParameters> m = model.modal_parameters(i)) {
      present.push_back(m->natural_frequency);
    }
  }
  for (const PeriodogramPeak& peak : residual_peaks(base.fit.residual, excited, h, relocation)) {
    const bool taken = std::any_of(present.begin(), present.end(), [&](double w) {
      return std::abs(w - peak.frequency) < relocation.search_half_width * line;
    });
    if (taken) continue;
    const ModeStart start =
        search_mode(peak, q, base.fit.residual, u, h, data.input_hold(), search_m, relocation);
    if (start.reduction <= 0.0) continue;
    for (int moved : movable_submodels) {
      const auto mi = static_cast<size_t>(moved);
      std::vector<Polynomial> moved_denominators = denominators;
      moved_denominators[mi] = mode_denominator(start.frequency, start.damping);
      const ProjectedFit fit =
          projected_fit(moved_denominators, orders, u, y, h, data.input_hold());
      Candidate c;
      c.submodel = moved;
      c.peak = peak;
      c.start = start;
      c.mean_squared_error = fit.mean_squared_error;
      c.beta.resize(model.parameter_count());
      Eigen::Index pos = 0;
      Eigen::Index col = 0;
      for (size_t i = 0; i < orders.size(); ++i) {
        const Polynomial& a = moved_denominators[i];
        for (int k = 1; k <= orders[i].n; ++k) c.beta(pos++) = k <= a.degree() ? a[k] : 0.0;
        for (int k = 0; k <= orders[i].m; ++k) c.beta(pos++) = fit.fit.coefficients(col++);
      }
      if (c.beta.allFinite()) candidates.push_back(std::move(c));
    }
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) {
                     return a.mean_squared_error < b.mean_squared_error;
                   });
  if (candidates.size() > static_cast<size_t>(relocation.trials_per_round)) {
    candidates.resize(static_cast<size_t>(relocation.trials_per_round));
  }
  return candidates;
}

// The summary of a relocation run: relocations kept, trials, rounds, the output errors before
// and after, and where each kept move took its submodel.
std::string relocation_message(const ModeRelocationResult& out) {
  std::ostringstream message;
  message << out.relocations << " relocation(s) kept of " << out.trials.size() << " tried in "
          << out.rounds << " round(s); mean squared output error "
          << format_brief(out.initial_mean_squared_error) << " -> "
          << format_brief(out.estimate.mean_squared_error)
          << " (numerators re-fitted: " << format_brief(out.initial_projected_mean_squared_error)
          << " -> " << format_brief(out.projected_mean_squared_error) << ")";
  for (const RelocationTrial& t : out.trials) {
    if (t.accepted) {
      message << "; submodel " << t.submodel + 1 << " moved from "
              << format_brief(t.moved_from / (2.0 * M_PI)) << " Hz to "
              << format_brief(t.start_frequency / (2.0 * M_PI)) << " Hz";
    }
  }
  return message.str();
}

}  // namespace

ModeRelocationResult additive_srivc_relocated(const SampledData& data,
                                              const std::vector<SubmodelOrder>& orders,
                                              const RefinedIvOptions& options,
                                              const ModeRelocationOptions& relocation,
                                              const std::function<void(int, int)>& progress) {
  relocation.validate();
  options.validate();
  RefinedIvOptions trial_options = options;
  trial_options.compute_covariance = false;
  trial_options.record_history = false;
  const bool projected = relocation.criterion == RelocationCriterion::projected_output_error;

  ModeRelocationResult out(additive_srivc(data, orders, options));
  out.initial_mean_squared_error = out.estimate.mean_squared_error;
  out.initial_projected_mean_squared_error = projected_mse(out.estimate, orders, data);
  EstimationResult current = out.estimate;
  // The criterion's value of the current estimate. Projected criterion: the output error of
  // the poles, at the iteration's fixed point or, if smaller, at the start it was reached
  // from (when the moved mode stayed within the search window of it). The refined IV fixed
  // point of a weak, very lightly damped mode can fit clearly worse than that nearby start,
  // and a later move must beat the better of the two.
  double current_score =
      projected ? out.initial_projected_mean_squared_error : current.mean_squared_error;
  out.initial_score = current_score;
  out.score = current_score;
  const double h = data.sample_time();
  std::vector<int> movable_submodels;
  for (size_t i = 0; i < orders.size(); ++i) {
    if (movable(orders[i])) movable_submodels.push_back(static_cast<int>(i));
  }
  const std::vector<bool> excited =
      excited_band(data.input(), relocation.floor_half_width, relocation.min_input_level);
  // The search uses the simplest numerator among the movable submodels.
  int search_m = std::numeric_limits<int>::max();
  for (int i : movable_submodels) search_m = std::min(search_m, orders[static_cast<size_t>(i)].m);

  for (int round = 0; round < relocation.max_relocations && !movable_submodels.empty(); ++round) {
    if (!std::isfinite(current_score) || !current.parameters.allFinite()) break;
    ++out.rounds;
    const Eigen::VectorXd u = delay_samples(data.input(), current.input_delay_samples);
    const AdditiveModel& model = current.model;
    const double line = 2.0 * M_PI / (static_cast<double>(data.size()) * h);
    const std::vector<Candidate> candidates = relocation_candidates(
        data, orders, model, u, relocation, excited, movable_submodels, search_m);

    std::optional<EstimationResult> kept;
    size_t kept_trial = 0;
    const double keep = 1.0 - relocation.min_relative_decrease;
    for (const Candidate& c : candidates) {
      RelocationTrial trial;
      trial.round = round;
      trial.submodel = c.submodel;
      const std::optional<ModalParameters> before = model.modal_parameters(c.submodel);
      trial.moved_from =
          before ? before->natural_frequency : std::numeric_limits<double>::quiet_NaN();
      trial.peak_frequency = c.peak.frequency;
      trial.peak_to_floor = c.peak.ratio;
      trial.start_frequency = c.start.frequency;
      trial.start_damping = c.start.damping;
      trial.start_mean_squared_error = c.mean_squared_error;
      RefinedIvOptions o = trial_options;
      o.initial_model =
          AdditiveModel::from_parameters(orders, c.beta, current.input_delay_samples * h);
      o.input_delay_samples = current.input_delay_samples;
      EstimationResult r = additive_srivc(data, orders, o);
      trial.mean_squared_error = r.mean_squared_error;
      trial.projected_mean_squared_error = projected_mse(r, orders, data);
      trial.termination = r.termination;
      out.trials.push_back(trial);
      if (progress) {
        progress(static_cast<int>(out.trials.size()),
                 relocation.max_relocations * relocation.trials_per_round);
      }
      double score = projected ? trial.projected_mean_squared_error : r.mean_squared_error;
      const std::optional<ModalParameters> after = r.model.modal_parameters(c.submodel);
      const bool stayed = after && std::abs(after->natural_frequency - c.start.frequency) <
                                       relocation.search_half_width * line;
      if (projected && stayed) score = std::min(score, c.mean_squared_error);
      out.trials.back().score = score;
      // A trial that did not converge may replace a current estimate that did not either.
      const bool settled = r.converged() || !current.converged();
      if (settled && score < keep * current_score) {
        kept = std::move(r);
        kept_trial = out.trials.size() - 1;
        current_score = score;
        break;
      }
    }
    if (!kept) break;
    out.trials[kept_trial].accepted = true;
    out.score = current_score;
    ++out.relocations;
    current = std::move(*kept);
  }

  if (out.relocations > 0) {
    // The kept estimate was found without covariance; one more run from it (a fixed point, so
    // it stops at once) fills in what the caller asked for.
    RefinedIvOptions o = options;
    o.initial_model = current.model;
    o.input_delay_samples = current.input_delay_samples;
    out.estimate = additive_srivc(data, orders, o);
  }
  out.projected_mean_squared_error = projected_mse(out.estimate, orders, data);
  out.message = relocation_message(out);
  return out;
}

}  // namespace ctid
