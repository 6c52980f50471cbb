// Fractional input delays in the sampled filters: a signal delayed by f h, held (ZOH) or
// interpolated (FOH) between samples, filtered exactly. The reference is independent of the
// split-period discretisation: the same continuous signal on a grid M times finer, where
// f h = j (h / M) is a whole number of fine samples, filtered with the plain hold there
// (exact on the fine grid too: a held or linear piece stays one between fine samples).
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/filtering/filter_bank.h"

namespace ctid {
namespace {

Eigen::VectorXd random_signal(int n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  Eigen::VectorXd x(n);
  for (int k = 0; k < n; ++k) x(k) = normal(rng);
  return x;
}

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

}  // namespace
}  // namespace ctid
