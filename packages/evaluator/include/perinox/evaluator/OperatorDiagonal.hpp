#pragma once
// An operator that can give its own diagonal without being a matrix: the matrix-free Jacobian
// implements it, and the two-stage preconditioner scales its Chebyshev smoother by it (a host
// application's matrix-free operator may implement it too; without it the preconditioner falls
// back to the auxiliary matrix's diagonal).
#include <Tpetra_MultiVector_fwd.hpp>

namespace perinox {

class OperatorDiagonal {
 public:
  virtual ~OperatorDiagonal() = default;
  /// The diagonal on the operator's range map, in column 0 of d (collective).
  virtual void getDiagonal(Tpetra::MultiVector<double, int, long long>& d) const = 0;
};

}  // namespace perinox
