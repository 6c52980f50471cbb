// Recursive SRIVC (recursive_srivc.h): exact on noise-free data, the batch estimate and its
// covariance with lambda = 1, honest standard errors, tracking a jump of the natural frequency
// with forgetting or a random walk, and the messages for bad input. All records are seeded.
#include <cmath>
#include <cstdint>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/refined_iv/recursive_srivc.h"
#include "ctid/refined_iv/srivc.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"

namespace ctid::recursive_srivc_test {
namespace {

using ::testing::HasSubstr;

constexpr double kH = 0.05;
const SubmodelOrder kOrder{2, 1, 0};

// theta = [a1, a2, b0, b1]: (b0 + b1 p) / (1 + a1 p + a2 p^2).
TransferFunction model_of(const Eigen::VectorXd& t) {
  return TransferFunction(Polynomial{t(2), t(3)}, Polynomial{1.0, t(0), t(1)});
}

// w_n = 2 rad/s, zeta = 0.3, a zero at -2.
Eigen::VectorXd truth() {
  Eigen::VectorXd t(4);
  t << 0.3, 0.25, 1.0, 0.5;
  return t;
}

// The same mode at natural frequency w (damping 0.3, same numerator).
Eigen::VectorXd with_frequency(double w) {
  Eigen::VectorXd t = truth();
  t(0) = 2.0 * 0.3 / w;
  t(1) = 1.0 / (w * w);
  return t;
}

double relative_error(const Eigen::VectorXd& estimate, const Eigen::VectorXd& reference) {
  return (estimate - reference).norm() / reference.norm();
}

// Output of a system whose parameters switch from `first` to `second` at sample `at`, the
// state (w, dw/dt with A(p) w = u, y = B(p) w) carried across the switch: one record of a
// system that changes while running, exact under the zero-order hold.
Eigen::VectorXd simulate_switching(const Eigen::VectorXd& first, const Eigen::VectorXd& second,
                                   int at, const Eigen::VectorXd& u) {
  auto discretize = [](const Eigen::VectorXd& t) {
    Eigen::MatrixXd a(2, 2);
    a << 0.0, 1.0, -1.0 / t(1), -t(0) / t(1);
    Eigen::MatrixXd b(2, 1);
    b << 0.0, 1.0 / t(1);
    return discretize_zoh(a, b, kH);
  };
  const ZohDiscretization d1 = discretize(first);
  const ZohDiscretization d2 = discretize(second);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(2);
  Eigen::VectorXd y(u.size());
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    const Eigen::VectorXd& t = k < at ? first : second;
    y(k) = t(2) * x(0) + t(3) * x(1);
    const ZohDiscretization& d = k < at ? d1 : d2;
    x = d.phi * x + d.gamma.col(0) * u(k);
  }
  return y;
}

TEST(RecursiveSrivc, NoiseFreeConvergesToTheTruthFromAStartTwentyPercentOff) {
  const int n = 2000;
  const Eigen::VectorXd u = white_noise(n, 1.0, 7);
  const SampledData data(kH, u, simulate(model_of(truth()), u, kH));
  Eigen::VectorXd start = truth();
  start(0) *= 1.2;
  start(1) *= 0.8;
  start(2) *= 1.2;
  start(3) *= 0.8;
  // Noise-free data need no warm-up: the filters follow the estimate from the 10th sample.
  RecursiveSrivcOptions options;
  options.warmup_samples = 0;
  const RecursiveSrivcResult r = recursive_srivc(data, kOrder, model_of(start), options);
  const Eigen::VectorXd final_theta = r.parameters.bottomRows(1).transpose();
  // Measured 1.5e-7: what is left is the weight of the start through P0 (1e6 theta0^2) and
  // of the first equations, whose filters were still off; both fall as 1/N.
  EXPECT_LT(relative_error(final_theta, truth()), 1e-6);
  EXPECT_TRUE(r.stable);
  EXPECT_TRUE(r.finite);
  EXPECT_EQ(r.rejected_refreshes, 0);
  EXPECT_EQ(r.parameters.rows(), n);
  EXPECT_EQ(r.parameters.cols(), 4);

  // Carrying the filtered derivatives across a refresh instead of re-filtering leaves a
  // transient after every change of A, a bias that only falls as 1/N with lambda = 1
  // (measured 2.1e-3): why refilter_samples exists (decision 0025).
  RecursiveSrivcOptions carried = options;
  carried.refilter_samples = 0;
  const RecursiveSrivcResult c = recursive_srivc(data, kOrder, model_of(start), carried);
  EXPECT_GT(relative_error(c.parameters.bottomRows(1).transpose(), truth()), 1e-4);

  // With the default warm-up the first 100 equations use the start's filter, 20 % off. The
  // measured output is interpolated linearly between samples, which is exact in the
  // equations only when the filter is the system's own A (ESTIMATOR-NOTES), so those
  // equations carry an error of the order of the interpolation error times the filter's
  // mismatch, and it too falls as 1/N (measured 4.0e-6).
  const RecursiveSrivcResult d = recursive_srivc(data, kOrder, model_of(start));
  EXPECT_LT(relative_error(d.parameters.bottomRows(1).transpose(), truth()), 1e-5);
}

TEST(RecursiveSrivc, WithoutForgettingItEndsAtTheBatchEstimateAndCovariance) {
  const int n = 2000;
  const Eigen::VectorXd u = white_noise(n, 1.0, 11);
  const Eigen::VectorXd e = white_noise(n, 0.2, 12);
  const SampledData data(kH, u, simulate(model_of(truth()), u, kH) + e);
  RefinedIvOptions batch_options;
  batch_options.initial_model = AdditiveModel::from_parameters({kOrder}, truth());
  batch_options.noise = NoiseAssumption::white;
  const EstimationResult batch = srivc(data, kOrder, batch_options);
  ASSERT_TRUE(batch.converged());
  Eigen::VectorXd start = truth() * 1.1;
  const RecursiveSrivcResult r = recursive_srivc(data, kOrder, model_of(start));
  const Eigen::VectorXd theta = r.parameters.bottomRows(1).transpose();
  const Eigen::VectorXd se = r.standard_errors.bottomRows(1).transpose();
  // Measured: within 0.17 batch standard errors, standard errors 1.2-2.1 % larger.
  for (int i = 0; i < 4; ++i) {
    SCOPED_TRACE(i);
    EXPECT_LT(std::abs(theta(i) - batch.parameters(i)), 0.5 * batch.standard_errors(i));
    const double ratio = se(i) / batch.standard_errors(i);
    EXPECT_GT(ratio, 0.8);
    EXPECT_LT(ratio, 1.25);
  }
  // The default refresh every 10 samples against the textbook refresh at every sample:
  // measured 0.010 standard errors apart (the docs quote it).
  RecursiveSrivcOptions every;
  every.refresh_interval = 1;
  const RecursiveSrivcResult r1 = recursive_srivc(data, kOrder, model_of(start), every);
  const Eigen::VectorXd theta1 = r1.parameters.bottomRows(1).transpose();
  EXPECT_LT((theta - theta1).cwiseAbs().cwiseQuotient(se).maxCoeff(), 0.05);
}

TEST(RecursiveSrivc, TwoStandardErrorIntervalsCoverTheTruth) {
  const int runs = 30;
  const int n = 1000;
  Eigen::VectorXi covered = Eigen::VectorXi::Zero(4);
  for (int run = 0; run < runs; ++run) {
    const auto seed = static_cast<std::uint64_t>(100 + 2 * run);
    const Eigen::VectorXd u = white_noise(n, 1.0, seed);
    const Eigen::VectorXd e = white_noise(n, 0.2, seed + 1);
    const SampledData data(kH, u, simulate(model_of(truth()), u, kH) + e);
    const RecursiveSrivcResult r = recursive_srivc(data, kOrder, model_of(truth() * 0.9));
    for (int i = 0; i < 4; ++i) {
      const double error = r.parameters(n - 1, i) - truth()(i);
      if (std::abs(error) <= 2.0 * r.standard_errors(n - 1, i)) ++covered(i);
    }
  }
  for (int i = 0; i < 4; ++i) {
    SCOPED_TRACE(i);
    EXPECT_GE(covered(i), 24);  // >= 80 % of 30 (about 95 % expected)
  }
}

// Samples after `from` until |a2 - target| / target stays below `tolerance` to the end
// (-1 if it never does).
int samples_to_settle(const RecursiveSrivcResult& r, int from, double target, double tolerance) {
  int last_outside = from - 1;
  for (int k = from; k < r.parameters.rows(); ++k) {
    if (std::abs(r.parameters(k, 1) - target) > tolerance * target) last_outside = k;
  }
  return last_outside + 1 >= r.parameters.rows() ? -1 : last_outside + 1 - from;
}

TEST(RecursiveSrivc, ForgettingOrARandomWalkFollowsAJumpOfTheNaturalFrequency) {
  const int n = 3000;
  const int jump = 1500;
  const Eigen::VectorXd before = with_frequency(2.0);
  const Eigen::VectorXd after = with_frequency(3.0);
  const Eigen::VectorXd u = white_noise(n, 1.0, 21);
  const Eigen::VectorXd e = white_noise(n, 0.05, 22);
  const SampledData data(kH, u, simulate_switching(before, after, jump, u) + e);

  RecursiveSrivcOptions forgetting;
  forgetting.forgetting_factor = 0.99;
  const RecursiveSrivcResult f = recursive_srivc(data, kOrder, model_of(before), forgetting);
  RecursiveSrivcOptions walk;
  walk.random_walk = {1e-5};
  const RecursiveSrivcResult w = recursive_srivc(data, kOrder, model_of(before), walk);
  const RecursiveSrivcResult plain = recursive_srivc(data, kOrder, model_of(before));

  const int settle_f = samples_to_settle(f, jump, after(1), 0.05);
  const int settle_w = samples_to_settle(w, jump, after(1), 0.05);
  // Measured: 115 samples (5.8 s, lambda = 0.99, a memory of 100 samples) and 226 samples
  // (random walk 1e-5) until a2 stays within 5 % of its new value (docs/algorithms/
  // recursive-srivc.md quotes these numbers).
  EXPECT_GE(settle_f, 0);
  EXPECT_LE(settle_f, 150);
  EXPECT_GE(settle_w, 0);
  EXPECT_LE(settle_w, 300);
  // Without forgetting the estimate averages both halves: a2 is still far from the new value
  // 1500 samples after the jump.
  EXPECT_EQ(samples_to_settle(plain, jump, after(1), 0.05), -1);
  // The price of tracking: a larger standard error with forgetting (1500 equations against
  // an effective 100).
  // Before the jump (both models right) the price of tracking shows: forgetting keeps an
  // effective 100 equations against 1500 (measured 0.0040 against 0.0014). After it the
  // plain estimate's standard error grows instead, its output error holding the mismatch.
  EXPECT_GT(f.standard_errors(jump - 1, 1), 2.0 * plain.standard_errors(jump - 1, 1));
  // (measured 9.7 % off at the end).
  EXPECT_GT(std::abs(plain.parameters(n - 1, 1) - after(1)) / after(1), 0.05);
  // Before the jump all three had found the first system.
  for (const RecursiveSrivcResult* r : {&f, &w, &plain}) {
    EXPECT_LT(std::abs(r->parameters(jump - 1, 1) - before(1)) / before(1), 0.05);
  }
}

TEST(RecursiveSrivc, BadInputIsRefusedWithOneMessageNamingTheField) {
  const Eigen::VectorXd u = white_noise(200, 1.0, 3);
  const SampledData data(kH, u, simulate(model_of(truth()), u, kH));
  const TransferFunction start = model_of(truth());
  auto message = [&](auto&& call) {
    try {
      call();
    } catch (const InvalidArgument& error) {
      return std::string(error.what());
    }
    return std::string("no exception");
  };
  RecursiveSrivcOptions o;
  o.forgetting_factor = 1.5;
  EXPECT_THAT(message([&] { recursive_srivc(data, kOrder, start, o); }),
              HasSubstr("RecursiveSrivcOptions.forgetting_factor is 1.5; it must be in (0, 1]"));
  o.forgetting_factor = 0.0;
  EXPECT_THAT(message([&] { recursive_srivc(data, kOrder, start, o); }),
              HasSubstr("forgetting_factor is 0; it must be in (0, 1]"));
  RecursiveSrivcOptions rw;
  rw.random_walk = {1e-3, 1e-3};
  EXPECT_THAT(message([&] { recursive_srivc(data, kOrder, start, rw); }),
              HasSubstr("random_walk has 2 values; it must have 0, 1 or np = n + m + 1 = 4"));
  rw.random_walk = {-1.0};
  EXPECT_THAT(message([&] { recursive_srivc(data, kOrder, start, rw); }),
              HasSubstr("random_walk[0] is -1; it must be finite and >= 0"));
  const TransferFunction third(Polynomial{1.0}, Polynomial{1.0, 1.0, 1.0, 1.0});
  EXPECT_THAT(message([&] { recursive_srivc(data, kOrder, third, {}); }),
              HasSubstr("has 3 non-zero poles"));
  const TransferFunction unstable(Polynomial{1.0}, Polynomial{1.0, -0.3, 0.25});
  EXPECT_THAT(message([&] { recursive_srivc(data, kOrder, unstable, {}); }),
              HasSubstr("the start must be stable"));
  EXPECT_THAT(message([&] {
                recursive_srivc(data, SubmodelOrder{2, 1, 1}, start, {});
              }),
              HasSubstr("order.integrators is 1; it must be 0"));
  EXPECT_THAT(message([&] {
                recursive_srivc(data, SubmodelOrder{2, 3, 0}, start, {});
              }),
              HasSubstr("order.m is 3; it must be <= order.n = 2"));
  EXPECT_THAT(message([&] { recursive_srivc(data.segment(0, 7), kOrder, start, {}); }),
              HasSubstr("the record has 7 samples; it must have at least 2 (n + m + 1) = 8"));
  RecursiveSrivc estimator(kOrder, kH, Hold::zero_order_hold, start);
  EXPECT_THAT(message([&] { estimator.update(1.0, std::nan("")); }),
              HasSubstr("sample 0 has u = 1, y = nan; both must be finite"));
  EXPECT_EQ(estimator.steps(), 0);
}

}  // namespace
}  // namespace ctid::recursive_srivc_test
