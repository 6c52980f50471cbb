#include "ctid/core/sampled_data.h"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "core/internal/signal_range.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"

namespace ctid {

namespace {

void require_finite_signal(const Eigen::VectorXd& v, const char* name) {
  for (Eigen::Index k = 0; k < v.size(); ++k) {
    require(std::isfinite(v(k)), name, " sample ", k, " is ", v(k),
            "; every sample must be finite");
  }
}

// The fewest significant digits (1..17) whose decimal text reads back as x: how many digits
// x was printed with, trailing zeros aside.
// Whether x rounded to `digits` significant digits reads back as x. std::to_chars rounds
// the exact binary value as printf("%.*e") does, and from_chars as strtod does, at a
// fraction of their cost (this runs once per time stamp).
bool reads_back(double x, int digits) {
  char buffer[40];
  const auto printed =
      std::to_chars(buffer, buffer + sizeof buffer, x, std::chars_format::scientific, digits - 1);
  double back = 0.0;
  const auto read = std::from_chars(buffer, printed.ptr, back);
  return read.ec == std::errc() && back == x;
}

int significant_digits(double x) {
  if (x == 0.0) return 1;
  for (int digits = 1; digits < 17; ++digits) {
    if (reads_back(x, digits)) return digits;
  }
  return 17;
}

}  // namespace

SampledData::SampledData(double sample_time, Eigen::VectorXd input, Eigen::VectorXd output,
                         std::optional<Eigen::VectorXd> reference, double start_time)
    : sample_time_(sample_time),
      start_time_(start_time),
      input_(std::move(input)),
      output_(std::move(output)),
      reference_(std::move(reference)) {
  require(std::isfinite(sample_time_) && sample_time_ > 0.0, "sample time is ", sample_time_,
          " s; it must be finite and > 0");
  require(std::isfinite(start_time_), "start time must be finite");
  require(input_.size() == output_.size(), "input has ", input_.size(), " samples but output has ",
          output_.size(), "; they must have equal lengths");
  require(input_.size() >= 2, "a record needs at least 2 samples; got ", input_.size());
  if (reference_) {
    require(reference_->size() == input_.size(), "reference has ", reference_->size(),
            " samples but input has ", input_.size(), "; they must have equal lengths");
    require_finite_signal(*reference_, "reference");
    internal::require_magnitude_in_range(*reference_, "the reference");
  }
  require_finite_signal(input_, "input");
  require_finite_signal(output_, "output");
  internal::require_magnitude_in_range(input_, "the input");
  internal::require_magnitude_in_range(output_, "the output");
}

SampledData SampledData::from_time_stamps(const Eigen::VectorXd& time, Eigen::VectorXd input,
                                          Eigen::VectorXd output,
                                          std::optional<Eigen::VectorXd> reference,
                                          double relative_tolerance) {
  require(time.size() == input.size(), "time has ", time.size(), " samples but input has ",
          input.size(), "; they must have equal lengths");
  const UniformGrid grid = uniform_grid(time, relative_tolerance);
  return SampledData(grid.sample_time, std::move(input), std::move(output), std::move(reference),
                     grid.start_time);
}

UniformGrid uniform_grid(const Eigen::VectorXd& time, double relative_tolerance) {
  require(time.size() >= 2, "a record needs at least 2 samples; got ", time.size());
  require_finite_signal(time, "time");
  internal::require_magnitude_in_range(time, "time");
  const TimeStampCheck check = check_time_stamps(time, relative_tolerance);
  if (check.worst_sample) {
    const Eigen::Index k = *check.worst_sample;
    require(false, "time stamps are not uniform: sample ", k, " (t = ", format_number(time(k)),
            " s) is ", format_brief(check.deviation),
            " s off the grid t_0 + k h, with h = ", format_number(check.step),
            " s from the first and last stamps; stamps printed to ", check.digits,
            " significant digits allow ", format_brief(check.tolerance), " s");
  }
  require(std::isfinite(check.step), "sample time is ", check.step,
          " s; it must be finite and > 0");
  return UniformGrid{time(0), check.step};
}

TimeStampCheck check_time_stamps(const Eigen::VectorXd& time, double relative_tolerance) {
  require(time.size() >= 2, "a record needs at least 2 samples; got ", time.size());
  const Eigen::Index n = time.size();
  TimeStampCheck check;
  check.step = (time(n - 1) - time(0)) / static_cast<double>(n - 1);
  require(check.step > 0.0, "time stamps must increase; first ", time(0), " s, last ", time(n - 1),
          " s");
  double largest = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    // Only the largest count matters: a stamp that reads back at the count so far cannot
    // raise it, and at 17 nothing can (one conversion per stamp instead of up to 16).
    if (check.digits < 17 && !reads_back(time(k), check.digits)) {
      check.digits = std::max(check.digits, significant_digits(time(k)));
    }
    largest = std::max(largest, std::abs(time(k)));
  }
  // One unit in the last printed digit of the largest stamp: half a unit of rounding on the
  // stamp itself plus at most half a unit carried into the grid by the two end stamps.
  const double unit =
      largest > 0.0 ? std::pow(10.0, std::floor(std::log10(largest)) - check.digits + 1) : 0.0;
  check.tolerance =
      std::max(relative_tolerance * check.step, std::min(unit, kMaxGridDeviation * check.step));
  for (Eigen::Index k = 1; k < n; ++k) {
    const double deviation = std::abs(time(k) - time(0) - static_cast<double>(k) * check.step);
    if (deviation > check.tolerance && deviation > check.deviation) {
      check.deviation = deviation;
      check.worst_sample = static_cast<int>(k);
    }
  }
  return check;
}

Eigen::VectorXd SampledData::time() const {
  return Eigen::VectorXd::LinSpaced(size(), 0.0, static_cast<double>(size() - 1)) * sample_time_ +
         Eigen::VectorXd::Constant(size(), start_time_);
}

const Eigen::VectorXd& SampledData::reference() const {
  require(reference_.has_value(), "this record has no reference signal");
  return *reference_;
}

SampledData SampledData::segment(int begin, int count) const {
  require(begin >= 0 && count >= 2 && begin + count <= size(), "segment [", begin, ", ",
          begin + count, ") does not fit a record of ", size(), " samples (and needs >= 2)");
  std::optional<Eigen::VectorXd> r;
  if (reference_) r = reference_->segment(begin, count);
  SampledData out(sample_time_, input_.segment(begin, count), output_.segment(begin, count),
                  std::move(r), start_time_ + begin * sample_time_);
  out.input_hold_ = input_hold_;
  return out;
}

SampledData SampledData::with_input_hold(Hold hold) const& {
  SampledData out = *this;
  out.input_hold_ = hold;
  return out;
}

SampledData SampledData::with_input_hold(Hold hold) && {
  input_hold_ = hold;
  return std::move(*this);
}

}  // namespace ctid
