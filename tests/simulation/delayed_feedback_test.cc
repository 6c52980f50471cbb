#include "ctid/simulation/delayed_feedback.h"

#include <cmath>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unsupported/Eigen/MatrixFunctions>

#include "ctid/core/error.h"

namespace ctid::delayed_feedback_test {
namespace {

// Independent reference: for t < (J+1)Δ the loop response is the finite Neumann series
// y = sum_{j<=J} (-1)^j F (H F)^j u(t - jΔ). Each term is a cascade realised block by block
// and driven by a ZOH input, which matrix exponentials integrate exactly, at any time.
struct Cascade {
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  Eigen::RowVectorXd c;
};

Cascade first_order(double gain, double pole) {
  Cascade r;
  r.a = Eigen::MatrixXd::Constant(1, 1, -pole);
  r.b = Eigen::VectorXd::Constant(1, gain);
  r.c = Eigen::RowVectorXd::Ones(1);
  return r;
}

Cascade series(const Cascade& first, const Cascade& second) {
  const Eigen::Index n = first.a.rows();
  const Eigen::Index m = second.a.rows();
  Cascade r;
  r.a = Eigen::MatrixXd::Zero(n + m, n + m);
  r.a.topLeftCorner(n, n) = first.a;
  r.a.bottomRightCorner(m, m) = second.a;
  r.a.bottomLeftCorner(m, n) = second.b * first.c;
  r.b = Eigen::VectorXd::Zero(n + m);
  r.b.head(n) = first.b;
  r.c = Eigen::RowVectorXd::Zero(n + m);
  r.c.tail(m) = second.c;
  return r;
}

// Response of `g` to the ZOH input u at time t (u_k held on [kδ, (k+1)δ)), zero for t <= 0.
double zoh_response_at(const Cascade& g, const Eigen::VectorXd& u, double delta, double t) {
  if (t <= 0.0) return 0.0;
  const Eigen::Index n = g.a.rows();
  auto step = [&](double h) {
    Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n + 1, n + 1);
    m.topLeftCorner(n, n) = g.a * h;
    m.topRightCorner(n, 1) = g.b * h;
    return Eigen::MatrixXd(m.exp());
  };
  const Eigen::MatrixXd full = step(delta);
  const int whole = static_cast<int>(std::floor(t / delta + 1e-12));
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  for (int k = 0; k < whole; ++k)
    x = full.topLeftCorner(n, n) * x + full.topRightCorner(n, 1) * u(k);
  const double rest = t - whole * delta;
  if (rest > 1e-12 * delta) {
    const Eigen::MatrixXd part = step(rest);
    x = part.topLeftCorner(n, n) * x + part.topRightCorner(n, 1) * u(whole);
  }
  return g.c.dot(x);
}

Eigen::VectorXd neumann_reference(const Eigen::VectorXd& u, double delta, double delay, int terms) {
  const Cascade f = first_order(1.0, 1.0);
  const Cascade h = first_order(2.0, 3.0);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(u.size());
  Cascade g = f;
  for (int j = 0; j < terms; ++j) {
    const double sign = (j % 2 == 0) ? 1.0 : -1.0;
    for (Eigen::Index k = 0; k < u.size(); ++k)
      y(k) += sign * zoh_response_at(g, u, delta, static_cast<double>(k) * delta - j * delay);
    g = series(series(g, h), f);
  }
  return y;
}

DelayedFeedbackLoop simple_loop(double delay) {
  return {TransferFunction(Polynomial{1.0}, Polynomial{1.0, 1.0}),
          TransferFunction(Polynomial{2.0}, Polynomial{3.0, 1.0}), delay};
}

DelayedFeedbackLoop paper_loop() {
  return {TransferFunction(Polynomial{2.0, 1.0, 2.0}, Polynomial{3.0, 2.0, 3.0, 1.0}),
          TransferFunction(Polynomial{1.0, 5.0, 1.0}, Polynomial{2.0, 2.0, 3.0, 1.0}), 0.5};
}

TEST(DelayedFeedbackSimulation, MatchesNeumannSeriesForZohInputWithIntegerDelay) {
  const double delta = 0.1;
  const int samples = 41;  // T = 4 s = 4 Δ: five terms of the series are exact
  Eigen::VectorXd u(samples);
  for (int k = 0; k < samples; ++k) u(k) = std::sin(0.7 * k) + 0.3 * std::cos(2.1 * k);
  const Eigen::VectorXd y =
      simulate_delayed(to_delayed_state_space(simple_loop(1.0)), u, delta, Hold::zero_order_hold);
  const Eigen::VectorXd ref = neumann_reference(u, delta, 1.0, 5);
  EXPECT_LT((y - ref).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_GT(ref.cwiseAbs().maxCoeff(), 0.1);
}

TEST(DelayedFeedbackSimulation, MatchesNeumannSeriesForFractionalDelay) {
  const double delta = 0.1;
  const double delay = 0.73;  // not a multiple of δ
  const int samples = 31;
  Eigen::VectorXd u(samples);
  for (int k = 0; k < samples; ++k) u(k) = (k % 7 < 3) ? 1.0 : -0.5;
  const Eigen::VectorXd y =
      simulate_delayed(to_delayed_state_space(simple_loop(delay)), u, delta, Hold::zero_order_hold);
  const Eigen::VectorXd ref = neumann_reference(u, delta, delay, 6);
  EXPECT_LT((y - ref).cwiseAbs().maxCoeff(), 1e-7);
}

TEST(DelayedFeedbackSimulation, SmoothStepEqualsClosedForm) {
  // A unit step given as a function of time equals the ZOH of ones.
  const double delta = 0.05;
  const int samples = 61;
  const Eigen::VectorXd y = simulate_delayed(
      to_delayed_state_space(simple_loop(0.5)), [](double) { return 1.0; }, delta, samples);
  const Eigen::VectorXd ref = neumann_reference(Eigen::VectorXd::Ones(samples), delta, 0.5, 7);
  EXPECT_LT((y - ref).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(DelayedFeedbackSimulation, FourierInputConvergesAtFourthOrder) {
  const DelayedStateSpace model = to_delayed_state_space(paper_loop());
  const FourierBasisInput u{12, 5.0};
  auto run = [&](int substeps) {
    return simulate_delayed(model, std::function<double(double)>(u), 0.05, 101,
                            DelayedSimulationOptions{substeps});
  };
  const Eigen::VectorXd fine = run(320);
  const double e5 = (run(5) - fine).cwiseAbs().maxCoeff();
  const double e10 = (run(10) - fine).cwiseAbs().maxCoeff();
  EXPECT_GT(e5 / e10, 10.0);  // ~16 for a fourth-order method
  EXPECT_LT((run(20) - fine).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_GT(fine.cwiseAbs().maxCoeff(), 1.0);
}

TEST(DelayedFeedbackSimulation, ClosedLoopPolynomialFormGivesTheSameResponse) {
  const DelayedFeedbackLoop loop = paper_loop();
  const std::complex<double> s(0.3, 1.7);
  const std::complex<double> w_poly =
      loop.alpha()(s) / (loop.beta()(s) + loop.gamma()(s) * std::exp(-loop.delay * s));
  EXPECT_LT(std::abs(w_poly - loop.closed_loop_response(s)), 1e-12);
  EXPECT_EQ(loop.beta().degree(), 6);
  EXPECT_EQ(loop.gamma().degree(), 4);
  Eigen::VectorXd u(81);
  for (int k = 0; k < 81; ++k) u(k) = std::cos(0.37 * k * k);
  const Eigen::VectorXd y1 =
      simulate_delayed(to_delayed_state_space(loop), u, 0.05, Hold::first_order_hold);
  const Eigen::VectorXd y2 =
      simulate_delayed(to_delayed_state_space(loop.alpha(), loop.beta(), loop.gamma(), loop.delay),
                       u, 0.05, Hold::first_order_hold);
  EXPECT_LT((y1 - y2).cwiseAbs().maxCoeff(), 1e-8);
}

TEST(DelayedFeedbackSimulation, ZeroDelayIsAnOrdinaryFeedbackLoop) {
  // F = 1/(s+1), H = 2/(s+3), Δ = 0: W = (s+3)/((s+1)(s+3)+2) = (s+3)/(s^2+4s+5).
  const Eigen::VectorXd y = simulate_delayed(to_delayed_state_space(simple_loop(0.0)),
                                             Eigen::VectorXd::Ones(21), 0.1, Hold::zero_order_hold);
  Cascade w;
  w.a = Eigen::MatrixXd(2, 2);
  w.a << 0, 1, -5, -4;
  w.b = Eigen::VectorXd(2);
  w.b << 0, 1;
  w.c = Eigen::RowVectorXd(2);
  w.c << 3, 1;
  for (int k = 0; k < 21; ++k)
    EXPECT_NEAR(y(k), zoh_response_at(w, Eigen::VectorXd::Ones(21), 0.1, 0.1 * k), 1e-9);
}

TEST(DelayedFeedbackSimulation, NoiseHasTheRequestedRatioAndIsReplayable) {
  Eigen::VectorXd y(200);
  for (int k = 0; k < 200; ++k) y(k) = std::sin(0.1 * k) + 0.2;
  const NoisyOutput a = add_noise_at_nsr(y, 0.15, 7);
  const NoisyOutput b = add_noise_at_nsr(y, 0.15, 7);
  const NoisyOutput c = add_noise_at_nsr(y, 0.15, 8);
  EXPECT_NEAR(a.noise.cwiseAbs().mean() / y.cwiseAbs().mean(), 0.15, 1e-12);
  EXPECT_EQ(a.output, b.output);
  EXPECT_NE(a.output, c.output);
  EXPECT_LT((a.output - y - a.noise).norm(), 1e-12);
}

TEST(DelayedFeedbackSimulation, FourierBasisInputMatchesThePaper) {
  const FourierBasisInput u{12, 5.0};
  EXPECT_NEAR(u(0.0), 1.0 + 12.0 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(u(1.3), u(6.3), 1e-9);
}

TEST(DelayedFeedbackSimulation, BadInputIsNamed) {
  EXPECT_THAT([] { to_delayed_state_space(simple_loop(-0.1)); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr("delay")));
  DelayedFeedbackLoop improper = simple_loop(0.5);
  improper.forward = TransferFunction(Polynomial{1.0, 1.0}, Polynomial{1.0, 1.0});
  EXPECT_THAT([&] { to_delayed_state_space(improper); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr("strictly proper")));
  EXPECT_THAT(
      [] {
        simulate_delayed(to_delayed_state_space(simple_loop(0.5)), Eigen::VectorXd::Ones(5), 0.0,
                         Hold::zero_order_hold);
      },
      ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr("sample_time")));
  EXPECT_THROW(add_noise_at_nsr(Eigen::VectorXd::Ones(3), -1.0, 1), InvalidArgument);
}

}  // namespace
}  // namespace ctid::delayed_feedback_test
