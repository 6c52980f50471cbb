// Continuous-time closed loop with a delay in the feedback path, y = W u with
// W = F / (1 + F H e^{-Δs}) (De Iuliis, Germani, Manes 2017, Section 2, eqs. 1-2), and the
// equivalent form W = α / (β + γ e^{-Δs}). Ground-truth simulation by the method of steps:
// on each delay interval the delayed signal is known from the previous one (dense cubic
// Hermite output), and the state is integrated by RK4 on a grid refined inside each sample
// period and broken at every multiple of Δ. Zero initial state and zero history on [-Δ, 0).
#pragma once

#include <cstdint>
#include <functional>
#include <string_view>
#include <tuple>

#include <Eigen/Core>

#include "ctid/core/fields.h"
#include "ctid/core/hold.h"
#include "ctid/core/polynomial.h"
#include "ctid/core/transfer_function.h"

namespace ctid {

/// The loop of the paper's Fig. 1: e = u - (H y)(t - Δ), y = F e. F and H strictly proper.
struct DelayedFeedbackLoop {
  TransferFunction forward;   ///< F(s), strictly proper, no input delay
  TransferFunction feedback;  ///< H(s), strictly proper, no input delay
  double delay = 0.0;         ///< Δ >= 0 [s], in the feedback path

  /// Throws InvalidArgument naming the rule broken (properness, Δ < 0, delays inside F/H).
  void validate() const;
  /// W(s) = F / (1 + F H e^{-Δs}).
  std::complex<double> closed_loop_response(std::complex<double> s) const;
  /// α = N_F D_H, β = D_F D_H, γ = N_F N_H (eq. 1) with F and H normalised to monic
  /// denominators, so β is monic of degree n + m.
  Polynomial alpha() const;
  Polynomial beta() const;
  Polynomial gamma() const;
};

/// dx/dt = A x + B u(t) + E z(t - Δ),  z = G x,  y = C x. x = 0 and z = 0 for t <= 0.
struct DelayedStateSpace {
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  Eigen::VectorXd e;
  Eigen::RowVectorXd c;
  Eigen::RowVectorXd g;
  double delay = 0.0;

  void validate() const;
};

/// State [x_F; x_H] with x_H driven by y; z = y_H is fed back through -B_F.
DelayedStateSpace to_delayed_state_space(const DelayedFeedbackLoop& loop);
/// W = α / (β + γ e^{-Δs}) realised as y = (α/β) u - (γ/β) y(t - Δ); requires deg α < deg β,
/// deg γ < deg β, β of degree >= 1.
DelayedStateSpace to_delayed_state_space(const Polynomial& alpha, const Polynomial& beta,
                                         const Polynomial& gamma, double delay);

struct DelayedSimulationOptions {
  /// RK4 steps per sample period (more are added when Δ is shorter than a step).
  int substeps = 20;

  static constexpr std::string_view type_name = "DelayedSimulationOptions";
  static constexpr auto fields() {
    return std::tuple{field("substeps", &DelayedSimulationOptions::substeps,
                            Between{1, 100000, true, true}, "RK4 steps per sample period.")};
  }
  /// Throws InvalidArgument naming the field, its value and the rule.
  void validate() const { validate_fields(*this); }
};

/// Output samples y(kδ), k = 0..samples-1, for an input given as a function of time.
Eigen::VectorXd simulate_delayed(const DelayedStateSpace& model,
                                 const std::function<double(double)>& input, double sample_time,
                                 int samples, const DelayedSimulationOptions& options = {});
/// Output samples for a sampled input continued by `hold`; y has the size of u.
Eigen::VectorXd simulate_delayed(const DelayedStateSpace& model, const Eigen::VectorXd& input,
                                 double sample_time, Hold hold,
                                 const DelayedSimulationOptions& options = {});

/// The identification input of the paper's Section 4:
/// u(t) = 1 + sum_{k=1}^{K} sqrt2 (sin(2πkt/T) + cos(2πkt/T)). Periodic with period T.
struct FourierBasisInput {
  int harmonics = 12;   ///< K = 2(n+m) in the paper
  double period = 5.0;  ///< T [s]
  double operator()(double t) const;
};

/// Gaussian white output noise scaled so that the realised
/// NSR = mean|noise| / mean|signal| equals the request exactly (the paper's definition).
struct NoisyOutput {
  Eigen::VectorXd output;  ///< signal + noise
  Eigen::VectorXd noise;
};
NoisyOutput add_noise_at_nsr(const Eigen::VectorXd& signal, double noise_to_signal,
                             std::uint64_t seed);

}  // namespace ctid
