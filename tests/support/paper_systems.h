// Example systems of the papers, shared by tests across layers.
// González et al. (../shared/papers/000_a62d478ae91c668d.txt): Section 6.1 (four modes,
// DC gains [3, 0.4, 0.2, 0.05], poles -0.25±1.39i, -0.15±3.16i, -0.17±5.77i, -0.5±9.99i,
// h = 0.05 s) and Section 6.2, eq. (46).
#pragma once

#include <complex>
#include <vector>

#include "ctid/core/additive_model.h"

namespace ctid::testing {

/// B/(1 + a1 p + a2 p^2) with poles sigma ± j omega and static gain `gain`.
inline Submodel mode_from_pole(double sigma, double omega, double gain) {
  const double m2 = sigma * sigma + omega * omega;
  return {Polynomial({1.0, -2.0 * sigma / m2, 1.0 / m2}), Polynomial({gain}), 0};
}

inline AdditiveModel open_loop_four_modes() {
  return AdditiveModel({mode_from_pole(-0.25, 1.39, 3.0), mode_from_pole(-0.15, 3.16, 0.4),
                        mode_from_pole(-0.17, 5.77, 0.2), mode_from_pole(-0.5, 9.99, 0.05)});
}

/// eq. (46): 3/(0.25p^2 + 0.25p + 1) + 1/(0.025p^2 + 0.01p + 1).
inline AdditiveModel closed_loop_two_modes() {
  return AdditiveModel({{Polynomial({1.0, 0.25, 0.25}), Polynomial({3.0}), 0},
                        {Polynomial({1.0, 0.01, 0.025}), Polynomial({1.0}), 0}});
}

}  // namespace ctid::testing
