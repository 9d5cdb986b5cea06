#pragma once
// Checks a Stratimikos linear-solver list (a preset of xml/solvers, or a scene's custom
// 'Solver/Linear Solver') before any work, so that a misspelt key or an unusable choice is refused
// with one sentence instead of being ignored or failing at the first load step. The Trilinos
// headers stay in LinearSolverValidation.cpp.
#include <string>
#include <utility>
#include <vector>

namespace Teuchos {
class ParameterList;
}

namespace perinox {

/// Throws std::invalid_argument with one sentence "<where>: ..." naming the key by its scene path
/// ('Solver/Linear Solver/...') when the list has
///  - a key that does not exist at a level with a known parameter list: Stratimikos' top level (plus
///    perinox's own keys, presetOwnKeys()), 'Linear Solver Types/<name>' (Belos,
///    Amesos2, MUMPS, ...), Belos' 'Solver Types/<solver>' sublists (each against that Belos solver's
///    own valid parameters), 'Preconditioner Types/Ifpack2' and its 'Ifpack2 Settings' (for the
///    RELAXATION family also against the chosen preconditioner's own list), MueLu's simple
///    parameter list and its 'level N' sublists (against MueLu's master list);
///    with "did you mean" when a valid name is close;
///  - a value of the wrong type, or a value a Trilinos validator refuses (e.g. MUMPS 'Ordering');
///  - an unknown 'Linear Solver Type' / 'Preconditioner Type', Belos 'Solver Type', Ifpack2
///    'Prec Type' or Amesos2 'Solver Type' (only those Stratimikos' Amesos2 adapter offers in this
///    build), an Epetra-only strategy (Amesos, Ifpack, ML: a bad cast at the first solve), or a
///    missing 'Linear Solver Type' (and 'Preconditioner Type' with Belos), whose Stratimikos
///    defaults (Amesos, Ifpack) are Epetra-only;
///  - a Belos 'Convergence Tolerance', 'Maximum Iterations', 'Num Blocks' or 'Block Size' <= 0.
/// Not checked (accepted as given): the contents of MueLu's 'smoother: params', 'coarse: params'
/// and other sublists it passes on, MueLu lists in 'Hierarchy' (factory) or ML syntax, and MueLu
/// values such as 'multigrid algorithm' (MueLu checks those when it builds its hierarchy).
/// 'where' (the scene file, or "preset 'gmres-ilu'") starts the sentence; empty: no prefix.
void validateLinearSolverList(const Teuchos::ParameterList& stratimikos, const std::string& where);

/// perinox's own top-level keys a preset may carry besides Stratimikos' (what it is meant for),
/// each with its allowed values in the order of the evaluator's enums (JacobianMode,
/// PreconditionerMatrix): "Jacobian", "Preconditioner Matrix", "Forcing Term". The validation
/// checks them, buildLinearSolverFactory leaves them out, evaluatorWithSolver(file) reads them.
const std::vector<std::pair<std::string, std::vector<std::string>>>& presetOwnKeys();

}  // namespace perinox
