#include "ctid/core/preprocessing.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <sstream>
#include <utility>

#include "ctid/core/error.h"
#include "ctid/core/format.h"

namespace ctid {

namespace {

struct Line {
  double offset = 0.0;
  double slope = 0.0;
};

// The removed line of x against t = k h (k from 0): its mean, or its least-squares line.
Line trend(const Eigen::VectorXd& x, double h, Detrend detrend) {
  Line line;
  if (detrend == Detrend::none) return line;
  const double n = static_cast<double>(x.size());
  if (detrend == Detrend::mean) {
    line.offset = x.mean();
    return line;
  }
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(x.size(), 0.0, n - 1.0) * h;
  const double t_mean = t.mean();
  const Eigen::VectorXd centred = t.array() - t_mean;
  line.slope = centred.dot(x) / centred.squaredNorm();
  line.offset = x.mean() - line.slope * t_mean;
  return line;
}

Eigen::VectorXd remove(const Eigen::VectorXd& x, double h, const Line& line) {
  const Eigen::VectorXd t =
      Eigen::VectorXd::LinSpaced(x.size(), 0.0, static_cast<double>(x.size() - 1)) * h;
  Eigen::VectorXd out = x.array() - line.offset - line.slope * t.array();
  return out;
}

Eigen::VectorXd keep_every(const Eigen::VectorXd& x, int factor) {
  const Eigen::Index n = (x.size() + factor - 1) / factor;
  Eigen::VectorXd out(n);
  for (Eigen::Index k = 0; k < n; ++k) out(k) = x(k * factor);
  return out;
}

void warn_large_mean(const Eigen::VectorXd& x, const char* name, double ratio,
                     std::vector<std::string>& warnings) {
  const double mean = x.mean();
  const double sd = std::sqrt((x.array() - mean).square().mean());
  // A constant signal is not warned about: removing its mean leaves nothing, and the command
  // that needs it to vary refuses it with one error that says so.
  if (sd > 0.0 && std::abs(mean) > ratio * sd) {
    warnings.push_back(internal::concat(name, " mean ", format_brief(mean), " is ",
                                        format_significant(std::abs(mean) / sd, 2),
                                        " x its standard deviation; consider removing it "
                                        "(detrend mean)"));
  }
}

}  // namespace

void PreprocessingOptions::check_relations(const std::string& path) const {
  require(!((first_row || end_row) && (start_time || end_time)), path,
          " has a row range and a time range; give one of them");
  if (first_row && end_row) {
    require(*first_row < *end_row, path, ".first_row is ", *first_row, " and ", path,
            ".end_row is ", *end_row, "; the row range is empty");
  }
  if (start_time && end_time) {
    require(*start_time < *end_time, path, ".start_time is ", *start_time, " and ", path,
            ".end_time is ", *end_time, "; the time range is empty");
  }
}

Eigen::VectorXd anti_alias_filter(const Eigen::VectorXd& x, int factor) {
  require(factor >= 1, "anti_alias_filter: factor is ", factor, "; it must be >= 1");
  if (factor == 1 || x.size() < 2) return x;
  const int half = 20 * factor;
  const double cutoff = 0.45 / factor;  // cycles per sample: 0.9 of the new Nyquist frequency
  Eigen::VectorXd taps(2 * half + 1);
  for (int j = -half; j <= half; ++j) {
    const double sinc = j == 0 ? 2.0 * cutoff
                               : std::sin(2.0 * std::numbers::pi * cutoff * j) /
                                     (std::numbers::pi * static_cast<double>(j));
    const double window = 0.54 + 0.46 * std::cos(std::numbers::pi * j / half);
    taps(j + half) = sinc * window;
  }
  taps /= taps.sum();
  const Eigen::Index n = x.size();
  // Odd reflection about the end samples keeps a trend continuous through the ends.
  const auto at = [&](Eigen::Index i) {
    if (i < 0) return 2.0 * x(0) - x(std::min(-i, n - 1));
    if (i >= n) return 2.0 * x(n - 1) - x(std::max(n - 1 - (i - (n - 1)), Eigen::Index{0}));
    return x(i);
  };
  Eigen::VectorXd y(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    double sum = 0.0;
    if (k >= half && k + half < n) {
      sum = taps.dot(x.segment(k - half, 2 * half + 1));
    } else {
      for (int j = -half; j <= half; ++j) sum += taps(j + half) * at(k + j);
    }
    y(k) = sum;
  }
  return y;
}

SampledData remove_trend(const SampledData& data, const PreprocessingRecord& trend) {
  const double h = data.sample_time();
  const Eigen::VectorXd u = remove(data.input(), h, {trend.input_offset, trend.input_slope});
  const Eigen::VectorXd y = remove(data.output(), h, {trend.output_offset, trend.output_slope});
  std::optional<Eigen::VectorXd> r;
  if (data.has_reference()) {
    r = remove(data.reference(), h, {trend.reference_offset, trend.reference_slope});
  }
  return SampledData(h, u, y, r, data.start_time()).with_input_hold(data.input_hold());
}

Eigen::VectorXd add_output_trend(const Eigen::VectorXd& output, double h,
                                 const PreprocessingRecord& trend) {
  return remove(output, h, {-trend.output_offset, -trend.output_slope});
}

PreprocessedData preprocess(const SampledData& data, const PreprocessingOptions& options) {
  options.validate();
  const int n = data.size();
  const double h = data.sample_time();
  PreprocessingRecord record;
  record.end_row = n;
  std::string range = "the record";
  if (options.first_row || options.end_row) {
    record.first_row = options.first_row.value_or(0);
    record.end_row = options.end_row.value_or(n);
    require(record.first_row < n && record.end_row <= n, "rows ", record.first_row, ":",
            record.end_row, " lie outside the record's ", n, " rows (0:", n, ")");
    range = internal::concat("rows ", record.first_row, ":", record.end_row);
  } else if (options.start_time || options.end_time) {
    const double slack = 1e-9 * h;
    const double t0 = data.start_time();
    const double start = options.start_time.value_or(t0);
    const double end = options.end_time.value_or(t0 + n * h);
    // Clamped in double before the cast: a time far outside the record (2e8 s, 1e300 s) is
    // beyond int's range, and casting it first would be undefined.
    const auto row_at = [&](double t) {
      const double row = std::ceil((t - t0 - slack) / h);
      return static_cast<int>(std::clamp(row, 0.0, static_cast<double>(n)));
    };
    record.first_row = row_at(start);
    record.end_row = row_at(end);
    range = internal::concat("time ", format_number(start), ":", format_number(end), " s");
    require(record.end_row > record.first_row, range, " keeps no sample of the record from ",
            format_number(t0), " to ", format_number(t0 + (n - 1) * h), " s");
  }
  const int kept = record.end_row - record.first_row;
  const int needed = options.detrend == Detrend::linear ? 3 : 2;
  if (kept < needed) {
    throw InvalidArgument(internal::concat(
        range, " keep", kept == 1 ? "s " : " ", kept, " sample", kept == 1 ? "" : "s",
        options.detrend == Detrend::none
            ? "; a record needs at least 2"
            : internal::concat("; detrend ", enum_name(options.detrend), " needs at least ",
                               needed)));
  }
  const int count_after = (kept + options.decimate - 1) / options.decimate;
  require(count_after >= 2, "decimate ", options.decimate, " leaves ", count_after,
          " sample of the ", kept, " kept; a record needs at least 2");

  Eigen::VectorXd u = data.input().segment(record.first_row, kept);
  Eigen::VectorXd y = data.output().segment(record.first_row, kept);
  std::optional<Eigen::VectorXd> r;
  if (data.has_reference()) r = data.reference().segment(record.first_row, kept);

  record.detrend = options.detrend;
  if (options.detrend == Detrend::none) {
    warn_large_mean(u, "input", options.large_mean_ratio, record.warnings);
    warn_large_mean(y, "output", options.large_mean_ratio, record.warnings);
  } else {
    const Line lu = trend(u, h, options.detrend);
    const Line ly = trend(y, h, options.detrend);
    u = remove(u, h, lu);
    y = remove(y, h, ly);
    record.input_offset = lu.offset;
    record.input_slope = lu.slope;
    record.output_offset = ly.offset;
    record.output_slope = ly.slope;
    if (r) {
      const Line lr = trend(*r, h, options.detrend);
      r = remove(*r, h, lr);
      record.reference_offset = lr.offset;
      record.reference_slope = lr.slope;
    }
  }

  record.decimate = options.decimate;
  if (options.decimate > 1) {
    u = keep_every(anti_alias_filter(u, options.decimate), options.decimate);
    y = keep_every(anti_alias_filter(y, options.decimate), options.decimate);
    if (r) r = keep_every(anti_alias_filter(*r, options.decimate), options.decimate);
    if (data.input_hold() == Hold::zero_order_hold) {
      record.warnings.push_back(
          "the anti-alias filter smooths the input, which is no longer held between the new "
          "samples; a first-order hold may describe it better");
    }
  }

  record.input_scale = options.input_scale;
  record.output_scale = options.output_scale;
  u *= options.input_scale;
  y *= options.output_scale;
  if (r) *r *= options.output_scale;

  const double new_h = h * options.decimate;
  const double start = data.start_time() + record.first_row * h;
  SampledData out(new_h, std::move(u), std::move(y), std::move(r), start);
  SampledData held = std::move(out).with_input_hold(data.input_hold());
  record.samples = held.size();
  record.sample_time = new_h;
  return PreprocessedData{std::move(held), std::move(record)};
}

std::string PreprocessingRecord::summary() const {
  std::ostringstream out;
  out << "rows " << first_row << ":" << end_row;
  if (detrend == Detrend::mean) {
    out << ", means removed (u " << format_brief(input_offset) << ", y "
        << format_brief(output_offset) << ")";
  } else if (detrend == Detrend::linear) {
    out << ", lines removed (u " << format_brief(input_offset) << " + " << format_brief(input_slope)
        << " t, y " << format_brief(output_offset) << " + " << format_brief(output_slope) << " t)";
  } else {
    out << ", no detrend";
  }
  if (decimate > 1) out << ", decimated by " << decimate;
  if (input_scale != 1.0) out << ", u scaled by " << format_brief(input_scale);
  if (output_scale != 1.0) out << ", y scaled by " << format_brief(output_scale);
  out << ", N = " << samples << ", h = " << format_number(sample_time) << " s";
  return out.str();
}

SampledData resample(const Eigen::VectorXd& time, const Eigen::VectorXd& input,
                     const Eigen::VectorXd& output, const std::optional<Eigen::VectorXd>& reference,
                     double h, Hold input_hold) {
  const Eigen::Index n = time.size();
  require(input.size() == n && output.size() == n && (!reference || reference->size() == n),
          "resample: the time stamps (", n, "), input (", input.size(), "), output (",
          output.size(), ")", reference ? " and reference" : "", " differ in length");
  require(std::isfinite(h) && h > 0.0, "resample: the sample time is ", h,
          "; it must be positive and finite");
  require(n >= 2, "resample: ", n, " time stamps; at least 2 are needed");
  for (Eigen::Index k = 0; k < n; ++k) {
    require(std::isfinite(time(k)), "resample: time stamp ", k, " is not finite");
  }
  for (Eigen::Index k = 1; k < n; ++k) {  // (require evaluates its message parts)
    require(time(k) > time(k - 1), "resample: time stamp ", k, " (", time(k),
            " s) is not after the one before it (", time(k - 1), " s)");
  }
  const double t0 = time(0);
  const double steps = std::floor((time(n - 1) - t0) / h * (1.0 + 1e-12)) + 1.0;
  require(steps <= kMaxRecordSamples, "resample: a step of ", h, " s over the stamps' ",
          time(n - 1) - t0, " s makes ", steps, " samples; ctid builds records of at most ",
          kMaxRecordSamples, " samples (choose a longer step)");
  const auto count = static_cast<Eigen::Index>(steps);
  require(count >= 2, "resample: the stamps span ", time(n - 1) - t0, " s, less than one step of ",
          h, " s");
  Eigen::VectorXd u(count);
  Eigen::VectorXd y(count);
  std::optional<Eigen::VectorXd> r;
  if (reference) r.emplace(count);
  Eigen::Index j = 0;  // time(j) <= t < time(j + 1)
  for (Eigen::Index k = 0; k < count; ++k) {
    const double t = std::min(t0 + static_cast<double>(k) * h, time(n - 1));
    while (j + 2 < n && time(j + 1) <= t) ++j;
    const double span = time(j + 1) - time(j);
    const double s = std::clamp((t - time(j)) / span, 0.0, 1.0);
    auto linear = [&](const Eigen::VectorXd& x) { return (1.0 - s) * x(j) + s * x(j + 1); };
    // A held input changes only at a stamp: the value at t is the last sample at or before t.
    u(k) =
        input_hold == Hold::first_order_hold ? linear(input) : (s >= 1.0 ? input(j + 1) : input(j));
    y(k) = linear(output);
    if (r) (*r)(k) = linear(*reference);
  }
  return SampledData(h, u, y, r, t0).with_input_hold(input_hold);
}

}  // namespace ctid
