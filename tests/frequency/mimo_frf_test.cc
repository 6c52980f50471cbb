// MIMO FRFs against closed forms: the SISO estimates as the 1 x 1 case, a noise-free two-input,
// three-output system (per-channel models summed) recovered line by line, the multiple
// coherence's theoretical value under white output noise, and a seeded Monte Carlo check of
// the stated variance.
#include "ctid/frequency/mimo_frf.h"

#include <cmath>
#include <complex>
#include <functional>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <Eigen/LU>

#include "ctid/core/error.h"
#include "ctid/core/transfer_function.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"

namespace ctid::mimo_frf_test {
namespace {

using Complex = std::complex<double>;
using ::testing::HasSubstr;

constexpr double kH = 0.05;

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

// C (zI - A)^-1 B + D at z = e^{j w h}: the response from u_k to y_k of the ZOH-sampled model.
Complex zoh_response(const TransferFunction& g, double omega) {
  const StateSpace d = zoh_equivalent(g, kH);
  const Complex z = std::exp(Complex(0.0, omega * kH));
  const Eigen::MatrixXcd lhs =
      z * Eigen::MatrixXcd::Identity(d.order(), d.order()) - d.a.cast<Complex>();
  const Eigen::VectorXcd x = lhs.partialPivLu().solve(d.b.cast<Complex>());
  return (d.c.cast<Complex>() * x)(0) + d.d;
}

// G_ji of a two-input, three-output system: well damped modes (transients short beside a
// segment, so that Welch's leakage is small) and one first-order channel.
std::vector<std::vector<TransferFunction>> system_2x3() {
  const auto mode = [](double gain, double wn, double zeta) {
    return TransferFunction(Polynomial{gain * wn * wn}, Polynomial{wn * wn, 2 * zeta * wn, 1.0});
  };
  const TransferFunction lag(Polynomial{2.0}, Polynomial{1.0, 1.0});
  return {{mode(1.0, 2.0, 0.5), mode(-0.5, 4.0, 0.4)},
          {lag, mode(0.8, 3.0, 0.6)},
          {mode(0.3, 5.0, 0.5), lag}};
}

// Outputs y_j = sum_i G_ji u_i (+ white noise of standard deviation `noise`, seeded).
Eigen::MatrixXd outputs_of(const std::vector<std::vector<TransferFunction>>& g,
                           const Eigen::MatrixXd& u, double noise, std::uint64_t seed) {
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(u.rows(), static_cast<Eigen::Index>(g.size()));
  for (std::size_t j = 0; j < g.size(); ++j) {
    for (std::size_t i = 0; i < g[j].size(); ++i) {
      y.col(static_cast<Eigen::Index>(j)) +=
          simulate(g[j][i], u.col(static_cast<Eigen::Index>(i)).eval(), kH);
    }
    if (noise > 0.0) {
      y.col(static_cast<Eigen::Index>(j)) +=
          white_noise(static_cast<int>(u.rows()), noise, seed + 1000 + j);
    }
  }
  return y;
}

Eigen::MatrixXd white_inputs(int samples, int count, std::uint64_t seed) {
  Eigen::MatrixXd u(samples, count);
  for (int i = 0; i < count; ++i) u.col(i) = white_noise(samples, 1.0, seed + i);
  return u;
}

TEST(MimoWelchFrf, OneByOneIsTheSisoEstimate) {
  const Eigen::VectorXd u = white_noise(8192, 1.0, 3);
  const TransferFunction g(Polynomial{4.0}, Polynomial{4.0, 0.8, 1.0});
  const Eigen::VectorXd y = simulate(g, u, kH) + white_noise(8192, 0.3, 4);
  const SampledData siso(kH, u, y);
  WelchOptions options;
  options.segment_length = 512;
  const Frf expected = welch_frf(siso, options);
  const MimoFrf mimo = welch_frf(MimoData(siso), options);
  ASSERT_EQ(mimo.lines, expected.lines);
  EXPECT_EQ(mimo.averages, expected.averages);
  const Frf got = mimo.channel(0, 0);
  const double m = expected.averages;
  for (Eigen::Index l = 0; l < got.response.size(); ++l) {
    EXPECT_NEAR(std::abs(got.response(l) - expected.response(l)), 0.0,
                1e-12 * std::abs(expected.response(l)));
    EXPECT_NEAR(got.coherence(l), expected.coherence(l), 1e-12);
    EXPECT_NEAR(got.input_level(l), expected.input_level(l), 1e-12);
    EXPECT_DOUBLE_EQ(got.frequencies(l), expected.frequencies(l));
    // The MIMO variance divides the residual by M - n_u (unbiased), the SISO one by M.
    EXPECT_NEAR(got.variance(l), expected.variance(l) * m / (m - 1), 1e-9 * expected.variance(l));
  }
  EXPECT_EQ(mimo.input_condition.maxCoeff(), 1.0);
}

TEST(MimoPeriodicFrf, OneByOneIsTheSisoEstimate) {
  MultisineOptions ms;
  ms.period_length = 256;
  ms.sample_time = kH;
  ms.max_frequency = 4.0;
  ms.periods = 5;
  ms.seed = 8;
  const Eigen::VectorXd u = multisine(ms).signal;
  const TransferFunction g(Polynomial{4.0}, Polynomial{4.0, 0.8, 1.0});
  const Eigen::VectorXd y = simulate(g, u, kH) + white_noise(u.size(), 0.05, 9);
  const SampledData siso(kH, u, y);
  PeriodicFrfOptions options;
  options.period_length = 256;
  const Frf expected = periodic_frf(siso, options);
  const Frf got = periodic_frf(std::vector<MimoData>{MimoData(siso)}, options).channel(0, 0);
  ASSERT_EQ(got.lines, expected.lines);
  for (Eigen::Index l = 0; l < got.response.size(); ++l) {
    EXPECT_NEAR(std::abs(got.response(l) - expected.response(l)), 0.0,
                1e-12 * std::abs(expected.response(l)));
    EXPECT_NEAR(got.variance(l), expected.variance(l), 1e-9 * expected.variance(l));
    EXPECT_NEAR(got.coherence(l), expected.coherence(l), 1e-12);
    EXPECT_NEAR(got.input_level(l), expected.input_level(l), 1e-12);
  }
}

TEST(MimoWelchFrf, NoiseFreeTwoInputsThreeOutputsRecoverEveryChannel) {
  const auto g = system_2x3();
  const Eigen::MatrixXd u = white_inputs(262144, 2, 21);
  const MimoData data(kH, u, outputs_of(g, u, 0.0, 0));
  WelchOptions options;
  options.segment_length = 4096;  // 205 s, against transients of a few seconds
  const MimoFrf frf = welch_frf(data, options);
  ASSERT_EQ(frf.response.front().rows(), 3);
  ASSERT_EQ(frf.response.front().cols(), 2);
  EXPECT_EQ(frf.output_names, (std::vector<std::string>{"y1", "y2", "y3"}));
  double worst = 0.0;
  double mean_error = 0.0;
  int entries = 0;
  for (std::size_t l = 0; l < frf.lines.size(); ++l) {
    const double w = frf.frequencies(static_cast<Eigen::Index>(l));
    if (w > 20.0) break;  // the band where every channel has gain
    for (int j = 0; j < 3; ++j) {
      for (int i = 0; i < 2; ++i) {
        const Complex truth =
            zoh_response(g[static_cast<std::size_t>(j)][static_cast<std::size_t>(i)], w);
        const double error = std::abs(frf.response[l](j, i) - truth) / std::abs(truth);
        worst = std::max(worst, error);
        mean_error += error;
        ++entries;
      }
    }
  }
  // What is left is the leakage of the transients at the segment edges, which a random input
  // turns into noise of relative size ~ sqrt(transient / segment), averaged over 127 segments.
  EXPECT_LT(worst, 3e-2);
  EXPECT_LT(mean_error / entries, 2e-3);  // 6.5e-4 measured
  // Noise-free, the outputs are linear in the inputs: multiple coherence 1 (up to leakage),
  // and independent white inputs are far from correlated.
  EXPECT_GT(frf.coherence.topRows(800).minCoeff(), 1.0 - 1e-3);
  EXPECT_LT(frf.input_condition.maxCoeff(), 2.0);
  EXPECT_FALSE(frf.inputs_correlated(5));
}

TEST(MimoWelchFrf, MultipleCoherenceMatchesItsTheoreticalValueUnderNoise) {
  const auto g = system_2x3();
  const double sigma = 0.7;
  const Eigen::MatrixXd u = white_inputs(262144, 2, 31);
  const MimoData data(kH, u, outputs_of(g, u, sigma, 32));
  WelchOptions options;
  options.segment_length = 512;
  const MimoFrf frf = welch_frf(data, options);
  // White unit inputs and white noise: gamma_j^2 = sum_i |G_ji|^2 / (sum_i |G_ji|^2 + sigma^2).
  // The estimate is biased up by about (1 - gamma^2) n_u / M; M ~ 1000 here.
  double worst = 0.0;
  int checked = 0;
  for (std::size_t l = 4; l < 160; ++l) {
    const double w = frf.frequencies(static_cast<Eigen::Index>(l));
    for (int j = 0; j < 3; ++j) {
      double power = 0.0;
      for (int i = 0; i < 2; ++i) {
        power +=
            std::norm(zoh_response(g[static_cast<std::size_t>(j)][static_cast<std::size_t>(i)], w));
      }
      const double theory = power / (power + sigma * sigma);
      worst = std::max(worst, std::abs(frf.coherence(static_cast<Eigen::Index>(l), j) - theory));
      ++checked;
    }
  }
  EXPECT_EQ(checked, 468);
  EXPECT_LT(worst, 0.05);
}

TEST(MimoWelchFrf, StatedVarianceMatchesTheMonteCarloSpread) {
  // Inputs fixed, output noise drawn anew in each of R runs; non-overlapping segments, so the
  // noise at a line is independent from segment to segment and the formula is exact given U.
  // The lowest lines are left out: there the leakage of the transients (the same in every run)
  // adds to the stated variance but not to the spread, so the statement is conservative.
  const auto g = system_2x3();
  const int runs = 200;
  const Eigen::MatrixXd u = white_inputs(256 * 24, 2, 41);
  WelchOptions options;
  options.segment_length = 256;
  options.overlap = 0.0;
  const Eigen::MatrixXd clean = outputs_of(g, u, 0.0, 0);
  const int first = 4;
  const int lines = 64;
  std::vector<Eigen::MatrixXcd> sum(lines, Eigen::MatrixXcd::Zero(3, 2));
  std::vector<Eigen::MatrixXd> sum2(lines, Eigen::MatrixXd::Zero(3, 2));
  std::vector<Eigen::MatrixXd> stated(lines, Eigen::MatrixXd::Zero(3, 2));
  for (int r = 0; r < runs; ++r) {
    Eigen::MatrixXd y = clean;
    for (int j = 0; j < 3; ++j)
      y.col(j) += white_noise(static_cast<int>(u.rows()), 1.0, 5000 + 10 * r + j);
    const MimoFrf frf = welch_frf(MimoData(kH, u, y), options);
    for (int l = 0; l < lines; ++l) {
      const auto q = static_cast<std::size_t>(l);
      sum[q] += frf.response[q];
      sum2[q] += frf.response[q].cwiseAbs2();
      stated[q] += frf.variance[q] / runs;
    }
  }
  double ratio_sum = 0.0;
  double lowest = 1e9;
  double highest = 0.0;
  for (int l = first; l < lines; ++l) {
    const auto q = static_cast<std::size_t>(l);
    const Eigen::MatrixXcd mean = sum[q] / runs;
    const Eigen::MatrixXd spread = (sum2[q] / runs - mean.cwiseAbs2()) * runs / (runs - 1.0);
    const Eigen::MatrixXd ratio = spread.cwiseQuotient(stated[q]);
    ratio_sum += ratio.sum();

    lowest = std::min(lowest, ratio.minCoeff());
    highest = std::max(highest, ratio.maxCoeff());
  }
  const double mean_ratio = ratio_sum / ((lines - first) * 6);
  // 360 entries of R = 200 runs: each ratio has a relative spread of about 1/sqrt(R) = 0.07.
  EXPECT_NEAR(mean_ratio, 1.0, 0.05);
  EXPECT_GT(lowest, 0.7);
  EXPECT_LT(highest, 1.4);
}

TEST(MimoWelchFrf, CorrelatedInputsAreFlagged) {
  Eigen::MatrixXd u = white_inputs(8192, 2, 51);
  u.col(1) = u.col(0) + 0.01 * u.col(1);
  const MimoData data(kH, u, u.col(0) * 2.0);
  const MimoFrf frf = welch_frf(data, WelchOptions{256, 0.5});
  // Squared coherence 1 - 1e-4 between the inputs: condition ~ 4e4 at every line.
  EXPECT_GT(frf.input_condition.minCoeff(), 1e3);
  EXPECT_TRUE(frf.inputs_correlated(10));
  // An input that is exactly the other: S_uu is singular, H is not formed.
  u.col(1) = u.col(0);
  const MimoFrf singular = welch_frf(MimoData(kH, u, u.col(0)), WelchOptions{256, 0.5});
  EXPECT_TRUE(std::isnan(singular.response[10](0, 0).real()));
  EXPECT_TRUE(singular.inputs_correlated(10));
}

TEST(MimoPeriodicFrf, HadamardMultisinesRecoverEveryChannelExactly) {
  // Two experiments: (s1, s2) then (s1, -s2), the rows of the 2 x 2 Hadamard matrix.
  const auto g = system_2x3();
  MultisineOptions ms;
  ms.period_length = 512;
  ms.sample_time = kH;
  ms.max_frequency = 3.0;
  ms.periods = 6;
  ms.seed = 61;
  const Multisine s1 = multisine(ms);
  ms.seed = 62;
  const Eigen::VectorXd s2 = multisine(ms).signal;
  std::vector<MimoData> experiments;
  Eigen::MatrixXd record_u(2 * s2.size(), 2);
  Eigen::MatrixXd record_y(2 * s2.size(), 3);
  for (int e = 0; e < 2; ++e) {
    Eigen::MatrixXd u(s2.size(), 2);
    u.col(0) = s1.signal;
    u.col(1) = (e == 0 ? 1.0 : -1.0) * s2;
    const Eigen::MatrixXd y = outputs_of(g, u, 0.0, 0);
    experiments.emplace_back(kH, u, y);
    record_u.middleRows(e * s2.size(), s2.size()) = u;
    record_y.middleRows(e * s2.size(), s2.size()) = y;
  }
  PeriodicFrfOptions options;
  options.period_length = 512;
  options.transient_periods = 2;  // 51 s: the slowest transient, e^{-t}, is below 1e-22
  const MimoFrf frf = periodic_frf(experiments, options);
  EXPECT_EQ(frf.lines, s1.lines);
  EXPECT_EQ(frf.averages, 4);
  double worst = 0.0;
  for (std::size_t l = 0; l < frf.lines.size(); ++l) {
    const double w = frf.frequencies(static_cast<Eigen::Index>(l));
    for (int j = 0; j < 3; ++j) {
      for (int i = 0; i < 2; ++i) {
        worst = std::max(
            worst,
            std::abs(frf.response[l](j, i) -
                     zoh_response(g[static_cast<std::size_t>(j)][static_cast<std::size_t>(i)], w)));
      }
    }
    EXPECT_LT(frf.variance[l].maxCoeff(), 1e-20);
  }
  EXPECT_LT(worst, 1e-10);
  EXPECT_GT(frf.coherence.minCoeff(), 1.0 - 1e-12);
  // Hadamard-phased inputs are orthogonal at every line.
  EXPECT_LT(frf.input_condition.maxCoeff(), 1.0 + 1e-9);
  // The same experiments one after another in one record.
  const MimoFrf joined = periodic_frf(MimoData(kH, record_u, record_y), options, 2);
  EXPECT_EQ(joined.response[7], frf.response[7]);
}

TEST(MimoPeriodicFrf, OrthogonalMultisinesForThreeInputsUseFourExperiments) {
  // Three inputs, two outputs: n_e = 4 > n_u = 3 experiments, H_p = Y_p U_p^+.
  const auto g = system_2x3();
  MultisineOptions ms;
  ms.period_length = 256;
  ms.sample_time = kH;
  ms.max_frequency = 3.0;
  ms.periods = 4;
  ms.seed = 81;
  const OrthogonalMultisines o = orthogonal_multisines(ms, 3);
  std::vector<MimoData> experiments;
  for (const Eigen::MatrixXd& u : o.experiments) {
    // Outputs 1 and 2 of system_2x3 from inputs 1, 2; input 3 drives output 2 through G_31.
    Eigen::MatrixXd y = outputs_of(g, u.leftCols(2), 0.0, 0).leftCols(2);
    y.col(1) += simulate(g[2][0], u.col(2).eval(), kH);
    experiments.emplace_back(kH, u, y);
  }
  PeriodicFrfOptions options;
  options.period_length = 256;
  options.transient_periods = 2;
  const MimoFrf frf = periodic_frf(experiments, options);
  EXPECT_EQ(frf.lines, o.lines);
  EXPECT_LT(frf.input_condition.maxCoeff(), 1.0 + 1e-9);
  double worst = 0.0;
  for (std::size_t l = 0; l < frf.lines.size(); ++l) {
    const double w = frf.frequencies(static_cast<Eigen::Index>(l));
    worst = std::max(worst, std::abs(frf.response[l](0, 1) - zoh_response(g[0][1], w)));
    worst = std::max(worst, std::abs(frf.response[l](1, 2) - zoh_response(g[2][0], w)));
    worst = std::max(worst, std::abs(frf.response[l](0, 2)));
  }
  EXPECT_LT(worst, 1e-10);
  EXPECT_GT(frf.coherence.minCoeff(), 1.0 - 1e-12);
}

TEST(MimoPeriodicFrf, StatedVarianceMatchesTheMonteCarloSpread) {
  // Hadamard experiments of two inputs, white output noise drawn anew in each of R runs: the
  // sample variance over P = 6 periods / P against the spread of H over the runs.
  const auto g = system_2x3();
  MultisineOptions ms;
  ms.period_length = 128;
  ms.sample_time = kH;
  ms.max_frequency = 4.0;
  ms.periods = 8;
  ms.seed = 91;
  const OrthogonalMultisines o = orthogonal_multisines(ms, 2);
  std::vector<Eigen::MatrixXd> clean;
  for (const Eigen::MatrixXd& u : o.experiments) clean.push_back(outputs_of(g, u, 0.0, 0));
  PeriodicFrfOptions options;
  options.period_length = 128;
  options.transient_periods = 2;
  const int runs = 300;
  const auto lines = static_cast<int>(o.lines.size());
  std::vector<Eigen::MatrixXcd> sum(static_cast<std::size_t>(lines), Eigen::MatrixXcd::Zero(3, 2));
  std::vector<Eigen::MatrixXd> sum2(static_cast<std::size_t>(lines), Eigen::MatrixXd::Zero(3, 2));
  std::vector<Eigen::MatrixXd> stated(static_cast<std::size_t>(lines), Eigen::MatrixXd::Zero(3, 2));
  for (int r = 0; r < runs; ++r) {
    std::vector<MimoData> experiments;
    for (std::size_t e = 0; e < clean.size(); ++e) {
      Eigen::MatrixXd y = clean[e];
      for (int j = 0; j < 3; ++j) {
        y.col(j) += white_noise(static_cast<int>(y.rows()), 0.3,
                                7000 + 100 * static_cast<std::uint64_t>(r) + 10 * e + j);
      }
      experiments.emplace_back(kH, o.experiments[e], y);
    }
    const MimoFrf frf = periodic_frf(experiments, options);
    ASSERT_EQ(static_cast<int>(frf.lines.size()), lines);
    for (std::size_t l = 0; l < frf.lines.size(); ++l) {
      sum[l] += frf.response[l];
      sum2[l] += frf.response[l].cwiseAbs2();
      stated[l] += frf.variance[l] / runs;
    }
  }
  double ratio_sum = 0.0;
  for (std::size_t l = 0; l < sum.size(); ++l) {
    const Eigen::MatrixXcd mean = sum[l] / runs;
    const Eigen::MatrixXd spread = (sum2[l] / runs - mean.cwiseAbs2()) * runs / (runs - 1.0);
    ratio_sum += spread.cwiseQuotient(stated[l]).sum();
  }
  // The mean over runs of the sample variance is unbiased: the ratio averages to 1, within
  // about 1/sqrt(runs x entries) = 0.01 plus the correlation between neighbouring lines.
  EXPECT_NEAR(ratio_sum / (lines * 6), 1.0, 0.05);
}

TEST(MimoPeriodicFrf, BadExperimentsAreRefusedWithOneMessage) {
  const Eigen::MatrixXd u = white_inputs(1024, 2, 71);
  const MimoData two(kH, u, u);
  PeriodicFrfOptions options;
  options.period_length = 256;
  EXPECT_THAT(error_of([&] { periodic_frf(std::vector<MimoData>{two}, options); }),
              HasSubstr("1 experiment for 2 inputs; the FRF matrix needs at least one "
                        "experiment per input"));
  const MimoData three_outputs(kH, u, Eigen::MatrixXd::Ones(1024, 3));
  EXPECT_THAT(error_of([&] {
                periodic_frf(std::vector<MimoData>{two, three_outputs}, options);
              }),
              HasSubstr("experiment 2 has 2 inputs and 3 outputs but experiment 1 has 2 and 2"));
  EXPECT_THAT(error_of([&] { periodic_frf(two, options, 3); }),
              HasSubstr("do not split into 3 experiments"));
}

TEST(MimoFrfSummary, SummedPowerIsTheFrobeniusNormWithPowerWeightedCoherence) {
  MimoFrf frf;
  frf.lines = {1};
  frf.frequencies = Eigen::VectorXd::Constant(1, 2.0);
  Eigen::MatrixXcd h(2, 2);
  h << Complex(3, 0), Complex(0, 4), Complex(0, 0), Complex(12, 0);
  frf.response = {h};
  frf.variance = {Eigen::MatrixXd::Constant(2, 2, 0.25)};
  frf.coherence = Eigen::RowVector2d(1.0, 0.5);
  frf.output_power = Eigen::RowVector2d(1.0, 3.0);
  frf.input_level = Eigen::RowVector2d(1.0, 0.2);
  frf.input_names = {"u1", "u2"};
  frf.output_names = {"y1", "y2"};
  const Frf summary = summed_power_frf(frf);
  EXPECT_DOUBLE_EQ(summary.response(0).real(), 13.0);
  EXPECT_DOUBLE_EQ(summary.variance(0), 1.0);
  EXPECT_DOUBLE_EQ(summary.coherence(0), (1.0 + 1.5) / 4.0);
  EXPECT_DOUBLE_EQ(summary.input_level(0), 0.2);
  EXPECT_EQ(excited_lines(frf, 0.3).lines.size(), 0u);
  EXPECT_EQ(excited_lines(frf, 0.1).lines.size(), 1u);
}

}  // namespace
}  // namespace ctid::mimo_frf_test
