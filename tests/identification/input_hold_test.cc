// The input's intersample behaviour, declared on the record (SampledData::input_hold), is what
// the refined IV filters, the automatic start and validation assume: a model driven by a
// piecewise-linear input (first-order hold) is recovered exactly when the record says so, and
// with the zero-order-hold assumption the known bias appears.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "ctid/estimation/validation.h"
#include "ctid/identification/identification.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/excitation.h"

namespace ctid::input_hold_test {
namespace {

constexpr double kH = 0.05;
constexpr int kN = 2000;

// Section 6.2, eq. (46): 3/(0.25p^2 + 0.25p + 1) + 1/(0.025p^2 + 0.01p + 1), as beta.
Eigen::VectorXd true_parameters() {
  Eigen::VectorXd beta(6);
  beta << 0.25, 0.25, 3.0, 0.01, 0.025, 1.0;
  return beta;
}

AdditiveModel truth() {
  return AdditiveModel::from_parameters(std::vector<SubmodelOrder>(2, SubmodelOrder{2, 0, 0}),
                                        true_parameters());
}

// The response from rest to the input linear between its samples, from the FOH
// discretisation of the model's own state-space realisation (not the estimator's filters):
// x_{k+1} = Phi x_k + Gamma0 u_k + Gamma1 u_{k+1}, y_k = C x_k + D u_k.
Eigen::VectorXd piecewise_linear_response(const AdditiveModel& g, const Eigen::VectorXd& u) {
  const StateSpace ss = g.to_transfer_function().to_state_space();
  const FohDiscretization d = discretize_foh(ss.a, ss.b, kH);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(ss.a.rows());
  Eigen::VectorXd y(u.size());
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    y(k) = ss.c.dot(x) + ss.d * u(k);
    const double next = k + 1 < u.size() ? u(k + 1) : u(k);
    x = d.phi * x + d.gamma0.col(0) * u(k) + d.gamma1.col(0) * next;
  }
  return y;
}

SampledData piecewise_linear_record(std::uint64_t seed) {
  const Eigen::VectorXd u = white_noise(kN, 1.0, seed);
  return SampledData(kH, u, piecewise_linear_response(truth(), u))
      .with_input_hold(Hold::first_order_hold);
}

double largest_relative_error(const Eigen::VectorXd& estimate, const Eigen::VectorXd& truth) {
  return ((estimate - truth).cwiseAbs().array() / truth.cwiseAbs().array()).maxCoeff();
}

TEST(InputHold, FirstOrderHoldRecordIsRecoveredExactlyAndZeroOrderHoldIsBiased) {
  const Eigen::VectorXd beta = true_parameters();
  for (std::uint64_t seed : {1U, 2U}) {
    const SampledData data = piecewise_linear_record(seed);
    IdentificationOptions options;
    options.refined_iv.compute_covariance = false;
    const IdentificationResult foh = identify(data, ModelStructure::modes(2), options);
    ASSERT_TRUE(foh.estimate.converged()) << foh.estimate.brief_report();
    EXPECT_LT(largest_relative_error(foh.estimate.parameters, beta), 1e-8) << "seed " << seed;
    EXPECT_TRUE(foh.estimate.verdict.usable);

    const IdentificationResult zoh =
        identify(data.with_input_hold(Hold::zero_order_hold), ModelStructure::modes(2), options);
    EXPECT_GT(largest_relative_error(zoh.estimate.parameters, beta), 1e-3) << "seed " << seed;
  }
}

TEST(InputHold, ValidationSimulatesTheInputAsTheRecordDeclares) {
  const SampledData data = piecewise_linear_record(3);
  const Eigen::VectorXd foh = model_output(truth(), data.input(), kH, Hold::first_order_hold);
  EXPECT_LT((foh - data.output()).cwiseAbs().maxCoeff(),
            1e-9 * data.output().cwiseAbs().maxCoeff());
  EXPECT_GT(validate_model(truth(), data).fit_percent, 99.9999);
  EXPECT_LT(validate_model(truth(), data.with_input_hold(Hold::zero_order_hold)).fit_percent, 99.0);
}

}  // namespace
}  // namespace ctid::input_hold_test
