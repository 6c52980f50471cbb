#include "ctid/core/state_space.h"

#include "ctid/core/error.h"

namespace ctid {

void StateSpace::validate() const {
  const Eigen::Index n = a.rows();
  require(a.cols() == n, "state matrix A is ", a.rows(), "x", a.cols(), "; it must be square");
  require(b.size() == n, "input matrix B has ", b.size(), " rows; A has ", n);
  require(c.size() == n, "output matrix C has ", c.size(), " columns; A has ", n);
  require(a.allFinite() && b.allFinite() && c.allFinite() && std::isfinite(d),
          "state-space matrices must be finite");
}

}  // namespace ctid
