// Text outputs of a Section 6 study (paper_study.h): per-run records, MSE per sample size and
// parameter beside the covariance prediction, and per-parameter trends (log-log slope of MSE
// against N, MSE ratio between estimators, MSE over prediction). CSV with a header row;
// doubles printed with 17 significant digits so a replayed run compares exactly.
#pragma once

#include <ostream>
#include <string>
#include <vector>

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
};
std::vector<ParameterTrend> parameter_trends(const StudyResult& result);

/// estimator,parameter,slope,mse_over_prediction,mse_over_srivc,n_mse_at_largest_N.
void write_trends_csv(const StudyResult& result, std::ostream& out);

}  // namespace ctid
