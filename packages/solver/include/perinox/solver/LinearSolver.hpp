#pragma once
// Linear solvers through Stratimikos, chosen in XML: Amesos2 (KLU2) direct, Belos with an
// Ifpack2 or MueLu preconditioner. Ifpack2 and MueLu are registered here (this build's
// Stratimikos does not know them for Tpetra by itself).
#include <Teuchos_ParameterList.hpp>
#include <Teuchos_RCP.hpp>
#include <Thyra_LinearOpWithSolveFactoryBase.hpp>
#include <Thyra_PreconditionerFactoryBase.hpp>

#include <memory>

namespace perinox {

class AuxiliarySource;  // TwoStagePreconditioner.hpp

/// Default Stratimikos parameters: Belos block GMRES (the tangent is not always symmetric
/// once damage is on) with an Ifpack2 ILU(k) preconditioner.
Teuchos::RCP<Teuchos::ParameterList> defaultLinearSolverParameters();

/// Builds the factory. Throws std::invalid_argument with a clear sentence when the choice is
/// unusable here (unknown solver or preconditioner names, Epetra-only ones). The Amesos2 direct
/// solver on more than one rank becomes MUMPS (this Trilinos build's KLU2 returns wrong answers
/// in parallel). auxiliary
/// feeds "Preconditioner Type" = "Two-Stage" (the `scalable` preset; makeAuxiliarySource in
/// AuxiliaryOperators.hpp makes perinox's); without it that preconditioner refuses to set up.
/// perinox's own keys a preset may carry ("Jacobian", "Preconditioner Matrix", "Forcing Term")
/// are left out of what Stratimikos sees, so a preset file can be passed as read.
Teuchos::RCP<Thyra::LinearOpWithSolveFactoryBase<double>> buildLinearSolverFactory(
    const Teuchos::RCP<Teuchos::ParameterList>& params, int nranks,
    const std::shared_ptr<AuxiliarySource>& auxiliary = nullptr);

/// For matrix-free solves: the Krylov solver with no preconditioner of its own, and the
/// preconditioner factory named by "Preconditioner Type" (null for None), which the model
/// evaluator applies to the matrix it assembles for preconditioning (W_prec).
struct SplitLinearSolver {
  Teuchos::RCP<Thyra::LinearOpWithSolveFactoryBase<double>> krylov;
  Teuchos::RCP<Thyra::PreconditionerFactoryBase<double>> preconditioner;
};
SplitLinearSolver buildSplitLinearSolver(const Teuchos::RCP<Teuchos::ParameterList>& params, int nranks,
                                         const std::shared_ptr<AuxiliarySource>& auxiliary = nullptr);

/// Valid Stratimikos parameters (for validation before any work).
Teuchos::RCP<const Teuchos::ParameterList> validLinearSolverParameters();

}  // namespace perinox
