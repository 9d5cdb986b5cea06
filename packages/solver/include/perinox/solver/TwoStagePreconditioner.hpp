#pragma once
// The two-stage preconditioner of the `scalable` preset (docs/performance.md, "Preconditioner
// study for issue 19"): a smoother S on the Jacobian J itself around one algebraic-multigrid
// V-cycle V of an auxiliary matrix A, a local elasticity operator on the same particles,
// symmetric multiplicative:
//
//     y = S r;   y += V (r - J y);   y += S (r - J y).
//
// A discretises the same elasticity as J and is spectrally equivalent to it uniformly in the
// resolution, so V removes the smooth error whatever the particle count; S removes the
// oscillatory error where J and A differ (the wide horizon, the stabilisation). A lives on an
// "all-DOF" map (every component of every owned particle, prescribed components as scaled unit
// rows) so that MueLu sees a constant block size; the preconditioner restricts it to J's free
// DOFs. An AuxiliarySource supplies A; this header knows no peridynamics (a host application may
// supply its own).
//
// J is either an assembled Tpetra::CrsMatrix (S is then an Ifpack2 smoother on it) or any
// Tpetra::Operator, e.g. the matrix-free Jacobian (S is then a Chebyshev iteration on that
// operator scaled by J's diagonal when the operator gives it, perinox::OperatorDiagonal, else by
// A's diagonal on J's rows; its largest eigenvalue found by the power method and warm-started
// between set-ups): nothing of J's size is stored.
#include <Teuchos_ParameterList.hpp>
#include <Teuchos_RCP.hpp>
#include <Thyra_PreconditionerFactoryBase.hpp>
#include <Tpetra_CrsMatrix_fwd.hpp>
#include <Tpetra_Map_fwd.hpp>
#include <Tpetra_MultiVector_fwd.hpp>
#include <Tpetra_Operator_fwd.hpp>

#include <memory>
#include <string>
#include <vector>

namespace perinox {

/// What the two-stage preconditioner needs besides J.
struct AuxiliaryOperator {
  /// The auxiliary matrix on the all-DOF map: blockSize consecutive rows per particle.
  Teuchos::RCP<const Tpetra::CrsMatrix<double, int, long long>> matrix;
  /// Its near-null space (the rigid-body modes) on the all-DOF map.
  Teuchos::RCP<const Tpetra::MultiVector<double, int, long long>> nullspace;
  /// Particle coordinates, one row per particle (the map of the owned particles), dim columns.
  Teuchos::RCP<const Tpetra::MultiVector<double, int, long long>> coordinates;
  /// J's local row k (an owned free DOF) is the all-DOF map's local row freeToAll[k].
  std::vector<int> freeToAll;
  int blockSize = 1;
  /// The body can soften and break bonds (damage on): its tangent is then smoothed less well by
  /// the Chebyshev steps on J alone, and "Auxiliary Fine Smoothing" = Auto keeps the auxiliary
  /// hierarchy's own finest-level smoother.
  bool damage = false;
  /// Changes whenever the matrix does: the multigrid hierarchy is rebuilt only then.
  long long version = 0;
};

/// Supplies the auxiliary operator; asked once per preconditioner set-up (every Newton iteration).
class AuxiliarySource {
 public:
  virtual ~AuxiliarySource() = default;
  /// The operator for the Jacobian about to be preconditioned (the same version while A does
  /// not change, e.g. until bonds break).
  virtual const AuxiliaryOperator& current() = 0;
  /// One line for the log: which operator, its size.
  virtual std::string description() const = 0;
};

/// Stratimikos' name of the strategy ("Preconditioner Type" = "Two-Stage").
inline const char* twoStageName() { return "Two-Stage"; }

/// The Thyra preconditioner factory (registered in Stratimikos by buildLinearSolverFactory when
/// given a source). Its parameter list ("Preconditioner Types/Two-Stage"):
///   "Fine Smoother" (string, an Ifpack2 type, default CHEBYSHEV) and its "Fine Smoother
///   Parameters" (Ifpack2 list; default Chebyshev degree 2, eigenvalue ratio 7);
///   "MueLu" (MueLu's list for the hierarchy of A);
///   "Warm Eigenvalue Iterations" (operator J: power
///   iterations at each set-up after the first, default 3);
///   "Auxiliary Fine Smoothing" (Auto | Always | Never: MueLu's smoother on the auxiliary matrix's
///   finest level; Auto: only with damage, since the Chebyshev steps on J smooth that level);
///   "Auxiliary Operator" (Auto | Lattice FEM | Short Horizon) and "Auxiliary Horizon Factor"
///   (for Short Horizon), read by whoever builds the source (makeAuxiliarySource).
/// Without a source (e.g. for validation), set-up throws a sentence saying what is missing.
Teuchos::RCP<Thyra::PreconditionerFactoryBase<double>> twoStagePreconditionerFactory(
    std::shared_ptr<AuxiliarySource> source);

/// The factory's valid parameters (with defaults).
Teuchos::RCP<const Teuchos::ParameterList> twoStageValidParameters();

/// The two pieces the factory composes, for programs that compose their own (the preconditioner
/// study, drivers/bench_preconditioners.cpp):
/// an operator on the all-DOF map seen on J's free DOFs, y_free = (M [x_free; 0])_free ...
Teuchos::RCP<const Tpetra::Operator<double, int, long long>> freeRestriction(
    Teuchos::RCP<const Tpetra::Operator<double, int, long long>> inner,
    Teuchos::RCP<const Tpetra::Map<int, long long>> freeMap, std::vector<int> freeToAll);
/// ... and y = S r; y += V (r - J y); y += S (r - J y).
Teuchos::RCP<const Tpetra::Operator<double, int, long long>> twoStageOperator(
    Teuchos::RCP<const Tpetra::Operator<double, int, long long>> J,
    Teuchos::RCP<const Tpetra::Operator<double, int, long long>> S,
    Teuchos::RCP<const Tpetra::Operator<double, int, long long>> V);

/// ... and the V-cycle of a MueLu hierarchy (a MueLu::TpetraOperator) as the factory applies it:
/// entered at level 1 when the finest level has no smoother (its residual from a zero guess is the
/// right-hand side: no product with the finest matrix), else the hierarchy itself. The same
/// numbers as the hierarchy's own apply. mueluParameters: the list the hierarchy was built from
/// (its "repartition: rebalance P and R" says whether a repartitioned level 1 is reached by an
/// import, as MueLu does, or not).
Teuchos::RCP<const Tpetra::Operator<double, int, long long>> auxiliaryCycle(
    Teuchos::RCP<const Tpetra::Operator<double, int, long long>> hierarchy, const Teuchos::ParameterList& mueluParameters);

/// Statistics of the factory's set-ups (for tests and reports): hierarchies built and reused.
struct TwoStageStatistics {
  long long setups = 0, hierarchiesBuilt = 0;
  /// Products with J the power method took for the matrix-free smoother's eigenvalue estimates.
  long long eigenvalueProducts = 0;
  /// Set-ups that scaled it by the operator's own diagonal (OperatorDiagonal), not A's.
  long long operatorDiagonals = 0;
  int levels = 0;
  /// Hierarchies of more than one level whose finest level MueLu smooths (a PreSmoother or
  /// PostSmoother on level 0): see "Auxiliary Fine Smoothing".
  long long fineSmoothedHierarchies = 0;
  /// Hierarchies whose V-cycle is entered at level 1 (auxiliaryCycle): no product with the
  /// auxiliary matrix in an application.
  long long coarseEntryHierarchies = 0;
};
/// The statistics of a factory made by twoStagePreconditionerFactory (zeros for another one).
TwoStageStatistics twoStageStatistics(const Thyra::PreconditionerFactoryBase<double>& factory);

}  // namespace perinox
