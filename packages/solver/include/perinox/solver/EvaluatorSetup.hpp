#pragma once
// What every host does before its first solve: perinox's evaluator for a ProblemSpec with its
// linear solver (Stratimikos list checked, the Two-Stage preconditioner's auxiliary operator,
// matrix-free modes), and the NOX pieces of a Newton solve made the way NewtonSolver makes them.
#include <Teuchos_Comm.hpp>
#include <Teuchos_ParameterList.hpp>
#include <Teuchos_RCP.hpp>
#include <memory>
#include <string>

#include "perinox/evaluator/PeridynamicEvaluator.hpp"

namespace perinox {

/// How NOX gets the Jacobian (a scene's Solver/Jacobian, Preconditioner Matrix and Jacobian-Free
/// Perturbation): assembled, or matrix-free / Jacobian-free with a preconditioner from `matrix`.
struct JacobianChoice {
  JacobianMode mode = JacobianMode::Assembled;
  PreconditionerMatrix matrix = PreconditionerMatrix::Neighbours;
  double jacobianFreeLambda = 1e-6;
};

/// perinox's evaluator for `problem` with the linear solver of the Stratimikos list `linear`,
/// which is checked first (validateLinearSolverList; `where` names the list in its message, e.g.
/// "preset 'mumps'"): a misspelt Belos, Ifpack2 or MueLu key would be ignored by Trilinos. The
/// Two-Stage preconditioner gets its auxiliary operator from the evaluator. Throws
/// std::invalid_argument (one sentence) for a bad problem or list.
Teuchos::RCP<PeridynamicEvaluator> evaluatorWithSolver(const Teuchos::RCP<const Teuchos::Comm<int>>& comm,
                                                       std::shared_ptr<const ProblemSpec> problem,
                                                       const Teuchos::ParameterList& linear, const std::string& where,
                                                       const JacobianChoice& jacobian = JacobianChoice());

/// The same with the linear solver read from an XML file (a preset such as
/// <prefix>/share/perinox/xml/solvers/mumps.xml; its "Jacobian" and "Preconditioner Matrix" keys,
/// if any, choose the Jacobian).
Teuchos::RCP<PeridynamicEvaluator> evaluatorWithSolver(const Teuchos::RCP<const Teuchos::Comm<int>>& comm,
                                                       std::shared_ptr<const ProblemSpec> problem,
                                                       const std::string& solverFile);

}  // namespace perinox
