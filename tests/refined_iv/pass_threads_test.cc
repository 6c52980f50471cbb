// Threads inside one fit (RefinedIvOptions::threads, decision 0068): the passes split a step's
// filters over the submodels and add its sums beside the next step's filters, each filter and
// each sum in its own fixed order, so an estimate is the same to the bit with one thread and
// with many. Checked on records a few steps long with a partial last step, for every path of
// the passes: open loop with the coloured-noise covariance and an estimated delay's column,
// closed loop, several records with their free responses, RIVC's prefilter, and the automatic
// count on a long record.
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/core/parallel.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/noise.h"
#include "ctid/simulation/simulate.h"
#include "refined_iv/internal/refined_iv_engine.h"
#include "support/paper_systems.h"

namespace ctid::pass_threads_test {
namespace {

constexpr double kH = testing::kPaperSampleTime;

// The estimate with one thread and with `counts` threads: every number the result carries
// equal, bit for bit.
void expect_same_bits(const internal::RefinedIvProblem& problem, RefinedIvOptions options,
                      const std::string& label, const std::vector<int>& counts = {2, 3, 5}) {
  options.threads = 1;
  const EstimationResult one = internal::run_refined_iv(problem, options);
  ASSERT_GT(one.iterations, 1) << label << ": " << one.message;
  ASSERT_TRUE(one.parameters.allFinite()) << label;
  for (const int threads : counts) {
    options.threads = threads;
    const EstimationResult many = internal::run_refined_iv(problem, options);
    const std::string where = label + ", " + std::to_string(threads) + " threads";
    EXPECT_EQ(many.iterations, one.iterations) << where;
    EXPECT_EQ(many.parameters, one.parameters) << where;
    EXPECT_EQ(many.covariance, one.covariance) << where;
    EXPECT_EQ(many.standard_errors, one.standard_errors) << where;
    EXPECT_EQ(many.mean_squared_error, one.mean_squared_error) << where;
    EXPECT_EQ(many.relative_change, one.relative_change) << where;
    EXPECT_EQ(many.delay_standard_error, one.delay_standard_error) << where;
    EXPECT_EQ(many.message, one.message) << where;
    ASSERT_EQ(many.noise_model.has_value(), one.noise_model.has_value()) << where;
    if (one.noise_model) {
      EXPECT_EQ(many.noise_model->ma, one.noise_model->ma) << where;
      EXPECT_EQ(many.noise_model->ar, one.noise_model->ar) << where;
    }
  }
}

RefinedIvOptions started_at(const AdditiveModel& truth, double factor) {
  RefinedIvOptions options;
  options.initial_model =
      AdditiveModel::from_parameters(truth.orders(), truth.parameters() * factor, 0.0);
  return options;
}

// n samples of `truth` under white noise input (seed), with the paper's coloured output noise
// (seed + 1).
SampledData open_loop_record(const AdditiveModel& truth, int n, std::uint64_t seed) {
  const Eigen::VectorXd u = white_noise(n, 1.0, seed);
  return SampledData(
      kH, u,
      simulate(truth, u, kH) + colored_noise(testing::open_loop_noise_filter(), n, 0.02, seed + 1));
}

TEST(PassThreads, OpenLoopSameBitsWithColouredCovarianceAndADelayColumn) {
  const AdditiveModel truth = testing::open_loop_four_modes();
  // Whole segments of checkpoints, steps and a partial step.
  const SampledData data = open_loop_record(truth, 3 * 4096 + 1500, 81);
  internal::RefinedIvProblem problem;
  problem.records = {&data};
  problem.orders = truth.orders();
  RefinedIvOptions options = started_at(truth, 1.03);
  expect_same_bits(problem, options, "four modes, coloured");
  options.noise = NoiseAssumption::white;
  options.input_delay_fraction = 0.3;
  options.delay_estimated = true;
  expect_same_bits(problem, options, "four modes, white, delay column", {2});
}

TEST(PassThreads, ClosedLoopSameBits) {
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const DiscreteTransferFunction pid = testing::closed_loop_pid();
  const int n = 9000;
  const Eigen::VectorXd r = white_noise(n, 1.0, 83);
  const ClosedLoopSimulation loop = simulate_closed_loop(truth, pid, r, white_noise(n, 0.1, 84));
  const SampledData data(kH, loop.input, loop.output, r);
  internal::RefinedIvProblem problem;
  problem.records = {&data};
  problem.orders = truth.orders();
  problem.controller = &pid;
  expect_same_bits(problem, started_at(truth, 1.03), "closed loop");
}

TEST(PassThreads, SeveralRecordsWithFreeResponsesSameBits) {
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const int total = 16000;
  const Eigen::VectorXd u = white_noise(total, 1.0, 85);
  const Eigen::VectorXd y =
      simulate(truth, u, kH) + colored_noise(testing::open_loop_noise_filter(), total, 0.01, 86);
  std::vector<SampledData> pieces;
  int from = 300;
  for (const int length : {700, 1024, 4097, 9000}) {
    pieces.emplace_back(kH, u.segment(from, length), y.segment(from, length));
    from += length + 50;
  }
  internal::RefinedIvProblem problem;
  for (const SampledData& piece : pieces) problem.records.push_back(&piece);
  problem.orders = truth.orders();
  RefinedIvOptions options = started_at(truth, 1.02);
  options.initial_conditions = InitialConditions::estimate;
  expect_same_bits(problem, options, "four records, free responses");
}

TEST(PassThreads, RivcPrefilterSameBits) {
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const SampledData data = open_loop_record(truth, 6000, 87);
  internal::RefinedIvProblem problem;
  problem.records = {&data};
  problem.orders = truth.orders();
  RefinedIvOptions options = started_at(truth, 1.02);
  options.noise_model = NoiseModelOrders{2, 1};
  expect_same_bits(problem, options, "RIVC ARMA(2,1)", {2});
}

TEST(PassThreads, AutomaticCountOnALongRecordSameBitsAsOne) {
  // 0: every core for a record of at least 100 000 samples (on a one-core machine, one).
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const int n = 100000;
  const Eigen::VectorXd u = white_noise(n, 1.0, 89);
  const SampledData data(kH, u, simulate(truth, u, kH) + white_noise(n, 0.05, 90));
  internal::RefinedIvProblem problem;
  problem.records = {&data};
  problem.orders = truth.orders();
  RefinedIvOptions options = started_at(truth, 1.02);
  expect_same_bits(problem, options, "automatic, N = 1e5", {0});
  // Inside a parallel loop the automatic count is one: the fits there run side by side.
  options.threads = 0;
  std::vector<Eigen::VectorXd> inside(2);
  parallel_for(2, 2, [&](int i) {
    inside[static_cast<size_t>(i)] = internal::run_refined_iv(problem, options).parameters;
  });
  options.threads = 1;
  const Eigen::VectorXd alone = internal::run_refined_iv(problem, options).parameters;
  EXPECT_EQ(inside[0], alone);
  EXPECT_EQ(inside[1], alone);
}

TEST(PassThreads, NegativeCountIsRefusedByName) {
  RefinedIvOptions options;
  options.threads = -1;
  try {
    options.validate();
    FAIL() << "no exception";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("threads"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ctid::pass_threads_test
