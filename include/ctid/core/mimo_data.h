// A uniformly sampled record with several inputs and several outputs: inputs u_k (n_u
// columns), outputs y_k (n_y columns) and optionally the references r_k of a closed-loop
// experiment (n_u columns), at t_k = t_0 + k h, k = 0..N-1, each channel with a name.
// SampledData is the one-input, one-output record every SISO estimator takes; channel()
// takes one pair out of this one, and MimoData(SampledData) makes a SISO record a 1 x 1 one.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/hold.h"
#include "ctid/core/sampled_data.h"

namespace ctid {

class MimoData {
 public:
  /// inputs: N x n_u, outputs: N x n_y, references: N x n_u. Throws InvalidArgument for a
  /// non-positive or non-finite sample time, unequal lengths, fewer than 2 samples, no input
  /// or output column, or a non-finite value (naming the signal, the channel and the index).
  /// Channels are named u1..u{n_u}, y1..y{n_y} until with_names() names them.
  MimoData(double sample_time, Eigen::MatrixXd inputs, Eigen::MatrixXd outputs,
           std::optional<Eigen::MatrixXd> references = std::nullopt, double start_time = 0.0);
  /// The SISO record as a 1 x 1 one (names u1, y1; the input hold is kept).
  explicit MimoData(const SampledData& data);

  int size() const { return static_cast<int>(inputs_.rows()); }
  int input_count() const { return static_cast<int>(inputs_.cols()); }
  int output_count() const { return static_cast<int>(outputs_.cols()); }
  double sample_time() const { return sample_time_; }
  double start_time() const { return start_time_; }
  Eigen::VectorXd time() const;
  const Eigen::MatrixXd& inputs() const { return inputs_; }    ///< N x n_u
  const Eigen::MatrixXd& outputs() const { return outputs_; }  ///< N x n_y
  bool has_references() const { return references_.has_value(); }
  /// N x n_u; throws InvalidArgument if there are none.
  const Eigen::MatrixXd& references() const;

  const std::vector<std::string>& input_names() const { return input_names_; }
  const std::vector<std::string>& output_names() const { return output_names_; }
  /// The same record with its channels named; throws InvalidArgument for a wrong count, an
  /// empty name or a name used twice (among inputs and outputs together).
  MimoData with_names(std::vector<std::string> input_names,
                      std::vector<std::string> output_names) const;

  /// How every input is continued between samples (zero-order hold by default).
  Hold input_hold() const { return input_hold_; }
  MimoData with_input_hold(Hold hold) const;

  /// Samples [begin, begin + count), names and hold kept.
  MimoData segment(int begin, int count) const;
  /// Input `input`, output `output` (and that input's reference) as a SISO record.
  SampledData channel(int input, int output) const;

 private:
  double sample_time_;
  double start_time_;
  Eigen::MatrixXd inputs_;
  Eigen::MatrixXd outputs_;
  std::optional<Eigen::MatrixXd> references_;
  std::vector<std::string> input_names_;
  std::vector<std::string> output_names_;
  Hold input_hold_ = Hold::zero_order_hold;
};

}  // namespace ctid
