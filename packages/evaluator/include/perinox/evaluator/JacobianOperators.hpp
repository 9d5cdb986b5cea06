#pragma once
// The two matrix-free forms of W = df/dx as Tpetra operators (defined in Assembly.cpp): the
// analytic product of the linearised kernels, and the finite difference of f.
#include <Thyra_ModelEvaluator.hpp>
#include <Thyra_VectorBase.hpp>
#include <Tpetra_Operator.hpp>
#include <functional>
#include <vector>

#include "perinox/evaluator/Assembly.hpp"
#include "perinox/evaluator/OperatorAssembly.hpp"
#include "perinox/evaluator/OperatorDiagonal.hpp"

namespace perinox {

using TOperator = Tpetra::Operator<double, LO, GO>;
using TMultiVector = Tpetra::MultiVector<double, LO, GO>;

/// The analytic matrix-free Jacobian: W v = (df_int/du) v from the linearised kernels at the state
/// set by the last evaluation with W_op (its displacements are kept; nothing is assembled).
class JacobianOperator final : public TOperator, public OperatorDiagonal, public OperatorAssembly {
 public:
  JacobianOperator(const Assembler& assembler, const FrozenDofs& frozen, Teuchos::RCP<const TMap> map)
      : assembler_(assembler), frozen_(frozen), map_(std::move(map)) {}
  Teuchos::RCP<const TMap> getDomainMap() const override { return map_; }
  Teuchos::RCP<const TMap> getRangeMap() const override { return map_; }
  bool hasTransposeApply() const override { return false; }
  /// The local displacements (owned and ghost particles) to linearise at.
  void setState(std::vector<double> u) { u_ = std::move(u); }
  void apply(const TMultiVector& X, TMultiVector& Y, Teuchos::ETransp mode, double alpha, double beta) const override;
  /// diag(W) at the state, from the element tangents' diagonal blocks (no matrix formed).
  void getDiagonal(TMultiVector& d) const override;
  /// The assembled Jacobian at the state, by the function the evaluator sets while it sets up a
  /// preconditioner (null outside that).
  void setAssembly(std::function<Teuchos::RCP<const Tpetra::CrsMatrix<double, int, long long>>()> f) {
    assembly_ = std::move(f);
  }
  Teuchos::RCP<const Tpetra::CrsMatrix<double, int, long long>> assembled() const override {
    return assembly_ ? assembly_() : Teuchos::null;
  }

 private:
  std::function<Teuchos::RCP<const Tpetra::CrsMatrix<double, int, long long>>()> assembly_;
  const Assembler& assembler_;
  const FrozenDofs& frozen_;
  Teuchos::RCP<const TMap> map_;
  std::vector<double> u_;
};

/// The Jacobian-free product: W v = (f(x + h v) - f(x)) / h, one residual evaluation per product.
/// NOX's own difference operator takes an absolute floor of lambda^2 for the step, which in SI
/// units (displacements of 1e-3 m, Krylov vectors of 1e-10 m after an ILU preconditioner) is lost
/// in the residual's round-off; here the step is relative to the displacement scale:
/// h |v|_inf = lambda max(|x|_inf, dx).
class DifferenceJacobianOperator final : public TOperator {
 public:
  DifferenceJacobianOperator(const Thyra::ModelEvaluator<double>& model, Teuchos::RCP<const TMap> map, double lambda,
                             double dx)
      : model_(model), map_(std::move(map)), lambda_(lambda), dx_(dx) {}
  Teuchos::RCP<const TMap> getDomainMap() const override { return map_; }
  Teuchos::RCP<const TMap> getRangeMap() const override { return map_; }
  bool hasTransposeApply() const override { return false; }
  /// The state to difference at (f(x) is evaluated once here).
  void setState(const Thyra::VectorBase<double>& x);
  void apply(const TMultiVector& X, TMultiVector& Y, Teuchos::ETransp mode, double alpha, double beta) const override;

 private:
  void evalF(const Thyra::VectorBase<double>& x, Thyra::VectorBase<double>& f) const;
  const Thyra::ModelEvaluator<double>& model_;
  Teuchos::RCP<const TMap> map_;
  double lambda_, dx_;
  Teuchos::RCP<Thyra::VectorBase<double>> x_, f0_;
};

}  // namespace perinox
