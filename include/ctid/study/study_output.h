// Text outputs of a Section 6 study (paper_study.h): per-run records, MSE per sample size and
// parameter beside the covariance prediction, and per-parameter trends (log-log slope of MSE
// against N, MSE ratio between estimators, MSE over prediction). CSV with a header row;
// doubles printed with 17 significant digits so a replayed run compares exactly.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/fields.h"
#include "ctid/study/paper_study.h"

namespace ctid {

/// One row per record: estimator,size_index,run_index,N,seed,termination,iterations,valid,
/// <parameter>... (estimates), se_<parameter>... (standard errors), error.
void write_records_csv(const StudyResult& result, std::ostream& out);
/// The same for records of a replayed case (run_study_case), with the study's names.
void write_records_csv(const std::vector<StudyRecord>& records,
                       const std::vector<std::string>& parameter_names, std::ostream& out);

/// estimator,N,size_index,parameter,true_value,mse,bias,predicted_mse,valid_runs,
/// converged_runs: one row per MseRow.
void write_mse_csv(const StudyResult& result, std::ostream& out);

/// Trend of one estimator and parameter over all sample sizes.
struct ParameterTrend {
  StudyEstimator estimator = StudyEstimator::srivc;
  int parameter = 0;
  /// Least-squares slope of log10 MSE against log10 N (-1: MSE ~ 1/N).
  double slope = 0.0;
  /// Geometric mean over the sizes of MSE / predicted MSE (NaN without covariance).
  double mse_over_prediction = 0.0;
  /// Geometric mean over the sizes of MSE / MSE of the study's reference estimator (srivc).
  double mse_over_reference = 0.0;
  /// N * MSE at the largest N.
  double scaled_mse_at_largest = 0.0;

  static constexpr std::string_view type_name = "ParameterTrend";
  static constexpr auto fields() {
    using S = ParameterTrend;
    return std::tuple{
        field("estimator", &S::estimator, "StudyEstimator."),
        field("parameter", &S::parameter, "Index of the compared parameter."),
        field("slope", &S::slope, "Least-squares slope of log10 MSE against log10 N."),
        field("mse_over_prediction", &S::mse_over_prediction,
              "Geometric mean of MSE / predicted MSE (NaN without covariance)."),
        field("mse_over_reference", &S::mse_over_reference,
              "Geometric mean of MSE / MSE of the reference estimator (srivc)."),
        field("scaled_mse_at_largest", &S::scaled_mse_at_largest, "N * MSE at the largest N."),
    };
  }
};
std::vector<ParameterTrend> parameter_trends(const StudyResult& result);

/// estimator,parameter,slope,mse_over_prediction,mse_over_srivc,n_mse_at_largest_N.
void write_trends_csv(const StudyResult& result, std::ostream& out);

/// What a whole study found, without its per-run records (those are in runs.csv): the
/// study's kind, estimators, runs and seed, the sample sizes, the compared parameters with
/// their true values, the MSE table and the trends. `ctid study` writes it as a
/// study_summary document (io/report_json.h) beside its CSV files.
struct StudySummary {
  StudyKind kind = StudyKind::open_loop;
  std::vector<StudyEstimator> estimators;  ///< those that ran, in the order of the tables
  int runs = 0;                            ///< Monte Carlo runs per sample size
  std::uint64_t seed = 0;                  ///< the study seed
  std::vector<int> sample_sizes;
  std::vector<std::string> parameter_names;
  Eigen::VectorXd true_parameters;
  std::vector<MseRow> mse;
  std::vector<ParameterTrend> trends;

  static constexpr std::string_view type_name = "StudySummary";
  static constexpr auto fields() {
    using S = StudySummary;
    return std::tuple{
        field("kind", &S::kind, "StudyKind: Section 6.1 (open loop) or 6.2 (closed loop)."),
        field("estimators", &S::estimators, "The estimators that ran."),
        field("runs", &S::runs, "Monte Carlo runs per sample size."),
        field("seed", &S::seed, "The study seed."),
        field("sample_sizes", &S::sample_sizes, "N per size index."),
        field("parameter_names", &S::parameter_names, "Names of the compared parameters."),
        field("true_parameters", &S::true_parameters, "Their true values."),
        field("mse", &S::mse, "MseRow per estimator, size and parameter."),
        field("trends", &S::trends, "ParameterTrend per estimator and parameter."),
    };
  }
};

/// The summary of a finished study: its MSE table and parameter_trends(result).
StudySummary study_summary(const StudyResult& result);

}  // namespace ctid
