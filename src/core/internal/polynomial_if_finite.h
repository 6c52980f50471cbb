// Polynomial::from_roots, the product and Polynomial::anti_monic as values (decision 0045): the
// polynomial, or none with the reason those functions throw, for callers that steer on whether a
// set of poles makes a representable denominator (a start whose poles overflow is not a candidate).
// Private to ctid's layers.
#pragma once

#include <optional>
#include <string>

#include <Eigen/Core>

#include "ctid/core/polynomial.h"

namespace ctid::internal {

/// Polynomial::from_roots(roots, leading), or none when a root is not finite, the roots are
/// not in complex-conjugate pairs or a coefficient overflows; the reason in `failure` if given.
std::optional<Polynomial> polynomial_from_roots(const Eigen::VectorXcd& roots, double leading = 1.0,
                                                std::string* failure = nullptr);

/// a * b, or none when a coefficient of the product overflows (where the product throws).
std::optional<Polynomial> product_if_finite(const Polynomial& a, const Polynomial& b);

/// p.anti_monic(), or none when p's constant coefficient is zero or dividing by it overflows;
/// the reason in `failure` if given.
std::optional<Polynomial> anti_monic_if_finite(const Polynomial& p, std::string* failure = nullptr);

}  // namespace ctid::internal
