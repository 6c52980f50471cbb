#include "ctid/frequency/mimo_frf.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <limits>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "ctid/core/error.h"
#include "frequency/internal/dft_blocks.h"

namespace ctid {
namespace {

using Complex = std::complex<double>;
using internal::dft;
using internal::line_frequency;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Beyond this condition number an input matrix counts as singular: H is not formed.
constexpr double kSingularCondition = 1e12;

// The DFTs of the columns of m[begin, begin + length), each times `window` when given.
Eigen::MatrixXcd column_spectra(Eigen::FFT<double>& fft, const Eigen::MatrixXd& m, int begin,
                                int length, const Eigen::VectorXd* window) {
  Eigen::MatrixXcd spectra(length, m.cols());
  for (Eigen::Index c = 0; c < m.cols(); ++c) {
    Eigen::VectorXd block = m.col(c).segment(begin, length);
    if (window != nullptr) block = block.cwiseProduct(*window);
    spectra.col(c) = dft(fft, block);
  }
  return spectra;
}

// Condition number of the Gram matrix g (Hermitian, >= 0) scaled to a unit diagonal: 1 for
// orthogonal rows, infinite for a zero row or a singular one.
double normalised_condition(const Eigen::MatrixXcd& g) {
  const Eigen::Index n = g.rows();
  if (n == 1) return g(0, 0).real() > 0.0 ? 1.0 : kInfinity;
  Eigen::VectorXd scale(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!(g(i, i).real() > 0.0)) return kInfinity;
    scale(i) = 1.0 / std::sqrt(g(i, i).real());
  }
  const Eigen::MatrixXcd c = scale.asDiagonal() * g * scale.asDiagonal();
  const Eigen::VectorXd eig = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>(c).eigenvalues();
  const double smallest = eig.minCoeff();
  const double largest = eig.maxCoeff();
  if (!(smallest > 0.0)) return kInfinity;
  return std::min(largest / smallest, kInfinity);
}

// The multiple coherence sum_j (S_yju S_uu^-1 S_uyj) / S_yjyj, clamped to [0, 1], and the
// power S_yjyj explains.
double multiple_coherence(const Eigen::RowVectorXcd& syu_j, const Eigen::MatrixXcd& suu_inverse,
                          double syy_j, double* explained) {
  *explained = (syu_j * suu_inverse * syu_j.adjoint())(0, 0).real();
  if (syy_j == 0.0) return 0.0;
  return std::clamp(*explained / syy_j, 0.0, 1.0);
}

MimoFrf empty_result(const MimoData& data, int averages, int block_length) {
  MimoFrf result;
  result.averages = averages;
  result.block_length = block_length;
  result.input_names = data.input_names();
  result.output_names = data.output_names();
  return result;
}

void resize(MimoFrf& result, Eigen::Index lines, int n_u, int n_y) {
  result.frequencies.resize(lines);
  result.response.assign(static_cast<std::size_t>(lines), Eigen::MatrixXcd(n_y, n_u));
  result.variance.assign(static_cast<std::size_t>(lines), Eigen::MatrixXd(n_y, n_u));
  result.coherence.resize(lines, n_y);
  result.output_power.resize(lines, n_y);
  result.input_level.resize(lines, n_u);
  result.input_condition.resize(lines);
}

}  // namespace

bool MimoFrf::inputs_correlated(int index, double max_condition) const {
  require(index >= 0 && index < input_condition.size(), "MimoFrf::inputs_correlated: index ", index,
          " is out of range [0, ", input_condition.size(), ")");
  return !(input_condition(index) <= max_condition);
}

Frf MimoFrf::channel(int input, int output) const {
  require(input >= 0 && input < input_count(), "MimoFrf::channel: input index ", input,
          " is out of range [0, ", input_count(), ")");
  require(output >= 0 && output < output_count(), "MimoFrf::channel: output index ", output,
          " is out of range [0, ", output_count(), ")");
  const auto count = static_cast<Eigen::Index>(lines.size());
  Frf frf;
  frf.lines = lines;
  frf.frequencies = frequencies;
  frf.response.resize(count);
  frf.variance.resize(count);
  for (Eigen::Index l = 0; l < count; ++l) {
    frf.response(l) = response[static_cast<std::size_t>(l)](output, input);
    frf.variance(l) = variance[static_cast<std::size_t>(l)](output, input);
  }
  if (coherence.rows() == count) frf.coherence = coherence.col(output);
  if (input_level.rows() == count) frf.input_level = input_level.col(input);
  frf.averages = averages;
  frf.block_length = block_length;
  return frf;
}

MimoFrf welch_frf(const MimoData& data, const WelchOptions& options) {
  options.validate();
  const int length = options.segment_length;
  const int total = data.size();
  require(total >= length, "welch_frf: too few samples: the record has ", total,
          " samples, fewer than WelchOptions.segment_length = ", length);
  const int step = internal::welch_step(length, options.overlap);
  const Eigen::VectorXd window = internal::periodic_hann(length);
  const int n_u = data.input_count();
  const int n_y = data.output_count();
  const int half = length / 2;

  // Sums over segments of U U^H, Y U^H and |Y_j|^2 at lines 0..L/2 (line 0 unused).
  std::vector<Eigen::MatrixXcd> suu(static_cast<std::size_t>(half + 1),
                                    Eigen::MatrixXcd::Zero(n_u, n_u));
  std::vector<Eigen::MatrixXcd> syu(static_cast<std::size_t>(half + 1),
                                    Eigen::MatrixXcd::Zero(n_y, n_u));
  Eigen::MatrixXd syy = Eigen::MatrixXd::Zero(half + 1, n_y);
  Eigen::FFT<double> fft;
  int segments = 0;
  for (int begin = 0; begin + length <= total; begin += step) {
    const Eigen::MatrixXcd u = column_spectra(fft, data.inputs(), begin, length, &window);
    const Eigen::MatrixXcd y = column_spectra(fft, data.outputs(), begin, length, &window);
    for (int k = 1; k <= half; ++k) {
      const auto q = static_cast<std::size_t>(k);
      suu[q] += u.row(k).transpose() * u.row(k).conjugate();
      syu[q] += y.row(k).transpose() * u.row(k).conjugate();
      syy.row(k) += y.row(k).cwiseAbs2();
    }
    ++segments;
  }

  MimoFrf result = empty_result(data, segments, length);
  resize(result, half, n_u, n_y);
  Eigen::VectorXd largest = Eigen::VectorXd::Zero(n_u);
  for (int k = 1; k <= half; ++k) {
    for (int i = 0; i < n_u; ++i) {
      largest(i) = std::max(largest(i), suu[static_cast<std::size_t>(k)](i, i).real());
    }
  }
  const int residual_dof = segments - n_u;
  for (int k = 1; k <= half; ++k) {
    const int l = k - 1;
    const auto q = static_cast<std::size_t>(k);
    result.lines.push_back(k);
    result.frequencies(l) = line_frequency(k, length, data.sample_time());
    for (int i = 0; i < n_u; ++i) {
      result.input_level(l, i) =
          largest(i) > 0.0 ? std::sqrt(suu[q](i, i).real() / largest(i)) : 0.0;
    }
    result.output_power.row(l) = syy.row(k) / segments;
    result.input_condition(l) = normalised_condition(suu[q]);
    Eigen::MatrixXcd& h = result.response[static_cast<std::size_t>(l)];
    Eigen::MatrixXd& var = result.variance[static_cast<std::size_t>(l)];
    if (!(result.input_condition(l) < kSingularCondition)) {
      h.setConstant(Complex(kNan, kNan));
      var.setConstant(kNan);
      result.coherence.row(l).setConstant(kNan);
      continue;
    }
    const Eigen::MatrixXcd suu_inverse = suu[q].inverse();
    h = syu[q] * suu_inverse;
    for (int j = 0; j < n_y; ++j) {
      double explained = 0.0;
      result.coherence(l, j) =
          multiple_coherence(syu[q].row(j), suu_inverse, syy(k, j), &explained);
      // The residual power of the regression of Y_j on the inputs over the segments, unbiased.
      const double sigma2 =
          residual_dof > 0 ? std::max(syy(k, j) - explained, 0.0) / residual_dof : kNan;
      for (int i = 0; i < n_u; ++i) var(j, i) = sigma2 * suu_inverse(i, i).real();
    }
  }
  return result;
}

namespace {

// periodic_frf's checks of the experiments (at least one per input, alike in channels, sample
// time and length, whole periods); the number of periods each holds after the transient.
int checked_periodic_experiments(const std::vector<MimoData>& experiments,
                                 const PeriodicFrfOptions& options) {
  require(!experiments.empty(), "periodic_frf: no experiment given");
  const MimoData& first = experiments.front();
  const int n_u = first.input_count();
  const int n_y = first.output_count();
  const auto n_e = static_cast<int>(experiments.size());
  const int n = options.period_length;
  require(n_e >= n_u, "periodic_frf: ", n_e, " experiment", n_e == 1 ? "" : "s", " for ", n_u,
          " inputs; the FRF matrix needs at least one experiment per input");
  for (int e = 0; e < n_e; ++e) {
    const MimoData& x = experiments[static_cast<std::size_t>(e)];
    require(x.input_count() == n_u && x.output_count() == n_y, "periodic_frf: experiment ", e + 1,
            " has ", x.input_count(), " inputs and ", x.output_count(),
            " outputs but experiment 1 has ", n_u, " and ", n_y);
    require(std::abs(x.sample_time() - first.sample_time()) <= 1e-9 * first.sample_time(),
            "periodic_frf: experiment ", e + 1, " has sample time ", x.sample_time(),
            " s but experiment 1 has ", first.sample_time(), " s");
    require(x.size() % n == 0, "periodic_frf: experiment ", e + 1, ": the record length ", x.size(),
            " is not a multiple of period_length ", n);
    require(x.size() == first.size(), "periodic_frf: experiment ", e + 1, " has ", x.size(),
            " samples but experiment 1 has ", first.size(), "; give each the same periods");
  }
  const int total = first.size();
  const int periods = total / n - options.transient_periods;
  require(periods >= 2, "periodic_frf: too few samples: ", total, " samples hold ", total / n,
          " periods of ", n, "; after dropping transient_periods = ", options.transient_periods,
          " at least 2 must remain");
  return periods;
}

}  // namespace

MimoFrf periodic_frf(const std::vector<MimoData>& experiments, const PeriodicFrfOptions& options) {
  options.validate();
  const int periods = checked_periodic_experiments(experiments, options);
  const MimoData& first = experiments.front();
  const int n_u = first.input_count();
  const int n_y = first.output_count();
  const auto n_e = static_cast<int>(experiments.size());
  const int n = options.period_length;

  // u[p][e]: N x n_u spectra of period p of experiment e; y likewise.
  Eigen::FFT<double> fft;
  std::vector<std::vector<Eigen::MatrixXcd>> u(static_cast<std::size_t>(periods));
  std::vector<std::vector<Eigen::MatrixXcd>> y(static_cast<std::size_t>(periods));
  std::vector<Eigen::MatrixXcd> u_mean(static_cast<std::size_t>(n_e),
                                       Eigen::MatrixXcd::Zero(n, n_u));
  for (int p = 0; p < periods; ++p) {
    const int begin = (options.transient_periods + p) * n;
    for (int e = 0; e < n_e; ++e) {
      const MimoData& x = experiments[static_cast<std::size_t>(e)];
      u[static_cast<std::size_t>(p)].push_back(column_spectra(fft, x.inputs(), begin, n, nullptr));
      y[static_cast<std::size_t>(p)].push_back(column_spectra(fft, x.outputs(), begin, n, nullptr));
      u_mean[static_cast<std::size_t>(e)] += u[static_cast<std::size_t>(p)].back();
    }
  }
  const int half = n / 2;
  // level(k, i): the largest |mean U_i(k)| over the experiments, over its largest line's.
  Eigen::MatrixXd level = Eigen::MatrixXd::Zero(half + 1, n_u);
  for (int e = 0; e < n_e; ++e) {
    const Eigen::MatrixXd a = (u_mean[static_cast<std::size_t>(e)] / periods).cwiseAbs();
    level = level.cwiseMax(a.topRows(half + 1));
  }
  for (int i = 0; i < n_u; ++i) {
    const double largest = level.col(i).tail(half).maxCoeff();
    require(largest > 0.0, "periodic_frf: input ", first.input_names()[static_cast<std::size_t>(i)],
            " has no power at any line 1..", half);
    level.col(i) /= largest;
  }
  // The input matrix of period p at line k, n_u x n_e, and the output one, n_y x n_e.
  const auto input_matrix = [&](int p, int k) {
    Eigen::MatrixXcd m(n_u, n_e);
    for (int e = 0; e < n_e; ++e) {
      m.col(e) = u[static_cast<std::size_t>(p)][static_cast<std::size_t>(e)].row(k).transpose();
    }
    return m;
  };
  const auto output_matrix = [&](int p, int k) {
    Eigen::MatrixXcd m(n_y, n_e);
    for (int e = 0; e < n_e; ++e) {
      m.col(e) = y[static_cast<std::size_t>(p)][static_cast<std::size_t>(e)].row(k).transpose();
    }
    return m;
  };
  const auto condition = [&](int k) {
    double worst = 1.0;
    for (int p = 0; p < periods; ++p) {
      const Eigen::MatrixXcd m = input_matrix(p, k);
      worst = std::max(worst, normalised_condition(m * m.adjoint()));
    }
    return std::sqrt(worst);  // of U, not of U U^H
  };
  const double threshold = options.line_threshold;
  const auto excited = [&](int k) {
    return level.row(k).minCoeff() > threshold && condition(k) < std::sqrt(kSingularCondition);
  };

  MimoFrf result = empty_result(first, periods, n);
  result.lines = internal::periodic_lines(options.lines, half, excited, [&](int k) {
    throw InvalidArgument(internal::concat(
        "periodic_frf: line ", k,
        " requested in PeriodicFrfOptions.lines is not excited by every input (smallest "
        "relative level ",
        level.row(k).minCoeff(), ", threshold ", threshold,
        ") or the inputs are dependent there (condition ", condition(k), ")"));
  });

  const auto count = static_cast<Eigen::Index>(result.lines.size());
  resize(result, count, n_u, n_y);
  for (Eigen::Index l = 0; l < count; ++l) {
    const int k = result.lines[static_cast<std::size_t>(l)];
    result.frequencies(l) = line_frequency(k, n, first.sample_time());
    result.input_level.row(l) = level.row(k);
    result.input_condition(l) = condition(k);
    std::vector<Eigen::MatrixXcd> per_period;
    Eigen::MatrixXcd suu = Eigen::MatrixXcd::Zero(n_u, n_u);
    Eigen::MatrixXcd syu = Eigen::MatrixXcd::Zero(n_y, n_u);
    Eigen::VectorXd syy = Eigen::VectorXd::Zero(n_y);
    for (int p = 0; p < periods; ++p) {
      const Eigen::MatrixXcd um = input_matrix(p, k);
      const Eigen::MatrixXcd ym = output_matrix(p, k);
      if (n_e == n_u) {
        per_period.push_back(ym * um.inverse());
      } else {
        per_period.push_back(ym * um.adjoint() * (um * um.adjoint()).inverse());
      }
      suu += um * um.adjoint();
      syu += ym * um.adjoint();
      syy += ym.rowwise().squaredNorm();
    }
    Eigen::MatrixXcd mean = Eigen::MatrixXcd::Zero(n_y, n_u);
    for (const auto& h : per_period) mean += h;
    mean /= periods;
    Eigen::MatrixXd spread = Eigen::MatrixXd::Zero(n_y, n_u);
    for (const auto& h : per_period) spread += (h - mean).cwiseAbs2();
    result.response[static_cast<std::size_t>(l)] = mean;
    // Sample variance over periods, divided by P for the variance of the mean.
    result.variance[static_cast<std::size_t>(l)] = spread / (periods - 1) / periods;
    const Eigen::MatrixXcd suu_inverse = suu.inverse();
    for (int j = 0; j < n_y; ++j) {
      double explained = 0.0;
      result.coherence(l, j) = multiple_coherence(syu.row(j), suu_inverse, syy(j), &explained);
    }
    result.output_power.row(l) = syy.transpose() / (periods * n_e);
  }
  return result;
}

MimoFrf periodic_frf(const MimoData& record, const PeriodicFrfOptions& options, int experiments) {
  require(experiments >= 1, "periodic_frf: experiments is ", experiments, "; it must be >= 1");
  require(record.size() % experiments == 0, "periodic_frf: the record's ", record.size(),
          " samples do not split into ", experiments, " experiments of equal length");
  const int length = record.size() / experiments;
  std::vector<MimoData> blocks;
  for (int e = 0; e < experiments; ++e) blocks.push_back(record.segment(e * length, length));
  return periodic_frf(blocks, options);
}

MimoFrf excited_lines(const MimoFrf& frf, double line_threshold) {
  require(line_threshold >= 0.0 && line_threshold < 1.0, "excited_lines: line_threshold is ",
          line_threshold, "; it must be in [0, 1)");
  const auto size = static_cast<Eigen::Index>(frf.lines.size());
  require(frf.frequencies.size() == size &&
              static_cast<Eigen::Index>(frf.response.size()) == size &&
              static_cast<Eigen::Index>(frf.variance.size()) == size,
          "excited_lines: the FRF's lines, frequencies, responses and variances differ in size");
  if (frf.input_level.rows() == 0) return frf;
  require(frf.input_level.rows() == size, "excited_lines: the FRF has ", size, " lines but ",
          frf.input_level.rows(), " input levels");
  std::vector<Eigen::Index> kept;
  for (Eigen::Index l = 0; l < size; ++l) {
    if (frf.input_level.row(l).minCoeff() > line_threshold) kept.push_back(l);
  }
  const auto count = static_cast<Eigen::Index>(kept.size());
  MimoFrf result = frf;
  result.lines.clear();
  result.response.clear();
  result.variance.clear();
  const auto rows = [&](const Eigen::MatrixXd& m) {
    Eigen::MatrixXd out(count, m.cols());
    if (m.rows() != size) return m;
    for (Eigen::Index j = 0; j < count; ++j) out.row(j) = m.row(kept[static_cast<std::size_t>(j)]);
    return out;
  };
  result.coherence = rows(frf.coherence);
  result.output_power = rows(frf.output_power);
  result.input_level = rows(frf.input_level);
  result.frequencies.resize(count);
  result.input_condition.resize(count);
  for (Eigen::Index j = 0; j < count; ++j) {
    const Eigen::Index l = kept[static_cast<std::size_t>(j)];
    const auto q = static_cast<std::size_t>(l);
    result.lines.push_back(frf.lines[q]);
    result.frequencies(j) = frf.frequencies(l);
    result.response.push_back(frf.response[q]);
    result.variance.push_back(frf.variance[q]);
    result.input_condition(j) = frf.input_condition.size() == size ? frf.input_condition(l) : kNan;
  }
  return result;
}

Frf summed_power_frf(const MimoFrf& frf) {
  const auto count = static_cast<Eigen::Index>(frf.lines.size());
  Frf result;
  result.lines = frf.lines;
  result.frequencies = frf.frequencies;
  result.averages = frf.averages;
  result.block_length = frf.block_length;
  result.response.resize(count);
  result.variance.resize(count);
  if (frf.coherence.rows() == count && frf.output_power.rows() == count) {
    result.coherence.resize(count);
  }
  if (frf.input_level.rows() == count) result.input_level.resize(count);
  for (Eigen::Index l = 0; l < count; ++l) {
    const auto q = static_cast<std::size_t>(l);
    result.response(l) = std::sqrt(frf.response[q].cwiseAbs2().sum());
    result.variance(l) = frf.variance[q].sum();
    if (result.coherence.size() > 0) {
      const double power = frf.output_power.row(l).sum();
      result.coherence(l) =
          power > 0.0 ? frf.coherence.row(l).dot(frf.output_power.row(l)) / power : 0.0;
    }
    if (result.input_level.size() > 0) result.input_level(l) = frf.input_level.row(l).minCoeff();
  }
  return result;
}

}  // namespace ctid
