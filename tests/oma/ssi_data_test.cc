// Data-driven SSI: the past columns of the LQ factor are those of one Householder QR of the whole
// data Hankel matrix (chunked reduction included), a noise-free free decay gives the model's
// modes to rounding (the projection of the future on the past is exact there), a simulated ambient
// record of the chain gives every mode within its reported standard errors, records with no
// resonance give a verdict, and too short a record is refused naming what is wrong.
#include "ctid/oma/ssi_data.h"

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/oma/oma.h"
#include "ctid/oma/ssi_cov.h"
#include "oma/chain_model.h"

namespace ctid::ssi_data_test {
namespace {

using oma_test::ChainModel;

OmaOptions data_options() {
  OmaOptions o;
  o.method = OmaMethod::ssi_data;
  o.max_order = 24;
  o.block_rows = 20;
  return o;
}

// H built here as written in the papers (p block rows of past references over p block rows of
// future outputs, mean removed, 1/sqrt(j)).
Eigen::MatrixXd paper_hankel(const Eigen::MatrixXd& y, const std::vector<int>& refs, int p) {
  const Eigen::Index j = y.rows() - 2 * p + 1;
  const auto r = static_cast<Eigen::Index>(refs.size());
  const Eigen::Index l = y.cols();
  const Eigen::MatrixXd centred = y.rowwise() - y.colwise().mean();
  Eigen::MatrixXd hankel(p * (r + l), j);
  for (Eigen::Index i = 0; i < p; ++i) {
    for (Eigen::Index b = 0; b < r; ++b) {
      hankel.row(i * r + b) = centred.col(refs[static_cast<std::size_t>(b)]).segment(i, j);
    }
    for (Eigen::Index c = 0; c < l; ++c)
      hankel.row(p * r + i * l + c) = centred.col(c).segment(p + i, j);
  }
  return hankel / std::sqrt(static_cast<double>(j));
}

// The past columns [L11; L21] against one plain Householder QR of the whole H^T (H^T = Q R,
// L = R^T): equal up to the sign of each column, and their products with themselves equal the
// blocks of H H^T they stand for. 9000 samples run the reduction in several stripes and chunks;
// the cases differ in channels, references and block rows.
TEST(SsiData, PastColumnsAreThoseOfOneHouseholderQrOfTheWholeHankelMatrix) {
  struct Case {
    int dofs;
    std::vector<int> refs;
    int p;
    unsigned seed;
  };
  for (const Case& c : {Case{4, {1, 3}, 6, 4}, Case{4, {0, 1, 2, 3}, 9, 5}, Case{6, {2}, 14, 6}}) {
    SCOPED_TRACE(c.p);
    const ChainModel model(c.dofs);
    const int order = 2 * c.dofs;
    const Eigen::MatrixXd y = model.simulate(9000, 0.1, c.seed);
    const Eigen::MatrixXd hankel = paper_hankel(y, c.refs, c.p);
    const Eigen::Index past = c.p * static_cast<Eigen::Index>(c.refs.size());
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(hankel.transpose());
    const Eigen::MatrixXd whole = qr.matrixQR()
                                      .topRows(hankel.rows())
                                      .triangularView<Eigen::Upper>()
                                      .toDenseMatrix()
                                      .transpose();
    const Eigen::MatrixXd lower = oma_detail::ssi_data_past_columns(y, c.refs, c.p);
    ASSERT_EQ(lower.rows(), hankel.rows());
    ASSERT_EQ(lower.cols(), past);
    EXPECT_TRUE(lower.topRows(past).isLowerTriangular(0.0));
    const double size = whole.cwiseAbs().maxCoeff();
    EXPECT_LT((lower.cwiseAbs() - whole.leftCols(past).cwiseAbs()).cwiseAbs().maxCoeff(),
              1e-10 * size);
    const Eigen::MatrixXd gram = hankel * hankel.transpose();
    EXPECT_LT((lower * lower.topRows(past).transpose() - gram.leftCols(past)).cwiseAbs().maxCoeff(),
              1e-12 * gram.cwiseAbs().maxCoeff());
    // Issue 38's rounding rule: the poles of order 2 x dofs (every mode) from the SVD of the whole
    // QR's L21 and from ssi_data_factor agree to 1e-9 relative, shapes included.
    const Eigen::MatrixXd l21 = whole.block(past, 0, c.p * c.dofs, past);
    const Eigen::BDCSVD<Eigen::MatrixXd> svd(l21, Eigen::ComputeThinU);
    const auto reference = oma_detail::ssi_poles(
        oma_detail::observability_factor(svd.matrixU(), svd.singularValues(), c.dofs, order), order,
        model.h, 0.2);
    const auto poles = oma_detail::ssi_poles(oma_detail::ssi_data_factor(y, c.refs, c.p, order),
                                             order, model.h, 0.2);
    ASSERT_EQ(poles.size(), reference.size());
    ASSERT_FALSE(poles.empty());
    for (std::size_t i = 0; i < poles.size(); ++i) {
      EXPECT_NEAR(poles[i].frequency_hz / reference[i].frequency_hz, 1.0, 1e-9);
      EXPECT_NEAR(poles[i].damping_ratio / reference[i].damping_ratio, 1.0, 1e-9);
      EXPECT_LT((poles[i].shape - reference[i].shape).cwiseAbs().maxCoeff(), 1e-9);
    }
  }
}

// The stripes of H^T depend on its size alone, so one thread and several give the same bits.
TEST(SsiData, PastColumnsHaveTheSameBitsOnOneThreadAndSeveral) {
  const ChainModel model;
  const Eigen::MatrixXd y = model.simulate(9000, 0.1, 8);
  const std::vector<int> refs = {0, 2};
  const int p = 8;
  ASSERT_GT(oma_detail::ssi_data_stripes(y.rows() - 2 * p + 1, p * 6), 2);
  const Eigen::MatrixXd one = oma_detail::ssi_data_past_columns(y, refs, p, 1);
  for (int threads : {2, 3, 8}) {
    EXPECT_EQ(oma_detail::ssi_data_past_columns(y, refs, p, threads), one) << threads;
  }
}

// A free decay y_k = C A^k x_0 (no noise): the future rows lie in the row space of the past
// ones, so the projection is O times the states exactly. With the mean removed the record is of
// order 9 (a constant added); every order from 10 is cut to that rank and the four modes come
// back to rounding.
TEST(SsiData, NoiseFreeFreeDecayGivesTheModelsModesToRounding) {
  const ChainModel model;
  std::mt19937_64 rng(21);
  std::normal_distribution<double> normal;
  Eigen::VectorXd x(model.ad.rows());
  for (Eigen::Index i = 0; i < x.size(); ++i) x(i) = normal(rng);
  Eigen::MatrixXd y(1500, model.dofs);
  for (Eigen::Index k = 0; k < y.rows(); ++k) {
    y.row(k) = (model.c * x).transpose();
    x = model.ad * x;
  }
  const int p = 10;
  const auto factor = oma_detail::ssi_data_factor(y, {0, 1, 2, 3}, p, 20);
  EXPECT_EQ(factor.rank, 9);
  for (int n = 10; n <= 20; n += 2) {
    SCOPED_TRACE(n);
    const auto poles = oma_detail::ssi_poles(factor, n, model.h, 0.2);
    ASSERT_EQ(poles.size(), model.modes.size());
    for (std::size_t i = 0; i < poles.size(); ++i) {
      EXPECT_NEAR(poles[i].frequency_hz / model.modes[i].frequency_hz, 1.0, 1e-9);
      EXPECT_NEAR(poles[i].damping_ratio / model.modes[i].damping_ratio, 1.0, 1e-7);
      EXPECT_LT((poles[i].shape - model.modes[i].shape).cwiseAbs().maxCoeff(), 1e-8);
    }
  }
}

TEST(SsiData, SimulatedChainRecordGivesEveryModeWithinItsStandardErrors) {
  const ChainModel model;
  const Eigen::MatrixXd y = model.simulate(40000, 0.05, 11);
  const OmaResult r = oma(y, model.h, data_options());
  EXPECT_EQ(r.method, OmaMethod::ssi_data);
  EXPECT_TRUE(r.verdict.usable) << r.verdict.summary();
  ASSERT_EQ(r.modes.size(), model.modes.size());
  for (const auto& truth : model.modes) {
    SCOPED_TRACE(truth.frequency_hz);
    const OmaMode* m = oma_test::expect_found_within_errors(r, truth);
    ASSERT_NE(m, nullptr);
    EXPECT_GT(m->mpc, 0.95);
  }
}

TEST(SsiData, ReferenceChannelsGiveTheSameModes) {
  const ChainModel model;
  const Eigen::MatrixXd y = model.simulate(40000, 0.05, 12);
  OmaOptions o = data_options();
  o.reference_channels = {0, 3};
  const OmaResult r = oma(y, model.h, o);
  ASSERT_EQ(r.modes.size(), model.modes.size()) << r.verdict.summary();
  for (const auto& truth : model.modes) {
    const OmaMode* m = oma_test::nearest(r, truth.frequency_hz);
    EXPECT_LT(std::abs(m->frequency_hz - truth.frequency_hz), 4.0 * m->frequency_hz_std);
  }
}

TEST(SsiData, WhiteNoiseHasNoMode) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd y(20000, 4);
  for (Eigen::Index k = 0; k < y.rows(); ++k) {
    for (Eigen::Index j = 0; j < y.cols(); ++j) y(k, j) = normal(rng);
  }
  const OmaResult r = oma(y, 0.01, data_options());
  EXPECT_TRUE(r.modes.empty());
  EXPECT_FALSE(r.verdict.usable);
  EXPECT_THAT(r.verdict.summary(), ::testing::HasSubstr("no mode found"));
}

TEST(SsiData, FirstOrderLagHasNoMode) {
  std::mt19937_64 rng(6);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd y(20000, 3);
  double x = 0.0;
  for (Eigen::Index k = 0; k < y.rows(); ++k) {
    x = 0.95 * x + normal(rng);
    for (Eigen::Index j = 0; j < y.cols(); ++j) y(k, j) = (j + 1.0) * x + 0.1 * normal(rng);
  }
  OmaOptions o;
  o.method = OmaMethod::ssi_data;
  o.max_order = 12;
  const OmaResult r = oma(y, 0.01, o);
  EXPECT_TRUE(r.modes.empty()) << r.modes.size() << " modes, first at "
                               << (r.modes.empty() ? 0.0 : r.modes[0].frequency_hz);
  EXPECT_FALSE(r.verdict.usable);
}

// 12 channels and 20 block rows: 400 samples satisfy the 20 per block row, but the transposed
// Hankel matrix needs N - 2p + 1 >= p (r + l) = 480 rows, so 518 samples are one too few.
TEST(SsiData, TooShortARecordForTheHankelMatrixIsRefused) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd y(518, 12);
  for (Eigen::Index k = 0; k < y.rows(); ++k) {
    for (Eigen::Index j = 0; j < y.cols(); ++j) y(k, j) = normal(rng);
  }
  try {
    oma(y, 0.01, data_options());
    ADD_FAILURE() << "no exception";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("the record has 518 samples; ssi-data with 20 block "
                                               "rows over 12 references and 12 channels needs "
                                               "at least 519"));
  }
  Eigen::MatrixXd longer(519, 12);
  longer.topRows(518) = y;
  longer.row(518) = y.row(0);
  EXPECT_NO_THROW(oma(longer, 0.01, data_options()));
}

}  // namespace
}  // namespace ctid::ssi_data_test
