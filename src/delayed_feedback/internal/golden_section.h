// Golden-section search shared by the delay scan and the delay identification. Private to
// the delayed_feedback module.
#pragma once

#include <cmath>
#include <utility>

namespace ctid::internal {

// Golden-section search for a minimum of f on [lo, hi] with `iterations` reductions; returns
// the better of the two final interior points and its value.
template <class Function>
std::pair<double, double> golden_section_minimum(Function&& f, double lo, double hi,
                                                 int iterations) {
  const double ratio = (std::sqrt(5.0) - 1.0) / 2.0;
  double x1 = hi - ratio * (hi - lo), x2 = lo + ratio * (hi - lo);
  double f1 = f(x1), f2 = f(x2);
  for (int it = 0; it < iterations; ++it) {
    if (f1 < f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - ratio * (hi - lo);
      f1 = f(x1);
    } else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + ratio * (hi - lo);
      f2 = f(x2);
    }
  }
  return f1 < f2 ? std::make_pair(x1, f1) : std::make_pair(x2, f2);
}

}  // namespace ctid::internal
