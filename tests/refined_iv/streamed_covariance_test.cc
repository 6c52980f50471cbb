// The covariance of refined IV from the instrument streamed in blocks (issue 14: memory per
// sample independent of the model order) equals the covariance from the whole N x p instrument
// held in memory, within 1e-12 relative: open and closed loop, white and coloured noise, an
// estimated delay's extra column, several records with their free responses, records shorter
// and longer than a segment. The backward AR sum gives the explicit formula whatever the chunks.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ctid/core/fields.h"
#include "ctid/refined_iv/covariance.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/noise.h"
#include "ctid/simulation/simulate.h"
#include "refined_iv/internal/covariance_sums.h"
#include "refined_iv/internal/refined_iv_engine.h"
#include "support/paper_systems.h"

namespace ctid::streamed_covariance_test {
namespace {

constexpr double kH = testing::kPaperSampleTime;

// Largest |a_ij - b_ij| / sqrt(b_ii b_jj): the difference in units of the standard errors.
double scaled_difference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  double worst = 0.0;
  for (Eigen::Index i = 0; i < b.rows(); ++i) {
    for (Eigen::Index j = 0; j < b.cols(); ++j) {
      worst = std::max(worst, std::abs(a(i, j) - b(i, j)) / std::sqrt(b(i, i) * b(j, j)));
    }
  }
  return worst;
}

// The estimate twice, the covariance streamed and from the stored instrument: the same
// parameters bit for bit, the covariance within 1e-12.
void expect_streamed_equals_stored(internal::RefinedIvProblem problem,
                                   const RefinedIvOptions& options, const std::string& label) {
  problem.stored_instrument_covariance = true;
  const EstimationResult stored = internal::run_refined_iv(problem, options);
  problem.stored_instrument_covariance = false;
  const EstimationResult streamed = internal::run_refined_iv(problem, options);
  ASSERT_EQ(stored.covariance.rows(), stored.parameters.size()) << label << ": " << stored.message;
  ASSERT_TRUE(stored.covariance.allFinite()) << label;
  EXPECT_EQ(streamed.parameters, stored.parameters) << label;
  EXPECT_LT(scaled_difference(streamed.covariance, stored.covariance), 1e-12) << label;
  if (options.delay_estimated) {
    EXPECT_GT(stored.delay_standard_error, 0.0) << label;
    EXPECT_NEAR(streamed.delay_standard_error, stored.delay_standard_error,
                1e-12 * stored.delay_standard_error)
        << label;
  }
}

RefinedIvOptions started_at(const AdditiveModel& truth, double factor) {
  RefinedIvOptions options;
  options.initial_model =
      AdditiveModel::from_parameters(truth.orders(), truth.parameters() * factor, 0.0);
  return options;
}

TEST(StreamedCovariance, OpenLoopColouredAndWhiteNoiseWithAnEstimatedDelay) {
  const AdditiveModel truth = testing::open_loop_four_modes();
  const int n = 3 * 4096 + 1500;  // three whole segments of checkpoints and a part
  const Eigen::VectorXd u = white_noise(n, 1.0, 41);
  const SampledData data(
      kH, u,
      simulate(truth, u, kH) + colored_noise(testing::open_loop_noise_filter(), n, 0.02, 42));
  internal::RefinedIvProblem problem;
  problem.records = {&data};
  problem.orders = truth.orders();
  RefinedIvOptions options = started_at(truth, 1.02);
  options.noise = NoiseAssumption::coloured;
  expect_streamed_equals_stored(problem, options, "additive, coloured");
  options.noise = NoiseAssumption::white;
  expect_streamed_equals_stored(problem, options, "additive, white");
  options.noise = NoiseAssumption::coloured;
  options.input_delay_fraction = 0.3;
  options.delay_estimated = true;  // the delay's column joins the instrument
  expect_streamed_equals_stored(problem, options, "additive, coloured, delay column");
  // One unfactored transfer function (SRIVC 8/6): one large submodel.
  problem.orders = {SubmodelOrder{8, 6, 0}};
  problem.unfactored = true;
  options = RefinedIvOptions{};
  options.initial_model = AdditiveModel::from_parameters(
      problem.orders,
      internal::unfactored_parameters(truth.to_transfer_function(), problem.orders.front()), 0.0);
  expect_streamed_equals_stored(problem, options, "SRIVC 8/6, coloured");
}

TEST(StreamedCovariance, ClosedLoopWhiteAndColouredNoise) {
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const DiscreteTransferFunction pid = testing::closed_loop_pid();
  const int n = 9000;
  const Eigen::VectorXd r = white_noise(n, 1.0, 51);
  const ClosedLoopSimulation loop = simulate_closed_loop(truth, pid, r, white_noise(n, 0.1, 52));
  const SampledData data(kH, loop.input, loop.output, r);
  internal::RefinedIvProblem problem;
  problem.records = {&data};
  problem.orders = truth.orders();
  problem.controller = &pid;
  RefinedIvOptions options = started_at(truth, 1.03);
  for (const NoiseAssumption noise : {NoiseAssumption::white, NoiseAssumption::coloured}) {
    options.noise = noise;
    expect_streamed_equals_stored(problem, options,
                                  std::string("closed loop, ") + std::string(enum_name(noise)));
  }
}

TEST(StreamedCovariance, SeveralRecordsWithTheirFreeResponses) {
  // Pieces of one run, none from rest: the free-response columns of each record are zero on
  // the others' rows; lengths below, at and above one segment of checkpoints.
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const int total = 20000;
  const Eigen::VectorXd u = white_noise(total, 1.0, 61);
  const Eigen::VectorXd y =
      simulate(truth, u, kH) + colored_noise(testing::open_loop_noise_filter(), total, 0.01, 62);
  std::vector<SampledData> pieces;
  int from = 300;
  for (const int length : {900, 4096, 4097, 8000}) {
    pieces.emplace_back(kH, u.segment(from, length), y.segment(from, length));
    from += length + 100;
  }
  internal::RefinedIvProblem problem;
  for (const SampledData& piece : pieces) problem.records.push_back(&piece);
  problem.orders = truth.orders();
  RefinedIvOptions options = started_at(truth, 1.02);
  options.initial_conditions = InitialConditions::estimate;
  expect_streamed_equals_stored(problem, options, "four records, free responses");
}

TEST(StreamedCovariance, AdjointArSumIsTheExplicitFormulaWhateverTheChunks) {
  // Chunks newest first of every size, some shorter than the AR order, so the carry is made
  // from several chunks.
  const int n = 5000;
  Eigen::MatrixXd x(n, 3);
  x.col(0) = white_noise(n, 1.0, 71);
  x.col(1) = white_noise(n, 1e-3, 72);
  x.col(2) = white_noise(n, 1e4, 73) + x.col(0);
  const Eigen::VectorXd scales = Eigen::Vector3d(2.0, 1e-3, 5e5);
  AutoregressiveModel ar;
  ar.coefficients = (Eigen::VectorXd(7) << 1.0, -0.9, 0.2, 0.05, -0.1, 0.03, 0.01).finished();
  const Eigen::MatrixXd g = adjoint_ar_filter(x * scales.cwiseInverse().asDiagonal(), ar);
  const Eigen::MatrixXd expected = g * g.transpose();
  internal::AdjointArOuterSum sum(ar, scales);
  const std::vector<int> chunks{1, 2, 3, 1, 1500, 4, 2048, 5, 700};
  int end = n;
  for (size_t c = 0; end > 0; ++c) {
    const int length = std::min(end, chunks[c % chunks.size()]);
    sum.add_earlier(x.middleRows(end - length, length));
    end -= length;
  }
  EXPECT_LT(scaled_difference(sum.sum(), expected), 1e-12);
}

}  // namespace
}  // namespace ctid::streamed_covariance_test
