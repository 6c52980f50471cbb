// The Section 6 studies of González et al.: experiment set-up, one replayable run, the
// parallel study and its MSE summary (paper_study.h).
#include "ctid/study/paper_study.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <optional>
#include <random>
#include <utility>

#include "core/internal/finite_transfer_function.h"
#include "ctid/core/error.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/clsrivc.h"
#include "ctid/refined_iv/srivc.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/noise.h"
#include "ctid/simulation/simulate.h"
#include "ctid/study/monte_carlo.h"

namespace ctid {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kInputStream = 0;
constexpr int kNoiseStream = 1;
constexpr int kStartStream = 2;

// B/(1 + a1 p + a2 p^2) with poles sigma +- j omega and static gain `gain`.
Submodel mode_from_pole(double sigma, double omega, double gain) {
  const double magnitude2 = sigma * sigma + omega * omega;
  return {Polynomial({1.0, -2.0 * sigma / magnitude2, 1.0 / magnitude2}), Polynomial({gain}), 0};
}

// A uniform double in [0, 1) from the top 53 bits: the same on every standard library,
// unlike std::uniform_real_distribution.
double unit_uniform(std::mt19937_64& generator) {
  return static_cast<double>(generator() >> 11) * 0x1.0p-53;
}

bool is_open_loop_estimator(StudyEstimator e) {
  return e == StudyEstimator::srivc || e == StudyEstimator::additive_srivc;
}
bool is_closed_loop_estimator(StudyEstimator e) {
  return e == StudyEstimator::srivc || e == StudyEstimator::clsrivc ||
         e == StudyEstimator::additive_clsrivc;
}

// Central-difference Jacobian of the compared parameters with respect to the estimator's
// own parameters; empty if some evaluation does not fit the structure.
Eigen::MatrixXd compared_jacobian(StudyKind kind, const AdditiveModel& model,
                                  const Eigen::VectorXd& beta, Eigen::Index outputs) {
  Eigen::MatrixXd jacobian(outputs, beta.size());
  const double scale = std::max(beta.cwiseAbs().maxCoeff(), 1e-300);
  for (Eigen::Index j = 0; j < beta.size(); ++j) {
    const double step = 1e-6 * std::max(std::abs(beta[j]), 1e-6 * scale);
    Eigen::VectorXd plus = beta;
    Eigen::VectorXd minus = beta;
    plus[j] += step;
    minus[j] -= step;
    if (!plus.allFinite() || !minus.allFinite()) return {};
    const Eigen::VectorXd f_plus = compared_parameters(kind, model.with_parameters(plus));
    const Eigen::VectorXd f_minus = compared_parameters(kind, model.with_parameters(minus));
    if (f_plus.size() != outputs || f_minus.size() != outputs) return {};
    jacobian.col(j) = (f_plus - f_minus) / (2.0 * step);
  }
  return jacobian;
}

EstimationResult run_estimator(StudyEstimator estimator, const StudySetup& setup,
                               const SampledData& data, const RefinedIvOptions& riv) {
  const std::vector<SubmodelOrder> orders = setup.system.orders();
  // The unfactored equivalent of K zero-free second-order modes: n = 2K poles and
  // 2K - 2 zeros (8 and 6 in Section 6.1, 4 and 2 in Section 6.2).
  int poles = 0;
  for (const SubmodelOrder& order : orders) poles += order.n;
  const SubmodelOrder unfactored{poles, poles - 2, 0};
  switch (estimator) {
    case StudyEstimator::srivc:
      return srivc(data, unfactored, riv);
    case StudyEstimator::clsrivc:
      return clsrivc(data, *setup.controller, unfactored, riv);
    case StudyEstimator::additive_srivc:
      return additive_srivc(data, orders, riv);
    case StudyEstimator::additive_clsrivc:
      return additive_clsrivc(data, *setup.controller, orders, riv);
  }
  throw InvalidArgument("run_estimator: unknown estimator");
}

}  // namespace

std::string to_string(StudyKind kind) {
  return kind == StudyKind::open_loop ? "open-loop" : "closed-loop";
}

std::string to_string(StudyEstimator estimator) { return std::string(enum_name(estimator)); }

StudyOptions StudyOptions::paper(StudyKind kind) {
  StudyOptions options;
  options.kind = kind;
  if (kind == StudyKind::closed_loop) {
    options.sizes = 50;
    options.min_samples = 500;
    options.max_samples = 123036;
    options.tolerance = 1e-7;
  }
  return options;
}

void StudyOptions::check_relations(const std::string& path) const {
  require(max_samples >= min_samples, path, ".max_samples is ", max_samples,
          "; it must be >= min_samples (", min_samples, ")");
  require(max_samples <= kMaxStudySamples, path, ".max_samples is ", max_samples,
          "; a study's runs have at most ", kMaxStudySamples, " samples");
  const long long cases = static_cast<long long>(runs) * sizes;
  require(cases <= kMaxStudyCases, path, ".runs x ", path, ".sizes is ", runs, " x ", sizes, " = ",
          cases, " cases; a study runs at most ", kMaxStudyCases,
          " (split it over seeds or sample ranges)");
  for (std::size_t i = 0; i < estimators.size(); ++i) {
    const StudyEstimator e = estimators[i];
    if (kind == StudyKind::open_loop) {
      require(is_open_loop_estimator(e), path, ".estimators[", i, "] is ", to_string(e),
              "; it must be srivc or additive_srivc (the open-loop study)");
    } else {
      require(is_closed_loop_estimator(e), path, ".estimators[", i, "] is ", to_string(e),
              "; it must be srivc, clsrivc or additive_clsrivc (the closed-loop study)");
    }
  }
}

std::vector<StudyEstimator> StudyOptions::active_estimators() const {
  if (!estimators.empty()) return estimators;
  if (kind == StudyKind::open_loop) {
    return {StudyEstimator::srivc, StudyEstimator::additive_srivc};
  }
  return {StudyEstimator::srivc, StudyEstimator::clsrivc, StudyEstimator::additive_clsrivc};
}

StudySetup study_setup(StudyKind kind) {
  if (kind == StudyKind::open_loop) {
    StudySetup setup{
        AdditiveModel({mode_from_pole(-0.25, 1.39, 3.0), mode_from_pole(-0.15, 3.16, 0.4),
                       mode_from_pole(-0.17, 5.77, 0.2), mode_from_pole(-0.5, 9.99, 0.05)}),
        0.05,
        std::nullopt,
        std::nullopt,
        0.02,
        {"b10", "b20", "b30", "b40"},
        Eigen::Vector4d(3.0, 0.4, 0.2, 0.05)};
    setup.noise_filter = DiscreteTransferFunction(Polynomial({0.5, 1.0}), Polynomial({-0.85, 1.0}),
                                                  setup.sample_time);
    return setup;
  }
  StudySetup setup{AdditiveModel({{Polynomial({1.0, 0.25, 0.25}), Polynomial({3.0}), 0},
                                  {Polynomial({1.0, 0.01, 0.025}), Polynomial({1.0}), 0}}),
                   0.05,
                   std::nullopt,
                   std::nullopt,
                   0.01,
                   {"a11", "a12", "b10", "a21", "a22", "b20"},
                   Eigen::VectorXd(6)};
  setup.true_parameters << 0.25, 0.25, 3.0, 0.01, 0.025, 1.0;
  // 0.0115 + 0.00725 q/(q - 1) + 0.00454 (q - 1)/q over the common denominator q (q - 1).
  const double kp = 0.0115, ki = 0.00725, kd = 0.00454;
  setup.controller = DiscreteTransferFunction(Polynomial({kd, -kp - 2.0 * kd, kp + ki + kd}),
                                              Polynomial({0.0, -1.0, 1.0}), setup.sample_time);
  return setup;
}

StudyRunInput simulate_study_run(const StudyOptions& options, int samples, std::uint64_t seed) {
  require(samples >= 2, "simulate_study_run: samples is ", samples, "; it must be >= 2");
  const StudySetup setup = study_setup(options.kind);
  const double h = setup.sample_time;
  const Eigen::VectorXd excitation = white_noise(samples, 1.0, stream_seed(seed, kInputStream));

  std::mt19937_64 start_generator(stream_seed(seed, kStartStream));
  Eigen::VectorXd beta = setup.system.parameters();
  for (Eigen::Index k = 0; k < beta.size(); ++k) {
    const double u = 2.0 * unit_uniform(start_generator) - 1.0;
    beta[k] *= 1.0 + options.initial_perturbation * u;
  }
  AdditiveModel start = setup.system.with_parameters(beta);

  if (options.kind == StudyKind::open_loop) {
    const Eigen::VectorXd noise = colored_noise(*setup.noise_filter, samples, setup.noise_variance,
                                                stream_seed(seed, kNoiseStream));
    Eigen::VectorXd output = simulate(setup.system, excitation, h) + noise;
    return {SampledData(h, excitation, std::move(output)), std::move(start)};
  }
  const Eigen::VectorXd noise =
      white_noise(samples, std::sqrt(setup.noise_variance), stream_seed(seed, kNoiseStream));
  ClosedLoopSimulation loop =
      simulate_closed_loop(setup.system, *setup.controller, excitation, noise);
  return {SampledData(h, std::move(loop.input), std::move(loop.output), excitation),
          std::move(start)};
}

Eigen::VectorXd compared_parameters(StudyKind kind, const AdditiveModel& model) {
  const StudySetup setup = study_setup(kind);
  const int modes = setup.system.size();
  if (model.size() == 1 && model[0].n() > 2) {
    // A model without a finite transfer function or with repeated poles does not split.
    const std::optional<TransferFunction> g = internal::transfer_function_if_finite(model);
    const std::optional<AdditiveModel> split =
        g ? AdditiveModel::split_transfer_function(*g) : std::nullopt;
    return split ? compared_parameters(kind, *split) : Eigen::VectorXd();
  }
  if (model.size() != modes) return {};
  const bool dc_gains_only = kind == StudyKind::open_loop;
  Eigen::VectorXd compared(dc_gains_only ? modes : 3 * modes);
  for (int i = 0; i < modes; ++i) {
    const Submodel& sub = model[i];
    if (sub.n() != 2 || sub.integrators != 0) return {};
    if (dc_gains_only) {
      compared[i] = sub.b[0];
    } else {
      compared.segment(3 * i, 3) << sub.a[1], sub.a[2], sub.b[0];
    }
  }
  return compared;
}

std::vector<StudyRecord> run_study_case(const StudyOptions& options, int size_index,
                                        int run_index) {
  options.validate();
  const std::vector<int> sizes =
      log_spaced_sizes(options.min_samples, options.max_samples, options.sizes);
  require(size_index >= 0 && size_index < options.sizes, "run_study_case: size_index is ",
          size_index, "; it must be in [0, ", options.sizes, ")");
  require(run_index >= 0 && run_index < options.runs, "run_study_case: run_index is ", run_index,
          "; it must be in [0, ", options.runs, ")");
  const StudySetup setup = study_setup(options.kind);
  const Eigen::Index compared_count = setup.true_parameters.size();
  const std::uint64_t seed = run_seed(options.seed, size_index, run_index);
  const int samples = sizes[static_cast<size_t>(size_index)];
  const StudyRunInput input = simulate_study_run(options, samples, seed);

  RefinedIvOptions riv;
  riv.max_iterations = options.max_iterations;
  riv.tolerance = options.tolerance;
  riv.initial_model = input.initial_model;
  riv.compute_covariance = options.compute_covariance;
  riv.noise =
      options.kind == StudyKind::open_loop ? NoiseAssumption::coloured : NoiseAssumption::white;

  std::vector<StudyRecord> records;
  for (StudyEstimator estimator : options.active_estimators()) {
    StudyRecord record;
    record.size_index = size_index;
    record.run_index = run_index;
    record.samples = samples;
    record.seed = seed;
    record.estimator = estimator;
    record.estimate = Eigen::VectorXd::Constant(compared_count, kNaN);
    record.standard_error = Eigen::VectorXd::Constant(compared_count, kNaN);
    try {
      const EstimationResult result = run_estimator(estimator, setup, input.data, riv);
      static_cast<Outcome&>(record) = result;
      const Eigen::VectorXd compared = compared_parameters(options.kind, result.model);
      if (compared.size() == compared_count && compared.allFinite()) {
        record.valid = true;
        record.estimate = compared;
        if (result.covariance.rows() == result.parameters.size() && result.covariance.allFinite()) {
          const Eigen::MatrixXd jacobian =
              compared_jacobian(options.kind, result.model, result.parameters, compared_count);
          if (jacobian.size() > 0) {
            const Eigen::MatrixXd cov = jacobian * result.covariance * jacobian.transpose();
            record.standard_error = cov.diagonal().cwiseMax(0.0).cwiseSqrt();
          }
        }
      }
    } catch (const std::exception& error) {
      record.error = error.what();
    }
    records.push_back(std::move(record));
  }
  return records;
}

std::vector<MseRow> summarize_study(const std::vector<StudyRecord>& records,
                                    const std::vector<int>& sample_sizes,
                                    const std::vector<StudyEstimator>& estimators,
                                    const Eigen::VectorXd& true_parameters) {
  std::vector<MseRow> rows;
  const Eigen::Index p = true_parameters.size();
  for (StudyEstimator estimator : estimators) {
    for (size_t j = 0; j < sample_sizes.size(); ++j) {
      std::vector<const StudyRecord*> selected;
      for (const StudyRecord& record : records) {
        if (record.estimator == estimator && record.size_index == static_cast<int>(j)) {
          selected.push_back(&record);
        }
      }
      int converged = 0;
      for (const StudyRecord* record : selected) {
        if (record->termination == Termination::converged && record->error.empty()) ++converged;
      }
      for (Eigen::Index k = 0; k < p; ++k) {
        Eigen::VectorXd estimates(static_cast<Eigen::Index>(selected.size()));
        Eigen::VectorXd variances(static_cast<Eigen::Index>(selected.size()));
        for (size_t r = 0; r < selected.size(); ++r) {
          const StudyRecord& record = *selected[r];
          const bool usable = record.valid && record.estimate.size() == p;
          estimates[static_cast<Eigen::Index>(r)] = usable ? record.estimate[k] : kNaN;
          const double se =
              usable && record.standard_error.size() == p ? record.standard_error[k] : kNaN;
          variances[static_cast<Eigen::Index>(r)] = se * se;
        }
        const ErrorSummary summary = summarize_errors(estimates, true_parameters[k], variances);
        MseRow row;
        row.estimator = estimator;
        row.size_index = static_cast<int>(j);
        row.samples = sample_sizes[j];
        row.parameter = static_cast<int>(k);
        row.true_value = true_parameters[k];
        row.mean_squared_error = summary.mean_squared_error;
        row.bias = summary.bias;
        row.predicted_mean_squared_error = summary.predicted_mean_squared_error;
        row.valid_runs = summary.runs;
        row.converged_runs = converged;
        rows.push_back(row);
      }
    }
  }
  return rows;
}

StudyResult study_result_from_records(const StudyOptions& options,
                                      std::vector<StudyRecord> records) {
  options.validate();
  const std::vector<StudyEstimator> estimators = options.active_estimators();
  const std::size_t count = static_cast<std::size_t>(options.sizes) *
                            static_cast<std::size_t>(options.runs) * estimators.size();
  require(records.size() == count, "study_result_from_records: ", records.size(),
          " records; the study has ", count, " (", options.sizes, " sizes x ", options.runs,
          " runs x ", estimators.size(), " estimators)");
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t per_size = static_cast<std::size_t>(options.runs) * estimators.size();
    const int size_index = static_cast<int>(k / per_size);
    const int run_index = static_cast<int>(k % per_size / estimators.size());
    const StudyEstimator estimator = estimators[k % estimators.size()];
    const StudyRecord& record = records[k];
    require(record.size_index == size_index && record.run_index == run_index &&
                record.estimator == estimator,
            "study_result_from_records: records[", k, "] is (size ", record.size_index, ", run ",
            record.run_index, ", ", to_string(record.estimator),
            "); the study's order needs (size ", size_index, ", run ", run_index, ", ",
            to_string(estimator), ") there");
  }
  const StudySetup setup = study_setup(options.kind);
  StudyResult result;
  result.options = options;
  result.sample_sizes = log_spaced_sizes(options.min_samples, options.max_samples, options.sizes);
  result.parameter_names = setup.parameter_names;
  result.true_parameters = setup.true_parameters;
  result.records = std::move(records);
  result.mse =
      summarize_study(result.records, result.sample_sizes, estimators, result.true_parameters);
  return result;
}

StudyResult run_study(const StudyOptions& options, const std::function<void(int, int)>& progress) {
  options.validate();
  const int cases = options.sizes * options.runs;
  std::vector<std::vector<StudyRecord>> per_case(static_cast<size_t>(cases));
  std::mutex progress_mutex;
  int finished = 0;
  // Largest sizes first: the long runs start early, so the threads finish together.
  parallel_for(cases, options.threads, [&](int i) {
    const int order = cases - 1 - i;
    const int size_index = order / options.runs;
    const int run_index = order % options.runs;
    per_case[static_cast<size_t>(order)] = run_study_case(options, size_index, run_index);
    if (progress) {
      std::lock_guard<std::mutex> lock(progress_mutex);
      progress(++finished, cases);
    }
  });
  std::vector<StudyRecord> records;
  for (std::vector<StudyRecord>& each : per_case) {
    for (StudyRecord& record : each) records.push_back(std::move(record));
  }
  return study_result_from_records(options, std::move(records));
}

}  // namespace ctid
