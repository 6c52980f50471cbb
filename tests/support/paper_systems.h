// The example systems of the papers, defined once for every test and benchmark (C++; the
// Python tests get them from the `paper_systems` fixture of python/tests/conftest.py, which
// mirrors this file). The library's own copy of the Section 6 systems, study_setup()
// (study/paper_study.h), is checked against these bit for bit in tests/study.
//
// González et al. (../shared/papers/000_a62d478ae91c668d.txt):
// - Section 6.1: four modes, DC gains [3, 0.4, 0.2, 0.05], poles -0.25±1.39i, -0.15±3.16i,
//   -0.17±5.77i, -0.5±9.99i, h = 0.05 s, noise filter (q + 0.5)/(q - 0.85);
// - Section 6.2: the plant of eq. (46) under the PID
//   C_d(q) = 0.0115 + 0.00725 q/(q - 1) + 0.00454 (q - 1)/q, h = 0.05 s;
// - Section 7: the beam, taken as the paper's converged four-mode estimate theta_hat_1..4
//   with a 4-sample input delay, h = 1/4096 s, and the paper's deliberately wrong start
//   theta_i^1.
// The delayed-feedback loop of De Iuliis et al. Section 4 is in tests/delayed_feedback.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/core/polynomial.h"

namespace ctid::testing {

/// Sample time of Sections 6.1 and 6.2 [s].
inline constexpr double kPaperSampleTime = 0.05;

/// B/(1 + a1 p + a2 p^2) with poles sigma ± j omega and static gain `gain`.
inline Submodel mode_from_pole(double sigma, double omega, double gain) {
  const double m2 = sigma * sigma + omega * omega;
  return {Polynomial({1.0, -2.0 * sigma / m2, 1.0 / m2}), Polynomial({gain}), 0};
}

/// Section 6.1: the open-loop system, four modes.
inline AdditiveModel open_loop_four_modes() {
  return AdditiveModel({mode_from_pole(-0.25, 1.39, 3.0), mode_from_pole(-0.15, 3.16, 0.4),
                        mode_from_pole(-0.17, 5.77, 0.2), mode_from_pole(-0.5, 9.99, 0.05)});
}

/// Section 6.1: the noise filter H(q) = (q + 0.5)/(q - 0.85), driven by white noise of
/// variance 0.02 in the paper.
inline DiscreteTransferFunction open_loop_noise_filter() {
  return DiscreteTransferFunction(Polynomial({0.5, 1.0}), Polynomial({-0.85, 1.0}),
                                  kPaperSampleTime);
}

/// Section 6.2, eq. (46): 3/(0.25p^2 + 0.25p + 1) + 1/(0.025p^2 + 0.01p + 1).
inline AdditiveModel closed_loop_two_modes() {
  return AdditiveModel({{Polynomial({1.0, 0.25, 0.25}), Polynomial({3.0}), 0},
                        {Polynomial({1.0, 0.01, 0.025}), Polynomial({1.0}), 0}});
}

/// Section 6.2: the PID C_d(q) = kp + ki q/(q - 1) + kd (q - 1)/q with kp = 0.0115,
/// ki = 0.00725, kd = 0.00454, over the common denominator q (q - 1).
inline DiscreteTransferFunction closed_loop_pid() {
  const Polynomial q{0.0, 1.0};
  const Polynomial q_minus_1{-1.0, 1.0};
  const Polynomial numerator =
      0.0115 * q * q_minus_1 + 0.00725 * q * q + 0.00454 * q_minus_1 * q_minus_1;
  return DiscreteTransferFunction(numerator, q * q_minus_1, kPaperSampleTime);
}

/// Section 7: the beam's sample time [s], input delay [samples] and one period of its
/// multisine (0.5-500 Hz) [samples].
inline constexpr double kBeamSampleTime = 1.0 / 4096.0;
inline constexpr int kBeamDelay = 4;
inline constexpr int kBeamPeriod = 8192;

/// Section 7: four second-order modes, no integrators.
inline std::vector<SubmodelOrder> beam_orders() { return {4, SubmodelOrder{2, 0, 0}}; }

/// Section 7: theta_hat_i = [a_i1, a_i2, b_i0] of A_i = 1 + a_i1 p + a_i2 p^2 (eq. 3), the
/// paper's converged estimate, taken here as the true beam.
inline Eigen::VectorXd beam_parameters() {
  Eigen::VectorXd theta(12);
  theta << 0.0024, 0.023, 11.81, 2.33e-5, 1.65e-4, 0.159, 8.59e-7, 1.03e-5, 3.19e-4, 7.55e-7,
      3.55e-6, 1.27e-4;
  return theta;
}

/// Section 7: the paper's start theta_i^1 (deliberately wrong for modes 3 and 4).
inline Eigen::VectorXd beam_start_parameters() {
  Eigen::VectorXd theta(12);
  theta << 0.001, 0.025, 10.0, 5e-5, 1.5e-4, 0.2, 8.5e-7, 2e-5, 0.001, 7.5e-7, 5e-6, 0.01;
  return theta;
}

/// Section 7: the true beam, with its input delay.
inline AdditiveModel beam() {
  return AdditiveModel::from_parameters(beam_orders(), beam_parameters(),
                                        kBeamDelay * kBeamSampleTime);
}

}  // namespace ctid::testing
