#pragma once
// An operator that can assemble itself into a matrix when asked: the matrix-free Jacobian
// implements it while its evaluator sets up a preconditioner, so a preconditioner that needs a
// matrix only now and then (the kept MUMPS factorisation) pays for the assembly only when it
// refactorises.
#include <Teuchos_RCP.hpp>
#include <Tpetra_CrsMatrix_fwd.hpp>

namespace perinox {

class OperatorAssembly {
 public:
  virtual ~OperatorAssembly() = default;
  /// The operator as an assembled matrix on its own rows, at its current state (collective);
  /// null when it cannot be assembled now.
  virtual Teuchos::RCP<const Tpetra::CrsMatrix<double, int, long long>> assembled() const = 0;
};

}  // namespace perinox
