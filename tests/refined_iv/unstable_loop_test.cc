// Closed-loop identification of a plant that is unstable and non-minimum-phase inside a stable
// loop (issue 37): the rotary inverted pendulum of tests/support/rotary_pendulum.h.
#include <cmath>
#include <cstdint>
#include <cstdio>

#include <gtest/gtest.h>

#include "ctid/refined_iv/clsrivc.h"
#include "ctid/refined_iv/identification.h"
#include "ctid/refined_iv/srivc.h"
#include "ctid/refined_iv/unstable_clsrivc.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/discretization.h"
#include "support/rotary_pendulum.h"
#include "support/sanitizers.h"

namespace ctid::unstable_loop_test {
namespace {

constexpr SubmodelOrder kOrder{4, 3, 1};

TEST(UnstableLoop, TheScenarioIsUnstableAndNonMinimumPhase) {
  const TransferFunction g = testing::rotary_pendulum_plant();
  const Eigen::VectorXcd poles = g.poles();
  const Eigen::VectorXcd zeros = g.zeros();
  std::printf("poles:");
  for (auto p : poles) std::printf(" %.4g%+.4gj", p.real(), p.imag());
  std::printf("\nzeros:");
  for (auto z : zeros) std::printf(" %.4g%+.4gj", z.real(), z.imag());
  std::printf("\n");
  EXPECT_GT(poles.real().maxCoeff(), 1.0);
  EXPECT_GT(zeros.real().maxCoeff(), 8.0);
  const double radius = closed_loop_poles(zoh_equivalent(g, testing::kPendulumSampleTime),
                                          testing::rotary_pendulum_controller())
                            .cwiseAbs()
                            .maxCoeff();
  std::printf("loop radius %.6f\n", radius);
  EXPECT_LT(radius, 0.992);
}

TEST(UnstableLoop, Diagnose) {
  for (double noise : {0.0, 0.005}) {
    const SampledData data = testing::rotary_pendulum_record(1, 10000, noise);
    std::printf("y std %.4g u std %.4g r std %.4g\n",
                std::sqrt((data.output().array() - data.output().mean()).square().mean()),
                std::sqrt((data.input().array() - data.input().mean()).square().mean()),
                std::sqrt(data.reference().array().square().mean()));
    IdentificationOptions o;
    o.controller = testing::rotary_pendulum_controller();
    o.refined_iv.compute_covariance = false;
    const IdentificationResult auto_fit = identify(data, ModelStructure::unfactored(4, 3, 1), o);
    std::printf("noise %g automatic: %s\n  tf %s\n  fit %.3f cl %.3f usable %d\n", noise,
                auto_fit.estimate.message.c_str(),
                auto_fit.estimate.transfer_function.to_string().c_str(),
                auto_fit.estimate.fit_percent, auto_fit.estimate.closed_loop_fit_percent,
                auto_fit.estimate.verdict.usable);
    o.refined_iv.initial_model = testing::rotary_pendulum_model();
    const IdentificationResult truth_fit = identify(data, ModelStructure::unfactored(4, 3, 1), o);
    std::printf("noise %g truth start: %s\n  tf %s\n  fit %.3f cl %.3f usable %d\n", noise,
                truth_fit.estimate.message.c_str(),
                truth_fit.estimate.transfer_function.to_string().c_str(),
                truth_fit.estimate.fit_percent, truth_fit.estimate.closed_loop_fit_percent,
                truth_fit.estimate.verdict.usable);
    RefinedIvOptions ro;
    ro.compute_covariance = false;
    for (int from_truth = 0; from_truth < 2; ++from_truth) {
      if (from_truth) ro.initial_model = testing::rotary_pendulum_model();
      const EstimationResult e =
          unstable_clsrivc(data, testing::rotary_pendulum_controller(), kOrder, ro);
      std::printf("unstable_clsrivc %s: %s\n  tf %s\n  cl %.4f usable %d %s\n",
                  from_truth ? "truth" : "data", e.message.c_str(),
                  e.transfer_function.to_string().c_str(), e.closed_loop_fit_percent,
                  e.verdict.usable, e.verdict.summary().c_str());
    }
  }
}

}  // namespace
}  // namespace ctid::unstable_loop_test
