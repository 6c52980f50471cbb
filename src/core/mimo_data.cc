#include "ctid/core/mimo_data.h"

#include <cmath>
#include <set>
#include <utility>

#include "core/internal/signal_range.h"
#include "ctid/core/error.h"

namespace ctid {

namespace {

void require_finite_channels(const Eigen::MatrixXd& m, const char* signal) {
  for (Eigen::Index j = 0; j < m.cols(); ++j) {
    for (Eigen::Index k = 0; k < m.rows(); ++k) {
      if (!std::isfinite(m(k, j))) {
        require(false, signal, " ", j + 1, " sample ", k, " is ", m(k, j),
                "; every sample must be finite");
      }
    }
    internal::require_magnitude_in_range(m.col(j),
                                         std::string(signal) + " " + std::to_string(j + 1));
  }
}

std::vector<std::string> numbered(const char* prefix, Eigen::Index count) {
  std::vector<std::string> names;
  for (Eigen::Index j = 1; j <= count; ++j) names.push_back(prefix + std::to_string(j));
  return names;
}

}  // namespace

MimoData::MimoData(double sample_time, Eigen::MatrixXd inputs, Eigen::MatrixXd outputs,
                   std::optional<Eigen::MatrixXd> references, double start_time)
    : sample_time_(sample_time),
      start_time_(start_time),
      inputs_(std::move(inputs)),
      outputs_(std::move(outputs)),
      references_(std::move(references)),
      input_names_(numbered("u", inputs_.cols())),
      output_names_(numbered("y", outputs_.cols())) {
  require(std::isfinite(sample_time_) && sample_time_ > 0.0, "sample time is ", sample_time_,
          " s; it must be finite and > 0");
  require(std::isfinite(start_time_), "start time must be finite");
  require(inputs_.cols() >= 1, "a record needs at least one input column; got none");
  require(outputs_.cols() >= 1, "a record needs at least one output column; got none");
  require(inputs_.rows() == outputs_.rows(), "inputs have ", inputs_.rows(),
          " samples but outputs have ", outputs_.rows(), "; they must have equal lengths");
  require(inputs_.rows() >= 2, "a record needs at least 2 samples; got ", inputs_.rows());
  if (references_) {
    require(references_->rows() == inputs_.rows(), "references have ", references_->rows(),
            " samples but inputs have ", inputs_.rows(), "; they must have equal lengths");
    require(references_->cols() == inputs_.cols(), "there are ", references_->cols(),
            " reference columns for ", inputs_.cols(), " inputs; give one per input");
    require_finite_channels(*references_, "reference");
  }
  require_finite_channels(inputs_, "input");
  require_finite_channels(outputs_, "output");
}

MimoData::MimoData(const SampledData& data)
    : MimoData(
          data.sample_time(), data.input(), data.output(),
          data.has_reference() ? std::optional<Eigen::MatrixXd>(data.reference()) : std::nullopt,
          data.start_time()) {
  input_hold_ = data.input_hold();
}

Eigen::VectorXd MimoData::time() const {
  return Eigen::VectorXd::LinSpaced(size(), 0.0, static_cast<double>(size() - 1)) * sample_time_ +
         Eigen::VectorXd::Constant(size(), start_time_);
}

const Eigen::MatrixXd& MimoData::references() const {
  require(references_.has_value(), "this record has no reference signals");
  return *references_;
}

MimoData MimoData::with_names(std::vector<std::string> input_names,
                              std::vector<std::string> output_names) const {
  require(static_cast<int>(input_names.size()) == input_count(), "there are ", input_names.size(),
          " input names for ", input_count(), " inputs");
  require(static_cast<int>(output_names.size()) == output_count(), "there are ",
          output_names.size(), " output names for ", output_count(), " outputs");
  std::set<std::string> seen;
  for (const auto* names : {&input_names, &output_names}) {
    for (const std::string& name : *names) {
      require(!name.empty(), "a channel name is empty");
      require(seen.insert(name).second, "channel '", name,
              "' is named twice; every input and output needs its own name");
    }
  }
  MimoData out = *this;
  out.input_names_ = std::move(input_names);
  out.output_names_ = std::move(output_names);
  return out;
}

MimoData MimoData::with_input_hold(Hold hold) const {
  MimoData out = *this;
  out.input_hold_ = hold;
  return out;
}

MimoData MimoData::segment(int begin, int count) const {
  require(begin >= 0 && count >= 2 && begin + count <= size(), "segment [", begin, ", ",
          begin + count, ") does not fit a record of ", size(), " samples (and needs >= 2)");
  MimoData out = *this;
  out.start_time_ = start_time_ + begin * sample_time_;
  out.inputs_ = inputs_.middleRows(begin, count);
  out.outputs_ = outputs_.middleRows(begin, count);
  if (references_) out.references_ = references_->middleRows(begin, count);
  return out;
}

SampledData MimoData::channel(int input, int output) const {
  require(input >= 0 && input < input_count(), "input index ", input, " is out of range [0, ",
          input_count(), ")");
  require(output >= 0 && output < output_count(), "output index ", output, " is out of range [0, ",
          output_count(), ")");
  std::optional<Eigen::VectorXd> r;
  if (references_) r = references_->col(input);
  return SampledData(sample_time_, inputs_.col(input), outputs_.col(output), std::move(r),
                     start_time_)
      .with_input_hold(input_hold_);
}

}  // namespace ctid
