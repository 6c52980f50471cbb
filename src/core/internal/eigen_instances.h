// Eigen's dense decompositions, compiled once (src/core/eigen_instances.cc) instead of in every
// unity file that uses them: CMake force-includes this header into every ctid target
// (cmake/CtidOptions.cmake), so the explicit instantiation declarations below stop each file
// from instantiating the decompositions' non-inline members itself. A singular value
// decomposition alone took some 35 s of compile time in each file that named it. Decision 0073.
//
// Only the members are shared; inline functions are still inlined where they are called, and the
// arithmetic is the same code compiled with the same flags, so no result changes. A member
// template (compute() of the eigensolvers) is covered for a dense matrix argument; a call with an
// expression instantiates its own copy, as before.
#ifndef CTID_CORE_INTERNAL_EIGEN_INSTANCES_H
#define CTID_CORE_INTERNAL_EIGEN_INSTANCES_H

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

// PREFIX is `extern` here (a declaration) and empty in eigen_instances.cc (the definition).
#define CTID_EIGEN_INSTANCES(PREFIX)                                             \
  PREFIX template class Eigen::BDCSVD<Eigen::MatrixXd>;                          \
  PREFIX template class Eigen::JacobiSVD<Eigen::MatrixXd>;                       \
  PREFIX template class Eigen::JacobiSVD<Eigen::MatrixXcd>;                      \
  PREFIX template class Eigen::EigenSolver<Eigen::MatrixXd>;                     \
  PREFIX template Eigen::EigenSolver<Eigen::MatrixXd>&                           \
  Eigen::EigenSolver<Eigen::MatrixXd>::compute<Eigen::MatrixXd>(                 \
      const Eigen::EigenBase<Eigen::MatrixXd>&, bool);                           \
  PREFIX template class Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>;          \
  PREFIX template Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>&                \
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>::compute<Eigen::MatrixXd>(      \
      const Eigen::EigenBase<Eigen::MatrixXd>&, int);                            \
  PREFIX template class Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>;         \
  PREFIX template Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>&               \
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>::compute<Eigen::MatrixXcd>(    \
      const Eigen::EigenBase<Eigen::MatrixXcd>&, int);                           \
  PREFIX template class Eigen::HouseholderQR<Eigen::MatrixXd>;                   \
  PREFIX template class Eigen::ColPivHouseholderQR<Eigen::MatrixXd>;             \
  PREFIX template class Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>; \
  PREFIX template class Eigen::FullPivLU<Eigen::MatrixXd>;                       \
  PREFIX template class Eigen::PartialPivLU<Eigen::MatrixXd>;                    \
  PREFIX template class Eigen::PartialPivLU<Eigen::MatrixXcd>;                   \
  PREFIX template class Eigen::LDLT<Eigen::MatrixXd>;                            \
  PREFIX template class Eigen::LLT<Eigen::MatrixXd>;

CTID_EIGEN_INSTANCES(extern)

#endif  // CTID_CORE_INTERNAL_EIGEN_INSTANCES_H
