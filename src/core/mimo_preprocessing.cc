#include "ctid/core/mimo_preprocessing.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ctid/core/error.h"

namespace ctid {
namespace {

// "input mean 5 is ..." from the SISO record of one pair, said of the channel it concerns;
// a warning about neither signal (the input hold) is kept once.
void add_warnings(const std::vector<std::string>& from, const std::string& input_name,
                  const std::string& output_name, bool own_input, bool own_output,
                  std::vector<std::string>& to) {
  for (const std::string& w : from) {
    std::string text;
    if (w.rfind("input ", 0) == 0) {
      if (!own_input) continue;
      text = "input " + input_name + w.substr(5);
    } else if (w.rfind("output ", 0) == 0) {
      if (!own_output) continue;
      text = "output " + output_name + w.substr(6);
    } else {
      text = w;
    }
    if (std::find(to.begin(), to.end(), text) == to.end()) to.push_back(std::move(text));
  }
}

}  // namespace

PreprocessedMimoData preprocess(const MimoData& data, const PreprocessingOptions& options) {
  const int n_u = data.input_count();
  const int n_y = data.output_count();
  const int channels = std::max(n_u, n_y);
  Eigen::MatrixXd inputs;
  Eigen::MatrixXd outputs;
  std::optional<Eigen::MatrixXd> references;
  PreprocessingRecord record;
  double start = 0.0;
  std::vector<std::string> warnings;
  Eigen::VectorXd input_offsets(n_u), input_slopes(n_u), output_offsets(n_y), output_slopes(n_y);
  // Pair c carries input min(c, n_u - 1) and output min(c, n_y - 1): every channel once.
  for (int c = 0; c < channels; ++c) {
    const int i = std::min(c, n_u - 1);
    const int j = std::min(c, n_y - 1);
    const PreprocessedData p = preprocess(data.channel(i, j), options);
    if (c == 0) {
      record = p.record;
      start = p.data.start_time();
      inputs.resize(p.data.size(), n_u);
      outputs.resize(p.data.size(), n_y);
      if (data.has_references()) references = Eigen::MatrixXd(p.data.size(), n_u);
    }
    if (c < n_u) {
      inputs.col(c) = p.data.input();
      if (references) references->col(c) = p.data.reference();
      input_offsets(c) = p.record.input_offset;
      input_slopes(c) = p.record.input_slope;
    }
    if (c < n_y) {
      outputs.col(c) = p.data.output();
      output_offsets(c) = p.record.output_offset;
      output_slopes(c) = p.record.output_slope;
    }
    add_warnings(p.record.warnings, data.input_names()[static_cast<std::size_t>(i)],
                 data.output_names()[static_cast<std::size_t>(j)], c < n_u, c < n_y, warnings);
  }
  record.warnings = std::move(warnings);
  MimoData out = MimoData(record.sample_time, std::move(inputs), std::move(outputs),
                          std::move(references), start)
                     .with_names(data.input_names(), data.output_names())
                     .with_input_hold(data.input_hold());
  return PreprocessedMimoData{
      std::move(out),          std::move(record),         std::move(input_offsets),
      std::move(input_slopes), std::move(output_offsets), std::move(output_slopes)};
}

PreprocessedOutputs preprocess_outputs(const Eigen::MatrixXd& outputs, double sample_time,
                                       double start_time, const PreprocessingOptions& options) {
  PreprocessedOutputs result;
  PreprocessingOptions own = options;
  own.input_scale = 1.0;  // each channel rides as its own input; only output_scale applies
  for (Eigen::Index j = 0; j < outputs.cols(); ++j) {
    const Eigen::VectorXd channel = outputs.col(j);
    for (Eigen::Index k = 0; k < channel.size(); ++k) {
      require(std::isfinite(channel(k)), "output channel ", j + 1, " is ", channel(k),
              " at sample ", k, "; every value must be finite");
    }
    const PreprocessedData p =
        preprocess(SampledData(sample_time, channel, channel, std::nullopt, start_time), own);
    if (j == 0) {
      result.outputs.resize(p.data.size(), outputs.cols());
      result.record = p.record;
      result.start_time = p.data.start_time();
    }
    result.outputs.col(j) = p.data.output();
  }
  result.record.input_offset = result.record.input_slope = 0.0;
  result.record.output_offset = result.record.output_slope = 0.0;
  result.record.warnings.clear();
  return result;
}

}  // namespace ctid
