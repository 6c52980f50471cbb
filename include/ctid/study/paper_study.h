// The Monte Carlo studies of González et al., Section 6: 6.1 open loop (four modes, white
// input, noise (q + 0.5)/(q - 0.85) e, SRIVC with 8 poles and 6 zeros against the additive
// estimator, DC gains b_i0 compared) and 6.2 closed loop (eq. 46 under the paper's PID, direct
// SRIVC, CLSRIVC and the additive closed-loop estimator, all six additive parameters compared).
// Run r at size j is a pure function of (seed, j, r): see monte_carlo.h for the seed hash.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/core/fields.h"
#include "ctid/core/sampled_data.h"
#include "ctid/estimation/termination.h"
#include "ctid/refined_iv/estimation_result.h"

namespace ctid {

enum class StudyKind {
  open_loop,    ///< Section 6.1
  closed_loop,  ///< Section 6.2
};

enum class StudyEstimator {
  srivc,             ///< unfactored SRIVC (in closed loop: the direct approach)
  clsrivc,           ///< unfactored closed-loop SRIVC (closed loop only)
  additive_srivc,    ///< additive open-loop iteration (29) (open loop only)
  additive_clsrivc,  ///< additive closed-loop iteration (29) with instrument (20)
};

inline constexpr std::array<Enumerator<StudyKind>, 2> study_kind_enumerators{{
    {StudyKind::open_loop, "open_loop", "Section 6.1."},
    {StudyKind::closed_loop, "closed_loop", "Section 6.2."},
}};
constexpr std::span<const Enumerator<StudyKind>> enumerators(StudyKind) {
  return study_kind_enumerators;
}

inline constexpr std::array<Enumerator<StudyEstimator>, 4> study_estimator_enumerators{{
    {StudyEstimator::srivc, "srivc", "Unfactored SRIVC (closed loop: the direct approach)."},
    {StudyEstimator::clsrivc, "clsrivc", "Unfactored closed-loop SRIVC (closed loop only)."},
    {StudyEstimator::additive_srivc, "additive_srivc",
     "Additive open-loop iteration (29) (open loop only)."},
    {StudyEstimator::additive_clsrivc, "additive_clsrivc",
     "Additive closed-loop iteration (29) with instrument (20)."},
}};
constexpr std::span<const Enumerator<StudyEstimator>> enumerators(StudyEstimator) {
  return study_estimator_enumerators;
}

/// "open-loop" / "closed-loop" and "srivc", "clsrivc", "additive_srivc", "additive_clsrivc".
std::string to_string(StudyKind kind);
std::string to_string(StudyEstimator estimator);

/// The largest study: runs x sizes cases, and samples per run (a run's record, its simulation
/// and its estimators' regressors are held at once).
inline constexpr long long kMaxStudyCases = 10'000'000;
inline constexpr int kMaxStudySamples = 10'000'000;

struct StudyOptions {
  StudyKind kind = StudyKind::open_loop;
  /// Monte Carlo runs per sample size (paper: 300). >= 1; runs x sizes <= kMaxStudyCases.
  int runs = 300;
  /// Number of log-spaced sample sizes (paper: 30 open loop, 50 closed loop). >= 1.
  int sizes = 30;
  /// Smallest and largest N (paper: 2000 and 100000; 500 and 123036). 1 <= min <= max <=
  /// kMaxStudySamples, and min large enough for the parameter count (>= 50).
  int min_samples = 2000;
  int max_samples = 100000;
  std::uint64_t seed = 1;
  /// Worker threads; 0: std::thread::hardware_concurrency().
  int threads = 0;
  /// Estimator settings (paper: 100 iterations; tolerance 1e-10 open loop, 1e-7 closed loop).
  int max_iterations = 100;
  double tolerance = 1e-10;
  /// Start at beta* (1 + U(-p, p)) elementwise (paper: p = 0.05), the same start for every
  /// estimator of a run; the unfactored estimators get it converted to one transfer function.
  double initial_perturbation = 0.05;
  /// Ask the estimators for their covariance, which gives the per-run standard errors and
  /// the predicted MSE (costs time).
  bool compute_covariance = true;
  /// Estimators to run; empty: all of the study (open loop: srivc, additive_srivc; closed
  /// loop: srivc, clsrivc, additive_clsrivc).
  std::vector<StudyEstimator> estimators;

  static constexpr std::string_view type_name = "StudyOptions";
  static constexpr auto fields() {
    using O = StudyOptions;
    return std::tuple{
        field("kind", &O::kind, "Which Section 6 study."),
        field("runs", &O::runs, AtLeast{1}, "Monte Carlo runs per sample size."),
        field("sizes", &O::sizes, AtLeast{1}, "Number of log-spaced sample sizes."),
        field("min_samples", &O::min_samples, AtLeast{50},
              "Smallest N (enough samples for 15 parameters)."),
        field("max_samples", &O::max_samples, AtLeast{1}, "Largest N (>= min_samples)."),
        field("seed", &O::seed, "Study seed; run r at size j uses a hash of (seed, j, r)."),
        field("threads", &O::threads, AtLeast{0}, "Worker threads (0: all cores)."),
        field("max_iterations", &O::max_iterations, AtLeast{1}, "Estimator iteration limit."),
        field("tolerance", &O::tolerance, Between{0, 1}, "Estimator tolerance."),
        field("initial_perturbation", &O::initial_perturbation, Between{0, 1, true, false},
              "Start at beta* (1 + U(-p, p)) elementwise."),
        field("compute_covariance", &O::compute_covariance,
              "Ask the estimators for covariances (standard errors, predicted MSE)."),
        field("estimators", &O::estimators, "Estimators to run; empty: those of the study's kind."),
    };
  }

  /// The paper's study of that kind at full size.
  static StudyOptions paper(StudyKind kind);
  /// max_samples >= min_samples; the estimators belong to the study's kind.
  void check_relations(const std::string& path) const;
  /// Throws InvalidArgument naming the first bad field, its value and the rule.
  void validate() const { validate_fields(*this); }
  /// `estimators`, or the study's default set when empty.
  std::vector<StudyEstimator> active_estimators() const;
};

/// The true system and the experiment of a study.
struct StudySetup {
  AdditiveModel system;
  double sample_time = 0.05;
  /// Closed loop: the PID C_d(q) = 0.0115 + 0.00725 q/(q-1) + 0.00454 (q-1)/q.
  std::optional<DiscreteTransferFunction> controller;
  /// Open loop: (q + 0.5)/(q - 0.85) driven by white noise of variance 0.02; closed loop:
  /// none (white output noise of variance 0.01).
  std::optional<DiscreteTransferFunction> noise_filter;
  double noise_variance = 0.02;
  /// The compared parameters: names ("b10", "a11", ...) and true values.
  std::vector<std::string> parameter_names;
  Eigen::VectorXd true_parameters;
};

StudySetup study_setup(StudyKind kind);

/// The data and the start of one run.
struct StudyRunInput {
  SampledData data;
  AdditiveModel initial_model;
};

/// Simulates run `run_index` at N = `samples` from the run's seed: the input (open loop) or
/// reference (closed loop) from stream 0, the noise from stream 1, the start from stream 2.
StudyRunInput simulate_study_run(const StudyOptions& options, int samples, std::uint64_t seed);

/// One estimator's outcome in one run: how it stopped (the Outcome, `message` the estimator's
/// own) and the compared parameters.
struct StudyRecord : Outcome {
  int size_index = 0;
  int run_index = 0;
  int samples = 0;
  std::uint64_t seed = 0;
  StudyEstimator estimator = StudyEstimator::srivc;
  /// The compared parameters could be formed (the estimate splits into the true structure,
  /// e.g. four complex-pole modes); otherwise `estimate` is NaN.
  bool valid = false;
  Eigen::VectorXd estimate;
  /// Delta-method standard errors of `estimate` from the estimator's reported covariance
  /// (NaN without covariance).
  Eigen::VectorXd standard_error;
  /// Non-empty if the estimator threw (InvalidArgument on data it should accept): the
  /// message, so the run can be replayed and reported; the study goes on.
  std::string error;

  static constexpr std::string_view type_name = "StudyRecord";
  static constexpr auto fields() {
    using S = StudyRecord;
    return std::tuple_cat(
        std::tuple{
            field("size_index", &S::size_index, "Index of the sample size."),
            field("run_index", &S::run_index, "Index of the run."),
            field("samples", &S::samples, "N."),
            field("seed", &S::seed, "The run's seed."),
            field("estimator", &S::estimator, "StudyEstimator."),
        },
        Outcome::fields(),
        std::tuple{
            field("valid", &S::valid, "The compared parameters could be formed."),
            field("estimate", &S::estimate, "The compared parameters (NaN unless valid)."),
            field("standard_error", &S::standard_error,
                  "Their delta-method standard errors (NaN without covariance)."),
            field("error", &S::error, "The message if the estimator threw, else empty."),
        });
  }
};

/// Compared parameters of a model in the study's structure (K second-order modes sorted as
/// the truth): b_i0 (open loop) or [a_i1, a_i2, b_i0] per mode (closed loop). An unfactored
/// model is split by partial fractions first. Empty if the structure does not fit.
Eigen::VectorXd compared_parameters(StudyKind kind, const AdditiveModel& model);

/// Runs every active estimator on run (size_index, run_index): the pure function that the
/// full study evaluates at every index, and that `--run-index/--size-index` replays.
std::vector<StudyRecord> run_study_case(const StudyOptions& options, int size_index, int run_index);

/// MSE of one estimator and parameter at one sample size.
struct MseRow {
  StudyEstimator estimator = StudyEstimator::srivc;
  int size_index = 0;
  int samples = 0;
  int parameter = 0;
  double true_value = 0.0;
  double mean_squared_error = 0.0;
  double bias = 0.0;
  /// Mean over the runs of the squared reported standard errors (NaN without covariance).
  double predicted_mean_squared_error = 0.0;
  int valid_runs = 0;
  int converged_runs = 0;

  static constexpr std::string_view type_name = "MseRow";
  static constexpr auto fields() {
    using S = MseRow;
    return std::tuple{
        field("estimator", &S::estimator, "StudyEstimator."),
        field("size_index", &S::size_index, "Index of the sample size."),
        field("samples", &S::samples, "N."),
        field("parameter", &S::parameter, "Index of the compared parameter."),
        field("true_value", &S::true_value, "Its true value."),
        field("mean_squared_error", &S::mean_squared_error, "MSE over the valid runs."),
        field("bias", &S::bias, "Mean error over the valid runs."),
        field("predicted_mean_squared_error", &S::predicted_mean_squared_error,
              "Mean squared reported standard error (NaN without covariance)."),
        field("valid_runs", &S::valid_runs, "Runs with a valid estimate."),
        field("converged_runs", &S::converged_runs, "Runs that converged."),
    };
  }
};

struct StudyResult {
  StudyOptions options;
  std::vector<int> sample_sizes;
  std::vector<std::string> parameter_names;
  Eigen::VectorXd true_parameters;
  /// Ordered by size index, then run index, then estimator (options.active_estimators()).
  std::vector<StudyRecord> records;
  /// Ordered by estimator, then size index, then parameter.
  std::vector<MseRow> mse;

  static constexpr std::string_view type_name = "StudyResult";
  static constexpr auto fields() {
    using S = StudyResult;
    return std::tuple{
        field("options", &S::options, "The StudyOptions that were run."),
        field("sample_sizes", &S::sample_sizes, "N per size index."),
        field("parameter_names", &S::parameter_names, "Names of the compared parameters."),
        field("true_parameters", &S::true_parameters, "Their true values."),
        field("records", &S::records, "StudyRecord per size, run and estimator (in that order)."),
        field("mse", &S::mse, "MseRow per estimator, size and parameter (in that order)."),
    };
  }
};

/// MSE rows from records (any order) for the given sizes and estimators.
std::vector<MseRow> summarize_study(const std::vector<StudyRecord>& records,
                                    const std::vector<int>& sample_sizes,
                                    const std::vector<StudyEstimator>& estimators,
                                    const Eigen::VectorXd& true_parameters);

/// The StudyResult of a study whose cases were run elsewhere (e.g. on a Dask cluster, by
/// run_study_case): the options, sample sizes, compared parameters, `records` and their MSE
/// table, assembled exactly as run_study assembles its own. `records` must be in the study's
/// order (size index, then run index, then active estimator), one per case and estimator;
/// otherwise InvalidArgument names the first record out of place.
StudyResult study_result_from_records(const StudyOptions& options,
                                      std::vector<StudyRecord> records);

/// The whole study in parallel (options.threads). `progress`, if given, is called after each
/// finished case with the number finished and the total (from worker threads, serialised).
StudyResult run_study(const StudyOptions& options,
                      const std::function<void(int, int)>& progress = {});

}  // namespace ctid
