// A linearised rotary inverted pendulum (Furuta; QUBE-Servo-2-like parameters) balanced by an
// inner loop on the pendulum angle and positioned by an outer loop on the arm angle (issue 37).
//
// Model class. The arm angle theta and the pendulum angle alpha (upright: alpha = 0) obey
//   M q'' + D q' + K q = [km/Rm; 0] V,  q = [theta; alpha],
//   M = [[Jr + Mp Lr^2, -Mp Lp Lr/2], [-Mp Lp Lr/2, Jp + Mp Lp^2/4]],
//   D = diag(Dr + km^2/Rm, Dp),  K = diag(0, -Mp Lp g/2),
// with the motor voltage V as input (back-EMF folded into the arm's damping). The inner
// balancing loop is an analog PD with filtered derivative on alpha,
//   V = v - C_in(p) alpha,  C_in = kp + kd p / (tau p + 1),
// so that the plant seen by the outer controller, v -> theta, is a finite continuous transfer
// function (a discrete inner loop would make it a sampled-data system that no rational G(p)
// describes exactly; the inner loop of a real rig runs at many times the outer rate, and an
// analog one is its limit). That plant keeps the free arm's integrator, has a real unstable
// pole (a PD on alpha alone balances the pendulum but lets the arm drift away exponentially)
// and the pendulum's right-half-plane zero: unstable and non-minimum-phase, as in issue 37.
// The outer loop is a discrete PD with filtered derivative on theta at 500 Hz, the reference a
// low-pass filtered white noise, the arm encoder's noise white.
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/core/polynomial.h"
#include "ctid/core/sampled_data.h"
#include "ctid/core/transfer_function.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/excitation.h"

namespace ctid::testing {

/// Sample time of the rig's controllers and logs [s] (500 Hz).
inline constexpr double kPendulumSampleTime = 0.002;

/// v -> theta with the inner (analog) balancing loop closed, as B(p) / (p A(p)) with A
/// anti-monic: 4 non-zero poles (a fast filtered-derivative pair near -58 +- 96j, -11.5, and
/// the unstable +1.34), one integrator, zeros at -100, -12.7 and +8.97.
inline TransferFunction rotary_pendulum_plant() {
  const double mr = 0.095, lr = 0.085, mp = 0.024, lp = 0.129;
  const double jr = mr * lr * lr / 12.0, jp = mp * lp * lp / 12.0;
  const double dr = 0.0015, dp = 0.0005, rm = 8.4, km = 0.042, g = 9.81;
  const double j1 = jr + mp * lr * lr, j2 = jp + 0.25 * mp * lp * lp;
  const double c = 0.5 * mp * lp * lr, kg = 0.5 * mp * lp * g;
  const double bu = km / rm;
  const Polynomial m11{0.0, dr + km * km / rm, j1};
  const Polynomial m12{0.0, 0.0, -c};
  const Polynomial m22{-kg, dp, j2};
  const Polynomial det = m11 * m22 - m12 * m12;
  const Polynomial n_theta = bu * m22;                      // theta / V
  const Polynomial n_alpha = bu * Polynomial{0.0, 0.0, c};  // alpha / V
  const double kp = 30.0, kd = 2.0, tau = 0.01;
  const Polynomial cn{kp, kp * tau + kd};
  const Polynomial cd{1.0, tau};
  const Polynomial den = det * cd + cn * n_alpha;  // = p A(p) up to scale (den[0] = 0)
  const Polynomial num = n_theta * cd;
  const double scale = den[1];
  Eigen::VectorXd d = den.coefficients() / scale;
  d(0) = 0.0;  // exactly one integrator (den[0] cancels analytically)
  return TransferFunction(num * (1.0 / scale), Polynomial(d));
}

/// The same plant as one submodel B / (p A), A anti-monic (an initial_model for the estimators).
inline AdditiveModel rotary_pendulum_model() {
  const TransferFunction g = rotary_pendulum_plant();
  const Eigen::VectorXd d = g.denominator().coefficients();
  return AdditiveModel(
      {Submodel{Polynomial(Eigen::VectorXd(d.tail(d.size() - 1))), g.numerator(), 1}});
}

/// The outer positioning loop: v_k = C_d(q)(r_k - theta_k), a PD with a derivative filtered
/// at tau = 0.01 s (backward Euler), C_d = kp + kd (q - 1) / ((tau + h) q - tau), kp = -2,
/// kd = -1.3: the loop's poles are inside |z| < 0.991.
inline DiscreteTransferFunction rotary_pendulum_controller() {
  const double h = kPendulumSampleTime, kp = -2.0, kd = -1.3, tau = 0.01;
  const Polynomial den{-tau, tau + h};
  const Polynomial num = kp * den + kd * Polynomial{-1.0, 1.0};
  return DiscreteTransferFunction(num, den, h);
}

/// The reference: white noise of standard deviation `level` through 0.1 / (1 - 0.9 q^-1)
/// (a low-pass at about 50 rad/s, unit gain at DC).
inline Eigen::VectorXd rotary_pendulum_reference(int samples, double level, std::uint64_t seed) {
  const Eigen::VectorXd e = white_noise(samples, level, seed);
  Eigen::VectorXd r(samples);
  double state = 0.0;
  for (int k = 0; k < samples; ++k) {
    state = 0.9 * state + 0.1 * e(k);
    r(k) = state;
  }
  return r;
}

/// One logged record: reference (std 1 rad before the filter), the outer controller's
/// output, the arm angle with white encoder noise of standard deviation noise_std (none if 0).
inline SampledData rotary_pendulum_record(std::uint64_t seed, int samples, double noise_std) {
  const Eigen::VectorXd r = rotary_pendulum_reference(samples, 1.0, seed);
  const Eigen::VectorXd v =
      noise_std > 0.0 ? white_noise(samples, noise_std, 5000 + seed) : Eigen::VectorXd();
  const ClosedLoopSimulation loop =
      simulate_closed_loop(rotary_pendulum_plant(), rotary_pendulum_controller(), r, v);
  return SampledData(kPendulumSampleTime, loop.input, loop.output, r);
}

}  // namespace ctid::testing
