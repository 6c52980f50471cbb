#include <cmath>

#include "core/internal/balance.h"

namespace ctid::internal {

Eigen::VectorXd balance_in_place(Eigen::MatrixXd& a) {
  const Eigen::Index n = a.rows();
  Eigen::VectorXd scale = Eigen::VectorXd::Ones(n);
  constexpr double kRadix = 2.0;
  constexpr int kMaxSweeps = 100;  // converges in a handful of sweeps in practice
  bool changed = true;
  for (int sweep = 0; changed && sweep < kMaxSweeps; ++sweep) {
    changed = false;
    for (Eigen::Index i = 0; i < n; ++i) {
      double column = 0.0;
      double row = 0.0;
      for (Eigen::Index j = 0; j < n; ++j) {
        if (j == i) continue;
        column += std::abs(a(j, i));
        row += std::abs(a(i, j));
      }
      if (column == 0.0 || row == 0.0) continue;
      // Column i is multiplied by f and row i divided by f; f is a power of the radix
      // chosen to bring the two norms within a factor radix of each other.
      const double sum = column + row;
      double f = 1.0;
      double c = column;
      while (c < row / kRadix) {
        c *= kRadix * kRadix;
        f *= kRadix;
      }
      while (c >= row * kRadix) {
        c /= kRadix * kRadix;
        f /= kRadix;
      }
      if ((column * f + row / f) < 0.95 * sum) {
        changed = true;
        scale(i) *= f;
        a.row(i) /= f;
        a.col(i) *= f;
      }
    }
  }
  return scale;
}

}  // namespace ctid::internal
