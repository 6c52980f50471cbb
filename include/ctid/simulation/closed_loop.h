// Sampled-data closed loop: r_k -> e_k = r_k - y_k -> C_d(q) -> u_k -> ZOH -> G(p) -> y,
// with output noise v_k added at the samples, y_k = (G u)(t_k) + v_k, from rest. A
// biproper controller with a biproper plant makes u_k depend on y_k (an algebraic loop),
// solved exactly with the factor 1/(1 + D_c D_g). González et al. Section 2 and 6.2.
#pragma once

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/core/hold.h"
#include "ctid/core/state_space.h"
#include "ctid/core/transfer_function.h"

namespace ctid {

struct ClosedLoopSimulation {
  Eigen::VectorXd input;              ///< u_k, the controller output fed to the plant
  Eigen::VectorXd output;             ///< y_k, noise included
  Eigen::VectorXd noise_free_output;  ///< (G u)(t_k), the plant output without v_k
};

/// Discrete closed-loop poles of the ZOH plant (delay included, see zoh_equivalent) in
/// feedback with the controller: eigenvalues of the closed-loop state matrix, so hidden
/// (cancelled) modes count too. Throws InvalidArgument if 1 + D_c D_g = 0 (ill-posed loop).
Eigen::VectorXcd closed_loop_poles(const StateSpace& discrete_plant,
                                   const DiscreteTransferFunction& controller);

/// Whether the loop is well posed with every closed-loop pole inside the unit circle; false
/// (not an exception) otherwise.
bool digital_loop_is_stable(const StateSpace& discrete_plant,
                            const DiscreteTransferFunction& controller);

/// Simulates the loop with sample time controller.sample_time(). `noise` is v_k (same
/// length as `reference`) or empty for none. Throws InvalidArgument if the loop is
/// ill-posed or not stable (some closed-loop pole with |z| >= 1), naming the pole.
ClosedLoopSimulation simulate_closed_loop(const TransferFunction& plant,
                                          const DiscreteTransferFunction& controller,
                                          const Eigen::VectorXd& reference,
                                          const Eigen::VectorXd& noise = Eigen::VectorXd());
ClosedLoopSimulation simulate_closed_loop(const AdditiveModel& plant,
                                          const DiscreteTransferFunction& controller,
                                          const Eigen::VectorXd& reference,
                                          const Eigen::VectorXd& noise = Eigen::VectorXd());
/// The same for a plant already given as its discrete ZOH equivalent.
ClosedLoopSimulation simulate_closed_loop(const StateSpace& discrete_plant,
                                          const DiscreteTransferFunction& controller,
                                          const Eigen::VectorXd& reference,
                                          const Eigen::VectorXd& noise = Eigen::VectorXd());

/// Poles of the analog loop u = C(p)(r - y) around the plant G(p): the roots of
/// den(G) den(C) + num(G) num(C). Throws InvalidArgument if a model is improper or has a delay,
/// or the loop is ill-posed (1 + G C vanishes at infinity: the leading coefficients cancel).
Eigen::VectorXcd analog_closed_loop_poles(const TransferFunction& plant,
                                          const TransferFunction& controller);

/// Whether the analog loop is well posed with every pole's real part negative; false (not an
/// exception) for an improper model, a delay in the loop or an ill-posed loop.
bool analog_loop_is_stable(const TransferFunction& plant, const TransferFunction& controller);

/// The analog loop sampled every `sample_time`: r_k held between the samples as `hold` says,
/// e = r - y, u = C(p) e, x = G(p) u, y = x + v with v_k held (zero-order) as an output
/// disturbance the controller sees; exact at the samples: y = T (r - v) + v, u = C S (r - v),
/// T = G C / (1 + G C), S = 1 / (1 + G C). `noise` is v_k or empty for none. input holds u_k,
/// output y_k, noise_free_output x_k. Throws InvalidArgument as analog_closed_loop_poles does,
/// or naming a closed-loop pole with a real part >= 0.
ClosedLoopSimulation simulate_closed_loop(const TransferFunction& plant,
                                          const TransferFunction& controller,
                                          const Eigen::VectorXd& reference, double sample_time,
                                          const Eigen::VectorXd& noise = Eigen::VectorXd(),
                                          Hold hold = Hold::zero_order_hold);
/// The same for an additive plant (its sum as one transfer function).
ClosedLoopSimulation simulate_closed_loop(const AdditiveModel& plant,
                                          const TransferFunction& controller,
                                          const Eigen::VectorXd& reference, double sample_time,
                                          const Eigen::VectorXd& noise = Eigen::VectorXd(),
                                          Hold hold = Hold::zero_order_hold);

}  // namespace ctid
