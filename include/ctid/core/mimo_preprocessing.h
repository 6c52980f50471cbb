// Preprocessing of a record with several inputs and outputs: the steps of preprocess()
// (core/preprocessing.h: range, detrend, decimation behind the anti-alias filter, scaling)
// applied to every channel alike, each input and its reference with input_scale, each output
// with output_scale, so that a MIMO record and each of its channel() records agree.
#pragma once

#include <Eigen/Core>

#include "ctid/core/mimo_data.h"
#include "ctid/core/preprocessing.h"

namespace ctid {

struct PreprocessedMimoData {
  MimoData data;
  /// What was done (rows, decimation, scales, samples, sample time, warnings naming the
  /// channel); its offset and slope fields are those of the first input, output and reference.
  PreprocessingRecord record;
  /// The line a + b (t - t_first) removed from each channel (zeros for detrend none; slopes
  /// zero for detrend mean), in the units of the original record.
  Eigen::VectorXd input_offsets;
  Eigen::VectorXd input_slopes;  ///< [1/s]
  Eigen::VectorXd output_offsets;
  Eigen::VectorXd output_slopes;  ///< [1/s]
};

/// Throws InvalidArgument as preprocess(SampledData) does.
PreprocessedMimoData preprocess(const MimoData& data, const PreprocessingOptions& options = {});

/// An output-only record (oma) after the same steps: range, detrend, decimation behind the
/// anti-alias filter and output_scale, on every column alike. The record's input fields stay
/// at their defaults and it carries no warnings: oma removes each channel's mean itself, so
/// the large-mean advice does not apply.
struct PreprocessedOutputs {
  Eigen::MatrixXd outputs;
  PreprocessingRecord record;
  double start_time = 0.0;  ///< the first kept time stamp [s]
};
/// Throws InvalidArgument as preprocess(SampledData) does, naming the channel for a value.
PreprocessedOutputs preprocess_outputs(const Eigen::MatrixXd& outputs, double sample_time,
                                       double start_time, const PreprocessingOptions& options = {});

}  // namespace ctid
