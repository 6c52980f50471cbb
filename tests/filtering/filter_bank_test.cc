#include "ctid/filtering/filter_bank.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/simulation/discretization.h"

namespace ctid::filter_bank_test {
namespace {

Eigen::VectorXd random_signal(int n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  Eigen::VectorXd x(n);
  for (int k = 0; k < n; ++k) x(k) = normal(rng);
  return x;
}

TEST(FilterBank, FirstOrderStepResponseMatchesClosedForm) {
  // 1/(1 + tau p) of a unit step: w = 1 - e^{-t/tau}, p w = e^{-t/tau} / tau.
  const double tau = 0.7;
  const double h = 0.05;
  const int n = 100;
  const Eigen::MatrixXd out =
      filter_derivatives(Polynomial{1.0, tau}, Eigen::VectorXd::Ones(n), h, Hold::zero_order_hold);
  for (int k = 0; k < n; ++k) {
    const double t = k * h;
    EXPECT_NEAR(out(k, 0), 1.0 - std::exp(-t / tau), 1e-14);
    EXPECT_NEAR(out(k, 1), std::exp(-t / tau) / tau, 1e-13);
  }
}

TEST(FilterBank, FirstOrderHoldIsExactForARamp) {
  // 1/(1 + tau p) of x(t) = t from rest: w = t - tau + tau e^{-t/tau}.
  const double tau = 0.3;
  const double h = 0.1;
  const int n = 60;
  Eigen::VectorXd ramp(n);
  for (int k = 0; k < n; ++k) ramp(k) = k * h;
  const Eigen::MatrixXd foh =
      filter_derivatives(Polynomial{1.0, tau}, ramp, h, Hold::first_order_hold);
  const Eigen::MatrixXd zoh =
      filter_derivatives(Polynomial{1.0, tau}, ramp, h, Hold::zero_order_hold);
  for (int k = 0; k < n; ++k) {
    const double t = k * h;
    EXPECT_NEAR(foh(k, 0), t - tau + tau * std::exp(-t / tau), 1e-13);
  }
  // The zero-order hold lags the ramp by about h/2: visibly different.
  EXPECT_GT(std::abs(zoh(n - 1, 0) - foh(n - 1, 0)), 0.01);
}

TEST(FilterBank, IntegratorChainsGivePolynomials) {
  // 1/p^2 of a unit step = t^2/2, 1/p = t, p^2/p^2 = 1 (ZOH exact).
  const double h = 0.01;
  const int n = 200;
  const Eigen::MatrixXd out = filter_derivatives(
      Polynomial{0.0, 0.0, 1.0}, Eigen::VectorXd::Ones(n), h, Hold::zero_order_hold);
  for (int k = 0; k < n; ++k) {
    const double t = k * h;
    EXPECT_NEAR(out(k, 0), 0.5 * t * t, 1e-13);
    EXPECT_NEAR(out(k, 1), t, 1e-13);
    EXPECT_NEAR(out(k, 2), 1.0, 1e-15);
  }
}

TEST(FilterBank, WeightedSumOfDerivativesReproducesTheSignalAtTheSamples) {
  // sum_k a_k p^k/A x = x exactly at the samples for any interpolation: the property the
  // fixed point of the refined IV iteration rests on. An 8th-order A with spread poles
  // (the open-loop example of Section 6.1).
  const Polynomial a =
      Polynomial{1.0, 0.5 / 1.96, 1.0 / 1.96} * Polynomial{1.0, 0.3 / 10.0, 1.0 / 10.0} *
      Polynomial{1.0, 0.34 / 33.3, 1.0 / 33.3} * Polynomial{1.0, 1.0 / 100.0, 1.0 / 100.0};
  const Eigen::VectorXd x = random_signal(2000, 7);
  for (Hold hold : {Hold::zero_order_hold, Hold::first_order_hold}) {
    const Eigen::MatrixXd out = filter_derivatives(a, x, 0.05, hold);
    const Eigen::VectorXd recombined = out * a.coefficients();
    EXPECT_LT((recombined - x).cwiseAbs().maxCoeff(), 1e-11 * x.cwiseAbs().maxCoeff());
  }
}

TEST(FilterBank, CascadeEqualsOneBankOfTheSquaredDenominator) {
  // p^k B/A^2 from two cascaded 1/A stages against sum_j b_j p^{k+j}/A^2 from one bank of
  // A^2: two different realisations of the same transfer functions.
  const Polynomial a{1.0, 0.2, 0.05};
  const Polynomial b{2.0, -0.3};
  const FilterRealization first = derivative_filters(a);
  Eigen::VectorXd weights = Eigen::VectorXd::Zero(first.outputs());
  weights.head(2) = b.coefficients();
  const FilterRealization chain = cascade(first, weights, derivative_filters(a));
  const Eigen::VectorXd u = random_signal(500, 3);
  const double h = 0.02;
  const Eigen::MatrixXd cascaded = SampledFilter(chain, h, Hold::zero_order_hold).apply(u);
  const Eigen::MatrixXd squared = filter_derivatives(a * a, u, h, Hold::zero_order_hold);
  ASSERT_EQ(cascaded.cols(), 3);
  for (int k = 0; k <= 2; ++k) {
    const Eigen::VectorXd reference = b[0] * squared.col(k) + b[1] * squared.col(k + 1);
    EXPECT_LT((cascaded.col(k) - reference).cwiseAbs().maxCoeff(),
              1e-10 * (1.0 + reference.cwiseAbs().maxCoeff()))
        << "k = " << k;
  }
}

// The recursion of SampledFilter written out densely, every sum in index order: x_k feeds
// next_i = (gamma0_i x_{k-1} + gamma1_i x_k) + (phi_i0 z_0 + phi_i1 z_1 + ...) and
// out_j = d_j x_k + c_j0 z_0 + c_j1 z_1 + ...; with a delay fraction the step also weighs
// x_{k-2} (first term) and the outputs see the delayed signal at t_k instead of x_k.
Eigen::MatrixXd dense_recursion(const FilterRealization& f, double h, Hold hold, double fraction,
                                const Eigen::VectorXd& x) {
  const DelayedHoldDiscretization w = discretize_delayed(f.a, f.b, h, fraction, hold);
  const DelayedSample now = delayed_sample(fraction, hold);
  const auto at = [&x](Eigen::Index k) { return k >= 0 ? x(k) : 0.0; };
  const int s = f.order();
  Eigen::VectorXd z = Eigen::VectorXd::Zero(s);
  Eigen::VectorXd next(s);
  Eigen::MatrixXd out(x.size(), f.outputs());
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    if (k > 0) {
      for (int i = 0; i < s; ++i) {
        double sum = w.phi(i, 0) * z(0);
        for (int j = 1; j < s; ++j) sum = sum + w.phi(i, j) * z(j);
        const double held = fraction > 0.0 ? w.previous(i, 0) * at(k - 2) +
                                                 w.current(i, 0) * at(k - 1) + w.next(i, 0) * x(k)
                                           : w.current(i, 0) * x(k - 1) + w.next(i, 0) * x(k);
        next(i) = held + sum;
      }
      z = next;
    }
    const double signal = fraction > 0.0 ? now.previous * at(k - 1) + now.current * x(k) : x(k);
    for (int j = 0; j < f.outputs(); ++j) {
      double acc = f.d(j) * signal;
      for (int i = 0; i < s; ++i) acc = acc + f.c(j, i) * z(i);
      out(k, j) = acc;
    }
  }
  return out;
}

TEST(FilterBank, SkippingExactZerosChangesNoBit) {
  // The fixed-size kernels skip the zero upper right block of a cascade of two equal-order
  // stages and the zeros of C's rows; the refined IV results stay bit-identical only if the
  // sums left keep their order. Cascades of 4 to 16 states (split kernels; 6 is not split)
  // and banks of even order 2 to 8 (dense update, sparse rows of C), both holds, with and
  // without a delay fraction. (Eigen sums an odd fixed-size product by a tree, not in index
  // order; the kernel keeps that order too.)
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> damping(0.05, 0.6);
  std::uniform_real_distribution<double> frequency(0.3, 6.0);
  const Eigen::VectorXd x = random_signal(400, 9);
  for (int n : {2, 3, 4, 6, 8}) {
    Polynomial a{1.0};
    for (int m = 0; m + 1 < n; m += 2) {
      const double w0 = frequency(rng);
      a = a * Polynomial{1.0, 2.0 * damping(rng) / w0, 1.0 / (w0 * w0)};
    }
    if (n % 2 == 1) a = a * Polynomial{1.0, 1.0 / frequency(rng)};
    const FilterRealization bank = derivative_filters(a);
    Eigen::VectorXd weights = Eigen::VectorXd::Zero(bank.outputs());
    weights.head(n - 1).setLinSpaced(n - 1, 1.0, -0.5);
    const FilterRealization chain = cascade(bank, weights, derivative_filters(a));
    std::vector<FilterRealization> filters{chain};
    if (n % 2 == 0) filters.push_back(bank);
    for (const FilterRealization& f : filters) {
      for (Hold hold : {Hold::zero_order_hold, Hold::first_order_hold}) {
        for (double fraction : {0.0, 0.3}) {
          const Eigen::MatrixXd fast = SampledFilter(f, 0.05, hold, fraction).apply(x);
          const Eigen::MatrixXd reference = dense_recursion(f, 0.05, hold, fraction, x);
          EXPECT_EQ((fast - reference).cwiseAbs().maxCoeff(), 0.0)
              << f.order() << " states, " << (hold == Hold::zero_order_hold ? "zero" : "first")
              << "-order hold, delay fraction " << fraction;
        }
      }
    }
  }
}

TEST(FilterBank, StartsAtRestAndIsLinear) {
  const Polynomial a{1.0, 0.4, 0.1};
  const Eigen::VectorXd x1 = random_signal(300, 1);
  const Eigen::VectorXd x2 = random_signal(300, 2);
  const SampledFilter f(derivative_filters(a), 0.05, Hold::first_order_hold);
  const Eigen::MatrixXd y1 = f.apply(x1);
  const Eigen::MatrixXd y2 = f.apply(x2);
  const Eigen::MatrixXd y12 = f.apply(2.0 * x1 - x2);
  EXPECT_LT((y12 - (2.0 * y1 - y2)).cwiseAbs().maxCoeff(), 1e-12);
  // At rest at t_0: only the biproper output p^2/A sees x_0 (through 1/a_2).
  EXPECT_DOUBLE_EQ(y1(0, 0), 0.0);
  EXPECT_DOUBLE_EQ(y1(0, 1), 0.0);
  EXPECT_NEAR(y1(0, 2), x1(0) / 0.1, 1e-12);
}

TEST(FilterBank, StreamingInPiecesEqualsOnePass) {
  // Orders 5 (general kernel) and 8/16 (fixed-size kernels), both holds, uneven pieces.
  const Polynomial a5 =
      Polynomial{1.0, 0.3} * Polynomial{1.0, 0.2, 0.05} * Polynomial{1.0, 0.1, 0.02};
  const Polynomial a8 = Polynomial{1.0, 0.4, 0.1} * Polynomial{1.0, 0.1, 0.03} *
                        Polynomial{1.0, 0.05, 0.01} * Polynomial{1.0, 0.02, 0.003};
  const Eigen::VectorXd x = random_signal(1000, 4);
  Eigen::VectorXd b8 = Eigen::VectorXd::Zero(9);
  b8.head(3) << 1.0, -0.2, 0.05;
  const FilterRealization chain = cascade(derivative_filters(a8), b8, derivative_filters(a8));
  for (const FilterRealization& r : {derivative_filters(a5), derivative_filters(a8), chain}) {
    for (Hold hold : {Hold::zero_order_hold, Hold::first_order_hold}) {
      const SampledFilter f(r, 0.05, hold);
      const Eigen::MatrixXd whole = f.apply(x);
      Eigen::MatrixXd pieces(x.size(), f.outputs() - 1);
      SampledFilter::Stream stream = f.start();
      for (Eigen::Index k0 = 0, len = 1; k0 < x.size(); k0 += len, len = len * 3 + 1) {
        len = std::min<Eigen::Index>(len, x.size() - k0);
        Eigen::MatrixXd out(len, f.outputs() - 1);
        f.run(x.segment(k0, len), stream, out, 1);
        pieces.middleRows(k0, len) = out;
      }
      EXPECT_EQ((pieces - whole.rightCols(f.outputs() - 1)).cwiseAbs().maxCoeff(), 0.0)
          << "order " << f.order();
    }
  }
  const SampledFilter f(derivative_filters(a5), 0.05, Hold::zero_order_hold);
  SampledFilter::Stream stream = f.start();
  Eigen::MatrixXd too_wide(10, f.outputs() + 1);
  EXPECT_THROW(f.run(x.head(10), stream, too_wide), InvalidArgument);
}

TEST(FilterBank, DelayShiftsWithZeros) {
  const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(5, 1.0, 5.0);
  const Eigen::VectorXd d = delay_samples(x, 2);
  EXPECT_THAT(std::vector<double>(d.data(), d.data() + 5),
              ::testing::ElementsAre(0.0, 0.0, 1.0, 2.0, 3.0));
  EXPECT_TRUE(delay_samples(x, 9).isZero());
  EXPECT_THROW(delay_samples(x, -1), InvalidArgument);
}

TEST(FilterBank, RejectsBadArguments) {
  EXPECT_THROW(derivative_filters(Polynomial{2.0}), InvalidArgument);
  EXPECT_THROW(SampledFilter(derivative_filters(Polynomial{1.0, 1.0}), 0.0, Hold::zero_order_hold),
               InvalidArgument);
  const FilterRealization f = derivative_filters(Polynomial{1.0, 1.0});
  EXPECT_THROW(cascade(f, Eigen::VectorXd::Ones(5), f), InvalidArgument);
}

// Fractional input delays: a signal delayed by f h, held (ZOH) or interpolated (FOH)
// between samples, filtered exactly. The reference is independent of the split-period
// discretisation: the same continuous signal on a grid M times finer, where f h = j (h / M)
// is a whole number of fine samples, filtered with the plain hold there (exact on the fine
// grid too: a held or linear piece stays one between fine samples).

// The held signal on the fine grid: each sample repeated (ZOH) or the line to the next one
// sampled (FOH, held after the last sample).
Eigen::VectorXd refine(const Eigen::VectorXd& x, int m, Hold hold) {
  const Eigen::Index n = x.size();
  Eigen::VectorXd fine(n * m);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double next = k + 1 < n ? x(k + 1) : x(k);
    for (int j = 0; j < m; ++j) {
      const double s = static_cast<double>(j) / m;
      fine(k * m + j) = hold == Hold::zero_order_hold ? x(k) : (1.0 - s) * x(k) + s * next;
    }
  }
  return fine;
}

struct Case {
  Hold hold;
  int sub_samples;  // the delay fraction is sub_samples / kFine
};

constexpr int kFine = 40;

class FractionalDelay : public ::testing::TestWithParam<Case> {};

TEST_P(FractionalDelay, MatchesTheSameSignalDelayedOnAFinerGrid) {
  const Case c = GetParam();
  const double h = 0.05;
  const int n = 120;
  // A lightly damped pair and a real pole: p^k / D for k = 0..3, the last one biproper.
  const Polynomial den = Polynomial{1.0, 0.02, 0.01} * Polynomial{1.0, 0.2};
  const Eigen::VectorXd x = random_signal(n, 7);
  const double fraction = static_cast<double>(c.sub_samples) / kFine;
  const Eigen::MatrixXd got = SampledFilter(derivative_filters(den), h, c.hold, fraction).apply(x);
  // The continuous signal starts one sample early at zero (as a whole-sample delay pads
  // with zeros), so the delayed signal on [0, f h) is the end of that first interval.
  Eigen::VectorXd padded = Eigen::VectorXd::Zero(n + 1);
  padded.tail(n) = x;
  const Eigen::VectorXd delayed =
      refine(padded, kFine, c.hold).segment(kFine - c.sub_samples, n * kFine);
  const Eigen::MatrixXd fine =
      SampledFilter(derivative_filters(den), h / kFine, c.hold).apply(delayed);
  double worst = 0.0;
  for (int k = 0; k < n; ++k) {
    const Eigen::RowVectorXd difference = got.row(k) - fine.row(k * kFine);
    worst = std::max(worst, difference.cwiseAbs().maxCoeff() /
                                std::max(1.0, fine.row(k * kFine).cwiseAbs().maxCoeff()));
  }
  EXPECT_LT(worst, 1e-10) << "fraction " << fraction;
}

INSTANTIATE_TEST_SUITE_P(
    HoldsAndFractions, FractionalDelay,
    ::testing::Values(Case{Hold::zero_order_hold, 0}, Case{Hold::zero_order_hold, 1},
                      Case{Hold::zero_order_hold, 15}, Case{Hold::zero_order_hold, 39},
                      Case{Hold::first_order_hold, 0}, Case{Hold::first_order_hold, 1},
                      Case{Hold::first_order_hold, 15}, Case{Hold::first_order_hold, 39}));

TEST(FractionalDelayFilter, StreamedPiecesEqualOneApply) {
  const double h = 0.1;
  const Eigen::VectorXd x = random_signal(300, 3);
  for (Hold hold : {Hold::zero_order_hold, Hold::first_order_hold}) {
    const SampledFilter filter(derivative_filters(Polynomial{1.0, 0.5, 0.3}), h, hold, 0.37);
    const Eigen::MatrixXd whole = filter.apply(x);
    SampledFilter::Stream stream = filter.start();
    Eigen::MatrixXd pieces(x.size(), filter.outputs());
    for (Eigen::Index k0 = 0; k0 < x.size(); k0 += 70) {
      const Eigen::Index len = std::min<Eigen::Index>(70, x.size() - k0);
      filter.run(x.segment(k0, len), stream, pieces.middleRows(k0, len));
    }
    EXPECT_EQ((whole - pieces).cwiseAbs().maxCoeff(), 0.0);
  }
}

TEST(FractionalDelayFilter, RejectsAFractionOutsideZeroToOne) {
  const FilterRealization bank = derivative_filters(Polynomial{1.0, 1.0});
  for (double f : {-0.1, 1.0, 2.5}) {
    try {
      SampledFilter(bank, 0.1, Hold::zero_order_hold, f);
      FAIL() << "no exception for " << f;
    } catch (const InvalidArgument& error) {
      EXPECT_THAT(error.what(), ::testing::HasSubstr("delay fraction"));
      EXPECT_THAT(error.what(), ::testing::HasSubstr("[0, 1)"));
    }
  }
}

// derivative_filters as a value (decision 0045): the same realisation where there is a finite
// one; none for a constant denominator and for one whose leading coefficient is so small
// against the others that the realisation overflows (A lost its leading coefficient), where
// derivative_filters throws or gives entries that validate() refuses.
TEST(FiniteDerivativeFilters, IsTheSameRealisationOrNoneWhereThereIsNoFiniteOne) {
  const Polynomial d{1.0, 0.3, 0.02, 1e-3};
  const std::optional<FilterRealization> f = finite_derivative_filters(d);
  ASSERT_TRUE(f.has_value());
  const FilterRealization g = derivative_filters(d);
  EXPECT_EQ(f->a, g.a);
  EXPECT_EQ(f->b, g.b);
  EXPECT_EQ(f->c, g.c);
  EXPECT_EQ(f->d, g.d);
  EXPECT_TRUE(f->finite());

  EXPECT_FALSE(finite_derivative_filters(Polynomial{2.0}).has_value());
  EXPECT_THROW(derivative_filters(Polynomial{2.0}), InvalidArgument);
  const Polynomial lost{1.0, 1e10, 1e-300};  // a_1 / a_2 = 1e310 overflows
  EXPECT_FALSE(finite_derivative_filters(lost).has_value());
  EXPECT_FALSE(derivative_filters(lost).finite());
  EXPECT_THROW(derivative_filters(lost).validate(), InvalidArgument);
}

}  // namespace
}  // namespace ctid::filter_bank_test
