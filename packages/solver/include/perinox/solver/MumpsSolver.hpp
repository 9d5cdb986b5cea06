#pragma once
// MUMPS (a multifrontal sparse direct solver, MPI-parallel) as a Thyra linear-solve strategy,
// registered with Stratimikos as "Linear Solver Type" = "MUMPS". This Trilinos build's Amesos2
// offers only KLU2 (wrong answers on more than one rank) and Tacho (crashes beyond small sizes);
// MUMPS comes from Debian's libmumps and factorises the distributed Tpetra matrix on every rank.
//
// Each rank hands MUMPS its own rows (distributed assembled input, 1-based global indices); the
// ordering and symbolic analysis are kept while the sparsity pattern stays the same (every Newton
// iteration of a load step, and every step until bonds break), so a new Jacobian costs a numeric
// factorisation only. Right-hand sides are gathered to rank 0 and the solution scattered back.
// A numerically singular matrix throws std::runtime_error with "factorization failed" in the
// message, which the Newton wrapper reports as a singular tangent and the load stepping cuts back.
#include <Teuchos_ParameterList.hpp>
#include <Teuchos_RCP.hpp>
#include <Thyra_LinearOpWithSolveFactoryBase.hpp>
#include <Thyra_PreconditionerFactoryBase.hpp>

#include <memory>

namespace perinox {

class MumpsLinearOpWithSolveFactory : public Thyra::LinearOpWithSolveFactoryBase<double> {
 public:
  MumpsLinearOpWithSolveFactory();

  bool isCompatible(const Thyra::LinearOpSourceBase<double>& fwdOpSrc) const override;
  Teuchos::RCP<Thyra::LinearOpWithSolveBase<double>> createOp() const override;
  void initializeOp(const Teuchos::RCP<const Thyra::LinearOpSourceBase<double>>& fwdOpSrc,
                    Thyra::LinearOpWithSolveBase<double>* op,
                    const Thyra::ESupportSolveUse supportSolveUse) const override;
  void uninitializeOp(Thyra::LinearOpWithSolveBase<double>* op,
                      Teuchos::RCP<const Thyra::LinearOpSourceBase<double>>* fwdOpSrc,
                      Teuchos::RCP<const Thyra::PreconditionerBase<double>>* prec,
                      Teuchos::RCP<const Thyra::LinearOpSourceBase<double>>* approxFwdOpSrc,
                      Thyra::ESupportSolveUse* supportSolveUse) const override;

  void setParameterList(const Teuchos::RCP<Teuchos::ParameterList>& params) override;
  Teuchos::RCP<Teuchos::ParameterList> getNonconstParameterList() override;
  Teuchos::RCP<Teuchos::ParameterList> unsetParameterList() override;
  Teuchos::RCP<const Teuchos::ParameterList> getParameterList() const override;
  Teuchos::RCP<const Teuchos::ParameterList> getValidParameters() const override;
  std::string description() const override;

 private:
  Teuchos::RCP<Teuchos::ParameterList> params_;
  int ordering_ = 7;        // MUMPS ICNTL(7): 7 = chosen by MUMPS
  int memoryRelaxation_ = 30;  // ICNTL(14), percent of the estimated working space
};

/// Set-ups and factorisations of a MUMPS preconditioner (for tests and summary.json).
struct MumpsPreconditionerStatistics {
  long long setups = 0, factorizations = 0;
  /// Factorisations of an operator that assembled itself for them (the matrix-free Jacobian).
  long long selfAssembled = 0;
  /// The largest factorisation's bytes on all ranks, and the bytes of one entry (8 or 4: 'Factor
  /// Precision' Double or Single).
  long long factorBytes = 0;
  int bytesPerEntry = 0;
  /// Applications of the factors (one per Krylov iteration) and the time of their solves, and the
  /// time of the factorisations (seconds on rank 0; for summary.json, never for tests).
  long long solves = 0;
  double solveSeconds = 0, factorSeconds = 0;
  /// Single-precision factorisations that failed (singular at that precision) and were redone in
  /// double precision.
  long long doublePrecisionFallbacks = 0;
  /// Factorisations made within a solve ('Refactor Within A Solve Above'), counted in factorizations too.
  long long factorizationsDuringSolves = 0;
};

/// MUMPS's LU of the preconditioner matrix as a preconditioner ("Preconditioner Type" = "MUMPS"),
/// for a Krylov solver on the current Jacobian. The factors are kept across set-ups (Newton
/// iterations, load steps, broken bonds) while they still precondition well: a set-up refactorises
/// only when the solve since the previous set-up took more than 'Refactor Above Krylov Iterations'
/// applications, or the rows changed. Near a damaged state a factorisation costs about a hundred
/// residual evaluations and a solve with stale factors a few GMRES iterations
/// (docs/performance.md, "A kept factorisation"). With 'Refactor Within A Solve Above' = k > 0
/// (for a flexible Krylov solver only, which allows the preconditioner to change between
/// iterations) the factors are also renewed within a solve that has applied stale ones k times,
/// once per set-up: the solve goes on with the current Jacobian's factors instead of running to
/// its iteration limit with the old ones.
class MumpsPreconditionerFactory : public Thyra::PreconditionerFactoryBase<double> {
 public:
  MumpsPreconditionerFactory();
  ~MumpsPreconditionerFactory() override;

  bool isCompatible(const Thyra::LinearOpSourceBase<double>& fwdOpSrc) const override;
  Teuchos::RCP<Thyra::PreconditionerBase<double>> createPrec() const override;
  void initializePrec(const Teuchos::RCP<const Thyra::LinearOpSourceBase<double>>& fwdOpSrc,
                      Thyra::PreconditionerBase<double>* prec, const Thyra::ESupportSolveUse supportSolveUse) const override;
  void uninitializePrec(Thyra::PreconditionerBase<double>* prec,
                        Teuchos::RCP<const Thyra::LinearOpSourceBase<double>>* fwdOpSrc,
                        Thyra::ESupportSolveUse* supportSolveUse) const override;

  void setParameterList(const Teuchos::RCP<Teuchos::ParameterList>& params) override;
  Teuchos::RCP<Teuchos::ParameterList> getNonconstParameterList() override;
  Teuchos::RCP<Teuchos::ParameterList> unsetParameterList() override;
  Teuchos::RCP<const Teuchos::ParameterList> getParameterList() const override;
  Teuchos::RCP<const Teuchos::ParameterList> getValidParameters() const override;
  std::string description() const override;

  MumpsPreconditionerStatistics statistics() const;
  /// Drops the kept factors (and MUMPS's analysis): the next set-up factorises afresh, as a run
  /// resumed from a checkpoint does, so the two take the same path bit for bit.
  void renewFactors() const;

 private:
  struct State;
  Teuchos::RCP<Teuchos::ParameterList> params_;
  // The configuration, the factors, the layout they belong to, their applications, the
  // statistics; shared with the operator a set-up hands out, which may refactorise during a solve.
  std::shared_ptr<State> state_;
  mutable Teuchos::RCP<const Thyra::LinearOpSourceBase<double>> src_;
};

/// The statistics of a MumpsPreconditionerFactory (zeros for another factory).
MumpsPreconditionerStatistics mumpsPreconditionerStatistics(const Thyra::PreconditionerFactoryBase<double>& factory);
/// renewFactors of a MumpsPreconditionerFactory (nothing for another factory).
void renewKeptFactors(const Thyra::PreconditionerFactoryBase<double>& factory);

}  // namespace perinox
