// Scale invariance (issue 16): multiplying the output by 10^k multiplies every numerator by
// 10^k and leaves the poles alone, and stretching time by T scales a_q by T^q; the estimators
// must follow exactly. Noise-free data, so the estimate is the truth to rounding. Before the
// instrument's cascade carried B / ||B||, a gain of 1e6 moved the fixed point by 1e-4 and
// 1e11 ended in singular equations.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/srivc.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"
#include "support/paper_systems.h"

namespace ctid {
namespace {

constexpr int kSamples = 2000;

// Largest |estimate / truth - 1| over the coefficients.
double largest_relative_error(const Eigen::VectorXd& estimate, const Eigen::VectorXd& truth) {
  return (estimate.array() / truth.array() - 1.0).abs().maxCoeff();
}

// The model with every numerator multiplied by `gain`.
AdditiveModel with_gain(const AdditiveModel& g, double gain) {
  std::vector<Submodel> submodels;
  for (const Submodel& s : g.submodels()) {
    submodels.push_back(Submodel{s.a, gain * s.b, s.integrators});
  }
  return AdditiveModel(submodels, g.input_delay());
}

TEST(Scaling, GainsFrom1eMinus12To1e12RecoverTheSameModel) {
  // G = 4 / (s^2 + 0.8 s + 4) = 1 / (1 + 0.2 p + 0.25 p^2), the example, from the data
  // alone (SRIVC and the additive estimator), and the four modes of Section 6.1 from the truth.
  const double h = testing::kPaperSampleTime;
  const Eigen::VectorXd u = white_noise(kSamples, 1.0, 3);
  const AdditiveModel mode({Submodel{Polynomial{1.0, 0.2, 0.25}, Polynomial{1.0}, 0}});
  const AdditiveModel four = testing::open_loop_four_modes();
  const Eigen::VectorXd y_mode = simulate(mode, u, h);
  const Eigen::VectorXd y_four = simulate(four, u, h);
  for (int k = -12; k <= 12; k += 2) {
    const double gain = std::pow(10.0, k);
    const SampledData one(h, u, gain * y_mode);
    const Eigen::VectorXd truth = with_gain(mode, gain).parameters();
    const EstimationResult s = srivc(one, {2, 0, 0});
    ASSERT_TRUE(s.converged()) << "10^" << k << ": " << s.message;
    EXPECT_LT(largest_relative_error(s.parameters, truth), 1e-9) << "srivc, gain 10^" << k;
    const EstimationResult a = additive_srivc(one, {{2, 0, 0}});
    ASSERT_TRUE(a.converged()) << "10^" << k << ": " << a.message;
    EXPECT_LT(largest_relative_error(a.parameters, truth), 1e-9) << "additive, gain 10^" << k;

    RefinedIvOptions from_truth;
    from_truth.initial_model = with_gain(four, gain);
    const EstimationResult f =
        additive_srivc(SampledData(h, u, gain * y_four), four.orders(), from_truth);
    ASSERT_TRUE(f.converged()) << "10^" << k << ": " << f.message;
    EXPECT_LT(largest_relative_error(f.parameters, with_gain(four, gain).parameters()), 1e-9)
        << "four modes, gain 10^" << k;
  }
}

TEST(Scaling, TimeScalesFrom1eMinus6To1e3RecoverTheSameModel) {
  const Eigen::VectorXd u = white_noise(kSamples, 1.0, 3);
  for (int k = -6; k <= 3; ++k) {
    const double t = std::pow(10.0, k);
    const double h = 0.05 * t;
    const AdditiveModel mode(
        {Submodel{Polynomial{1.0, 0.2 * t, 0.25 * t * t}, Polynomial{1.0}, 0}});
    const SampledData data(h, u, simulate(mode, u, h));
    const EstimationResult s = srivc(data, {2, 0, 0});
    ASSERT_TRUE(s.converged()) << "T = 10^" << k << ": " << s.message;
    EXPECT_LT(largest_relative_error(s.parameters, mode.parameters()), 1e-9) << "T = 10^" << k;
    const EstimationResult a = additive_srivc(data, {{2, 0, 0}});
    ASSERT_TRUE(a.converged()) << "T = 10^" << k << ": " << a.message;
    EXPECT_LT(largest_relative_error(a.parameters, mode.parameters()), 1e-9) << "T = 10^" << k;
  }
}

}  // namespace
}  // namespace ctid
