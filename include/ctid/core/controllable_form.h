// The controllable canonical realisation of N(x)/D(x), deg N <= deg D, in any variable (s for
// continuous-time models, q for discrete-time controllers): A has ones on its superdiagonal
// and last row -D_k/D_n, B = e_n, C_k = (N_k - d D_k)/D_n with d = N_n/D_n. It is the form of
// De Iuliis et al.'s eq. 22 and the one ctid uses wherever a realisation must keep the
// polynomial coefficients visible (controllers, the delayed-feedback loop, the separation).
// Well-conditioned realisations for filtering are elsewhere (TransferFunction::to_state_space).
#pragma once

#include <Eigen/Core>

#include "ctid/core/state_space.h"

namespace ctid {

/// `numerator` and `denominator` hold ascending coefficients; coefficients of the numerator
/// beyond deg D are not read and missing ones are zero. The denominator has degree n >= 0 and
/// a non-zero leading coefficient (not checked here: the callers' models already are).
StateSpace controllable_form(const Eigen::VectorXd& numerator, const Eigen::VectorXd& denominator);

}  // namespace ctid
