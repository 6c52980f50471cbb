// Scale invariance (issue 16), open and closed loop, one and several outputs: multiplying the
// output by 10^k multiplies every numerator by 10^k and leaves the poles alone, and stretching
// time by T scales a_q by T^q; the estimators must follow exactly. Noise-free data, so the estimate
// is the truth to rounding. Before the instrument's cascade carried B / ||B||, a gain of 1e6 moved
// the fixed point by 1e-4 and 1e11 ended in singular equations.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/clsrivc.h"
#include "ctid/refined_iv/mimo_srivc.h"
#include "ctid/refined_iv/srivc.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"
#include "support/mimo_systems.h"
#include "support/paper_systems.h"
#include "support/sanitizers.h"

namespace ctid::scaling_test {
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

// Section 6.2's loop: the plant of eq. (46) and the PID, noise-free, with the reference
// white. One unfactored view of the plant: (3 A_2 + A_1) / (A_1 A_2).
struct Loop {
  AdditiveModel plant = testing::closed_loop_two_modes();
  DiscreteTransferFunction pid = testing::closed_loop_pid();
  Eigen::VectorXd r = white_noise(kSamples, 1.0, 5);
  ClosedLoopSimulation run = simulate_closed_loop(plant, pid, r);

  static AdditiveModel unfactored(const AdditiveModel& g) {
    const Submodel& s1 = g.submodels()[0];
    const Submodel& s2 = g.submodels()[1];
    return AdditiveModel({Submodel{s1.a * s2.a, s1.b * s2.a + s2.b * s1.a, 0}});
  }
};

// In closed loop, y and r scaled by g with the controller divided by g give the same u: the
// data of the plant g G under C / g. CLSRIVC (unfactored, 4/2) and the additive closed-loop
// estimator must return g G.
TEST(Scaling, ClosedLoopGainsFrom1eMinus12To1e12RecoverTheSameModel) {
  CTID_SKIP_UNDER_SANITIZERS(
      "the same closed-loop fit at many scales; the closed-loop tests run it once");
  const Loop loop;
  const double h = testing::kPaperSampleTime;
  for (int k = -12; k <= 12; k += 3) {
    const double gain = std::pow(10.0, k);
    const SampledData data(h, loop.run.input, gain * loop.run.noise_free_output, gain * loop.r);
    const DiscreteTransferFunction controller(loop.pid.numerator() * (1.0 / gain),
                                              loop.pid.denominator(), h);
    const AdditiveModel truth = with_gain(loop.plant, gain);
    RefinedIvOptions options;
    options.tolerance = 1e-12;
    const EstimationResult u = clsrivc(data, controller, {4, 2, 0}, options);
    ASSERT_TRUE(u.converged()) << "10^" << k << ": " << u.message;
    EXPECT_LT(largest_relative_error(u.parameters, Loop::unfactored(truth).parameters()), 1e-9)
        << "clsrivc, gain 10^" << k;
    const EstimationResult a = additive_clsrivc(data, controller, loop.plant.orders(), options);
    ASSERT_TRUE(a.converged()) << "10^" << k << ": " << a.message;
    EXPECT_LT(largest_relative_error(a.parameters, truth.parameters()), 1e-9)
        << "additive closed loop, gain 10^" << k;
  }
}

// Stretching time by T leaves the sampled loop alone (the controller acts per sample): the
// same r, u, y with h T are the data of the plant with a_q T^q.
TEST(Scaling, ClosedLoopTimeScalesFrom1eMinus6To1e3RecoverTheSameModel) {
  CTID_SKIP_UNDER_SANITIZERS(
      "the same closed-loop fit at many scales; the closed-loop tests run it once");
  const Loop loop;
  for (int k = -6; k <= 3; ++k) {
    const double t = std::pow(10.0, k);
    const double h = testing::kPaperSampleTime * t;
    std::vector<Submodel> stretched;
    for (const Submodel& s : loop.plant.submodels()) {
      const Polynomial& a = s.a;
      stretched.push_back(Submodel{
          Polynomial{a.coefficients()(0), a.coefficients()(1) * t, a.coefficients()(2) * t * t},
          s.b, 0});
    }
    const AdditiveModel truth(stretched);
    const SampledData data(h, loop.run.input, loop.run.noise_free_output, loop.r);
    const DiscreteTransferFunction controller(loop.pid.numerator(), loop.pid.denominator(), h);
    RefinedIvOptions options;
    options.tolerance = 1e-12;
    const EstimationResult u = clsrivc(data, controller, {4, 2, 0}, options);
    ASSERT_TRUE(u.converged()) << "T = 10^" << k << ": " << u.message;
    EXPECT_LT(largest_relative_error(u.parameters, Loop::unfactored(truth).parameters()), 1e-9)
        << "clsrivc, T = 10^" << k;
    const EstimationResult a = additive_clsrivc(data, controller, truth.orders(), options);
    ASSERT_TRUE(a.converged()) << "T = 10^" << k << ": " << a.message;
    EXPECT_LT(largest_relative_error(a.parameters, truth.parameters()), 1e-9)
        << "additive closed loop, T = 10^" << k;
  }
}

// Several outputs in different units: output j scaled by 10^(k + 3j) scales its residues
// alike; the shared poles and every residue must follow (MIMO estimator, data alone).
TEST(Scaling, MimoOutputsInUnitsFrom1eMinus12To1e12RecoverTheSameModel) {
  const MimoAdditiveModel g = testing::two_mode_structure();
  const double h = testing::kPaperSampleTime;
  Eigen::MatrixXd u(kSamples, g.inputs());
  for (int k = 0; k < g.inputs(); ++k) u.col(k) = white_noise(kSamples, 1.0, 7 + k);
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(kSamples, g.outputs());
  for (int j = 0; j < g.outputs(); ++j) {
    for (int k = 0; k < g.inputs(); ++k) y.col(j) += simulate(g.channel(j, k), u.col(k), h);
  }
  for (int k = -12; k <= 6; k += 3) {
    Eigen::VectorXd scale(g.outputs());
    for (int j = 0; j < g.outputs(); ++j) scale(j) = std::pow(10.0, k + 3 * j);
    const MimoEstimationResult r =
        mimo_srivc(MimoData(h, u, y * scale.asDiagonal()), {{2, 0, 0}, {2, 0, 0}});
    ASSERT_TRUE(r.converged() && r.model) << "10^" << k << ": " << r.message;
    double worst = 0.0;
    for (int i = 0; i < g.size(); ++i) {
      const MimoSubmodel& truth = g[i];
      const MimoSubmodel& estimate = (*r.model)[i];
      worst = std::max(worst,
                       largest_relative_error(estimate.a.coefficients(), truth.a.coefficients()));
      for (int j = 0; j < g.outputs(); ++j) {
        for (int c = 0; c < g.inputs(); ++c) {
          const auto n = static_cast<std::size_t>(j * g.inputs() + c);
          worst = std::max(worst, largest_relative_error(estimate.b[n].coefficients(),
                                                         scale(j) * truth.b[n].coefficients()));
        }
      }
    }
    EXPECT_LT(worst, 1e-9) << "output units 10^" << k << ".." << k + 6;
  }
}

}  // namespace
}  // namespace ctid::scaling_test
