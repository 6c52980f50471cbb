// Closed-loop simulation on the discrete ZOH equivalent of the plant: per sample, solve the
// loop equation for u_k, then advance plant and controller states.
#include "ctid/simulation/closed_loop.h"

#include <cmath>
#include <complex>
#include <optional>

#include <Eigen/Eigenvalues>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/simulate.h"
#include "simulation/internal/state_recursion.h"

namespace ctid {
namespace {

/// Whether 1 + D_c D_g, the loop's algebraic-loop factor, is clear of zero.
bool well_posed(const StateSpace& plant, const StateSpace& controller) {
  return std::abs(1.0 + controller.d * plant.d) > 1e-12 * (1.0 + std::abs(controller.d * plant.d));
}

/// 1 + D_c D_g; must not vanish.
double loop_factor(const StateSpace& plant, const StateSpace& controller) {
  const double factor = 1.0 + controller.d * plant.d;
  require(well_posed(plant, controller), "closed loop is ill-posed: 1 + D_c D_g = ", factor,
          " (controller feedthrough ", controller.d, ", plant feedthrough ", plant.d, ")");
  return factor;
}

void check_stable(const Eigen::VectorXcd& poles) {
  Eigen::Index worst = 0;
  double radius = 0.0;
  for (Eigen::Index i = 0; i < poles.size(); ++i) {
    if (std::abs(poles(i)) > radius) {
      radius = std::abs(poles(i));
      worst = i;
    }
  }
  require(radius<1.0, "the controller does not stabilise the loop: closed-loop pole z = ",
                 poles.size()> 0
              ? poles(worst)
              : std::complex<double>(),
          " has |z| = ", radius, " >= 1");
}

}  // namespace

Eigen::VectorXcd closed_loop_poles(const StateSpace& discrete_plant,
                                   const DiscreteTransferFunction& controller) {
  discrete_plant.validate();
  const StateSpace c = controller.to_state_space();
  const StateSpace& g = discrete_plant;
  const double s = 1.0 / loop_factor(g, c);
  const int ng = g.order();
  const int nc = c.order();
  // u = s (C_c x_c - D_c C_g x_g) for zero r and v; e = -(C_g x_g + D_g u).
  const Eigen::RowVectorXd u_from_xg = -s * c.d * g.c;
  const Eigen::RowVectorXd u_from_xc = s * c.c;
  Eigen::MatrixXd a(ng + nc, ng + nc);
  a.topLeftCorner(ng, ng) = g.a + g.b * u_from_xg;
  a.topRightCorner(ng, nc) = g.b * u_from_xc;
  a.bottomLeftCorner(nc, ng) = -c.b * (g.c + g.d * u_from_xg);
  a.bottomRightCorner(nc, nc) = c.a - c.b * (g.d * u_from_xc);
  if (a.size() == 0) return Eigen::VectorXcd();
  return Eigen::EigenSolver<Eigen::MatrixXd>(a, false).eigenvalues();
}

bool digital_loop_is_stable(const StateSpace& discrete_plant,
                            const DiscreteTransferFunction& controller) {
  if (!discrete_plant.a.allFinite() || !discrete_plant.b.allFinite() ||
      !discrete_plant.c.allFinite() || !std::isfinite(discrete_plant.d) ||
      !well_posed(discrete_plant, controller.to_state_space())) {
    return false;
  }
  const Eigen::VectorXcd poles = closed_loop_poles(discrete_plant, controller);
  return poles.allFinite() && (poles.size() == 0 || poles.cwiseAbs().maxCoeff() < 1.0);
}

ClosedLoopSimulation simulate_closed_loop(const StateSpace& discrete_plant,
                                          const DiscreteTransferFunction& controller,
                                          const Eigen::VectorXd& reference,
                                          const Eigen::VectorXd& noise) {
  const Eigen::Index n = reference.size();
  require(noise.size() == 0 || noise.size() == n, "noise has ", noise.size(),
          " samples but the reference has ", n, " (give equal lengths, or no noise)");
  for (Eigen::Index k = 0; k < n; ++k) {
    require(std::isfinite(reference(k)), "reference r[", k, "] is not finite (", reference(k), ")");
    if (noise.size() > 0) {
      require(std::isfinite(noise(k)), "noise v[", k, "] is not finite (", noise(k), ")");
    }
  }
  check_stable(closed_loop_poles(discrete_plant, controller));

  const StateSpace c = controller.to_state_space();
  const double s = 1.0 / loop_factor(discrete_plant, c);
  internal::StateRecursion plant(discrete_plant);
  internal::StateRecursion control(c);
  ClosedLoopSimulation result{Eigen::VectorXd(n), Eigen::VectorXd(n), Eigen::VectorXd(n)};
  for (Eigen::Index k = 0; k < n; ++k) {
    const double v = noise.size() > 0 ? noise(k) : 0.0;
    const double plant_free = plant.state_output();
    // u = C_c x_c + D_c (r - C_g x_g - D_g u - v), solved for u.
    const double u = s * (control.state_output() + c.d * (reference(k) - plant_free - v));
    const double y_clean = plant_free + plant.feedthrough() * u;
    const double y = y_clean + v;
    result.input(k) = u;
    result.output(k) = y;
    result.noise_free_output(k) = y_clean;
    plant.advance(u);
    control.advance(reference(k) - y);
  }
  return result;
}

ClosedLoopSimulation simulate_closed_loop(const TransferFunction& plant,
                                          const DiscreteTransferFunction& controller,
                                          const Eigen::VectorXd& reference,
                                          const Eigen::VectorXd& noise) {
  return simulate_closed_loop(zoh_equivalent(plant, controller.sample_time()), controller,
                              reference, noise);
}

ClosedLoopSimulation simulate_closed_loop(const AdditiveModel& plant,
                                          const DiscreteTransferFunction& controller,
                                          const Eigen::VectorXd& reference,
                                          const Eigen::VectorXd& noise) {
  return simulate_closed_loop(zoh_equivalent(plant, controller.sample_time()), controller,
                              reference, noise);
}

namespace {

// den(G) den(C) + num(G) num(C), or none when it is not finite or its leading coefficient
// cancels (1 + G C vanishes at infinity: an ill-posed loop).
std::optional<Polynomial> analog_loop_denominator(const TransferFunction& plant,
                                                  const TransferFunction& controller) {
  const Polynomial acl =
      plant.denominator() * controller.denominator() + plant.numerator() * controller.numerator();
  const int degree = plant.denominator().degree() + controller.denominator().degree();
  const Eigen::VectorXd& c = acl.coefficients();
  if (acl.degree() != degree || !c.allFinite() ||
      !(std::abs(c(degree)) > 1e-12 * c.cwiseAbs().maxCoeff())) {
    return std::nullopt;
  }
  return acl;
}

// y_k of g driven by x held as `hold` says, from rest (exact at the samples).
Eigen::VectorXd held_response(const TransferFunction& g, const Eigen::VectorXd& x, double h,
                              Hold hold) {
  if (hold == Hold::zero_order_hold) return simulate(g, x, h);
  const StateSpace ss = g.to_state_space();
  const FohDiscretization f = discretize_foh(ss.a, ss.b, h);
  Eigen::VectorXd y(x.size());
  Eigen::VectorXd z = Eigen::VectorXd::Zero(ss.a.rows());
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    y(k) = ss.c.dot(z) + ss.d * x(k);
    if (k + 1 < x.size()) z = f.phi * z + f.gamma0.col(0) * x(k) + f.gamma1.col(0) * x(k + 1);
  }
  return y;
}

}  // namespace

Eigen::VectorXcd analog_closed_loop_poles(const TransferFunction& plant,
                                          const TransferFunction& controller) {
  require(plant.is_proper() && controller.is_proper(), "analog loop: the plant ", plant.to_string(),
          " or the controller ", controller.to_string(), " is improper");
  require(plant.input_delay() == 0.0 && controller.input_delay() == 0.0,
          "analog loop: a delay in the loop is not supported (plant ", plant.input_delay(),
          " s, controller ", controller.input_delay(), " s)");
  const std::optional<Polynomial> acl = analog_loop_denominator(plant, controller);
  require(acl.has_value(),
          "analog loop: 1 + G C vanishes at infinity (the plant's and the controller's "
          "feedthroughs cancel), so the loop is ill-posed");
  return acl->degree() > 0 ? acl->roots() : Eigen::VectorXcd(0);
}

bool analog_loop_is_stable(const TransferFunction& plant, const TransferFunction& controller) {
  if (!plant.is_proper() || !controller.is_proper() || plant.input_delay() != 0.0 ||
      controller.input_delay() != 0.0) {
    return false;
  }
  const std::optional<Polynomial> acl = analog_loop_denominator(plant, controller);
  if (!acl) return false;
  const Eigen::VectorXcd poles = acl->degree() > 0 ? acl->roots() : Eigen::VectorXcd(0);
  return poles.allFinite() && (poles.size() == 0 || poles.real().maxCoeff() < 0.0);
}

ClosedLoopSimulation simulate_closed_loop(const TransferFunction& plant,
                                          const TransferFunction& controller,
                                          const Eigen::VectorXd& reference, double sample_time,
                                          const Eigen::VectorXd& noise, Hold hold) {
  require(sample_time > 0.0 && std::isfinite(sample_time), "analog loop: the sample time ",
          sample_time, " must be positive");
  require(noise.size() == 0 || noise.size() == reference.size(), "analog loop: the noise has ",
          noise.size(), " samples and the reference ", reference.size());
  const Eigen::VectorXcd poles = analog_closed_loop_poles(plant, controller);
  for (Eigen::Index k = 0; k < poles.size(); ++k) {
    require(poles(k).real() < 0.0, "analog loop: the controller does not stabilise the plant (",
            "closed-loop pole ", format_number(poles(k).real()), " + ",
            format_number(poles(k).imag()), "i has a real part >= 0)");
  }
  const Polynomial acl = *analog_loop_denominator(plant, controller);  // checked by the poles
  const TransferFunction t(plant.numerator() * controller.numerator(), acl);
  const TransferFunction cs(controller.numerator() * plant.denominator(), acl);
  require(reference.allFinite() && noise.allFinite(),
          "analog loop: the reference or the noise has a sample that is not finite");
  ClosedLoopSimulation out;
  out.noise_free_output = held_response(t, reference, sample_time, hold);
  out.input = held_response(cs, reference, sample_time, hold);
  if (noise.size() > 0) {
    out.noise_free_output -= simulate(t, noise, sample_time);
    out.input -= simulate(cs, noise, sample_time);
  }
  out.output =
      noise.size() > 0 ? Eigen::VectorXd(out.noise_free_output + noise) : out.noise_free_output;
  return out;
}

ClosedLoopSimulation simulate_closed_loop(const AdditiveModel& plant,
                                          const TransferFunction& controller,
                                          const Eigen::VectorXd& reference, double sample_time,
                                          const Eigen::VectorXd& noise, Hold hold) {
  return simulate_closed_loop(plant.to_transfer_function(), controller, reference, sample_time,
                              noise, hold);
}

}  // namespace ctid
