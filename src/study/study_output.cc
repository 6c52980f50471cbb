// CSV writers and trend summaries of study_output.h.
#include "ctid/study/study_output.h"

#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include "ctid/study/monte_carlo.h"

namespace ctid {
namespace {

constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

// CSV-safe one-line text: commas and line breaks become spaces, quotes are dropped.
std::string csv_text(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    if (c == ',' || c == '\n' || c == '\r') {
      out += ' ';
    } else if (c != '"') {
      out += c;
    }
  }
  return out;
}

// Geometric mean of the finite positive ratios a_k / b_k (NaN if none).
double geometric_mean_ratio(const std::vector<std::pair<double, double>>& pairs) {
  double sum = 0.0;
  int count = 0;
  for (const auto& [a, b] : pairs) {
    if (std::isfinite(a) && std::isfinite(b) && a > 0.0 && b > 0.0) {
      sum += std::log(a / b);
      ++count;
    }
  }
  return count == 0 ? kNoValue : std::exp(sum / count);
}

}  // namespace

void write_records_csv(const std::vector<StudyRecord>& records,
                       const std::vector<std::string>& parameter_names, std::ostream& out) {
  const auto precision = out.precision(17);
  out << "estimator,size_index,run_index,N,seed,termination,iterations,valid";
  for (const std::string& name : parameter_names) out << ',' << name;
  for (const std::string& name : parameter_names) out << ",se_" << name;
  out << ",error\n";
  for (const StudyRecord& r : records) {
    out << to_string(r.estimator) << ',' << r.size_index << ',' << r.run_index << ',' << r.samples
        << ',' << r.seed << ','
        << (r.error.empty() ? to_string(r.termination) : std::string("error")) << ','
        << r.iterations << ',' << (r.valid ? 1 : 0);
    for (Eigen::Index k = 0; k < r.estimate.size(); ++k) out << ',' << r.estimate[k];
    for (Eigen::Index k = 0; k < r.standard_error.size(); ++k) {
      out << ',' << r.standard_error[k];
    }
    out << ',' << csv_text(r.error) << '\n';
  }
  out.precision(precision);
}

void write_records_csv(const StudyResult& result, std::ostream& out) {
  write_records_csv(result.records, result.parameter_names, out);
}

void write_mse_csv(const StudyResult& result, std::ostream& out) {
  const auto precision = out.precision(17);
  out << "estimator,N,size_index,parameter,true_value,mse,bias,predicted_mse,valid_runs,"
         "converged_runs\n";
  for (const MseRow& row : result.mse) {
    out << to_string(row.estimator) << ',' << row.samples << ',' << row.size_index << ','
        << result.parameter_names.at(static_cast<size_t>(row.parameter)) << ',' << row.true_value
        << ',' << row.mean_squared_error << ',' << row.bias << ','
        << row.predicted_mean_squared_error << ',' << row.valid_runs << ',' << row.converged_runs
        << '\n';
  }
  out.precision(precision);
}

std::vector<ParameterTrend> parameter_trends(const StudyResult& result) {
  // (estimator, parameter) -> MSE rows in size order.
  std::map<std::pair<StudyEstimator, int>, std::vector<const MseRow*>> series;
  for (const MseRow& row : result.mse) series[{row.estimator, row.parameter}].push_back(&row);
  std::vector<ParameterTrend> trends;
  for (StudyEstimator estimator : result.options.active_estimators()) {
    for (int k = 0; k < static_cast<int>(result.parameter_names.size()); ++k) {
      const auto found = series.find({estimator, k});
      if (found == series.end()) continue;
      const std::vector<const MseRow*>& rows = found->second;
      const auto reference = series.find({StudyEstimator::srivc, k});
      std::vector<int> samples;
      std::vector<double> mse;
      std::vector<std::pair<double, double>> to_prediction;
      std::vector<std::pair<double, double>> to_reference;
      for (size_t j = 0; j < rows.size(); ++j) {
        samples.push_back(rows[j]->samples);
        mse.push_back(rows[j]->mean_squared_error);
        to_prediction.emplace_back(rows[j]->mean_squared_error,
                                   rows[j]->predicted_mean_squared_error);
        if (reference != series.end() && j < reference->second.size()) {
          to_reference.emplace_back(rows[j]->mean_squared_error,
                                    reference->second[j]->mean_squared_error);
        }
      }
      ParameterTrend trend;
      trend.estimator = estimator;
      trend.parameter = k;
      trend.slope = log_log_slope(samples, mse);
      trend.mse_over_prediction = geometric_mean_ratio(to_prediction);
      trend.mse_over_reference = geometric_mean_ratio(to_reference);
      trend.scaled_mse_at_largest =
          rows.empty() ? kNoValue : rows.back()->samples * rows.back()->mean_squared_error;
      trends.push_back(trend);
    }
  }
  return trends;
}

void write_trends_csv(const StudyResult& result, std::ostream& out) {
  const auto precision = out.precision(6);
  out << "estimator,parameter,slope,mse_over_prediction,mse_over_srivc,n_mse_at_largest_N\n";
  for (const ParameterTrend& t : parameter_trends(result)) {
    out << to_string(t.estimator) << ','
        << result.parameter_names.at(static_cast<size_t>(t.parameter)) << ',' << t.slope << ','
        << t.mse_over_prediction << ',' << t.mse_over_reference << ',' << t.scaled_mse_at_largest
        << '\n';
  }
  out.precision(precision);
}

StudySummary study_summary(const StudyResult& result) {
  StudySummary summary;
  summary.kind = result.options.kind;
  summary.estimators = result.options.active_estimators();
  summary.runs = result.options.runs;
  summary.seed = result.options.seed;
  summary.sample_sizes = result.sample_sizes;
  summary.parameter_names = result.parameter_names;
  summary.true_parameters = result.true_parameters;
  summary.mse = result.mse;
  summary.trends = parameter_trends(result);
  return summary;
}

}  // namespace ctid
