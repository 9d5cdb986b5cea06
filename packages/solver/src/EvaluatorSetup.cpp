// The evaluator with its linear solver (EvaluatorSetup.hpp).
#include "perinox/solver/EvaluatorSetup.hpp"

#include <Teuchos_XMLParameterListHelpers.hpp>
#include <algorithm>
#include <stdexcept>

#include "perinox/solver/AuxiliaryOperators.hpp"
#include "perinox/solver/LinearSolver.hpp"
#include "perinox/solver/LinearSolverValidation.hpp"
#include "perinox/solver/TwoStagePreconditioner.hpp"

namespace perinox {

Teuchos::RCP<PeridynamicEvaluator> evaluatorWithSolver(const Teuchos::RCP<const Teuchos::Comm<int>>& comm,
                                                       std::shared_ptr<const ProblemSpec> problem,
                                                       const Teuchos::ParameterList& linear, const std::string& where,
                                                       const JacobianChoice& jacobian) {
  validateLinearSolverList(linear, where);
  auto evaluator = Teuchos::rcp(new PeridynamicEvaluator(comm, std::move(problem)));
  const auto params = Teuchos::rcp(new Teuchos::ParameterList(linear));
  // The two-stage preconditioner (preset scalable) gets its auxiliary operator from the model.
  std::shared_ptr<AuxiliarySource> auxiliary;
  if (params->get<std::string>("Preconditioner Type", "None") == twoStageName())
    auxiliary = makeAuxiliarySource(evaluator, params->sublist("Preconditioner Types").sublist(twoStageName()));
  if (jacobian.mode == JacobianMode::Assembled) {
    evaluator->set_W_factory(buildLinearSolverFactory(params, comm->getSize(), auxiliary));
    return evaluator;
  }
  // Matrix-free: Belos without a preconditioner of its own; the model builds the preconditioner
  // from the matrix chosen.
  auto split = buildSplitLinearSolver(params, comm->getSize(), auxiliary);
  evaluator->set_W_factory(split.krylov);
  evaluator->setJacobian(jacobian.mode, jacobian.matrix, split.preconditioner, jacobian.jacobianFreeLambda);
  return evaluator;
}

Teuchos::RCP<PeridynamicEvaluator> evaluatorWithSolver(const Teuchos::RCP<const Teuchos::Comm<int>>& comm,
                                                       std::shared_ptr<const ProblemSpec> problem,
                                                       const std::string& solverFile) {
  Teuchos::RCP<Teuchos::ParameterList> linear;
  try {
    linear = Teuchos::getParametersFromXmlFile(solverFile);
  } catch (const std::exception&) {
    throw std::invalid_argument("cannot read the linear solver list '" + solverFile + "'");
  }
  // A preset may name the Jacobian it is meant for (as a scene's 'Solver/Jacobian = Preset' reads it).
  JacobianChoice choice;
  // The value's place among presetOwnKeys()'s choices for key (their order is the enum's).
  auto take = [&](const std::string& key) -> int {
    if (!linear->isParameter(key)) return -1;
    const std::string v = linear->isType<std::string>(key) ? linear->get<std::string>(key) : std::string();
    linear->remove(key);
    const auto& own = *std::find_if(presetOwnKeys().begin(), presetOwnKeys().end(), [&](const auto& k) { return k.first == key; });
    const auto at = std::find(own.second.begin(), own.second.end(), v);
    if (at == own.second.end())
      throw std::invalid_argument("'" + solverFile + "': '" + key + "' = '" + v + "' is not one of the evaluator's choices");
    return static_cast<int>(at - own.second.begin());
  };
  const int mode = take("Jacobian");
  const int matrix = take("Preconditioner Matrix");
  if (mode >= 0) choice.mode = static_cast<JacobianMode>(mode);
  if (matrix >= 0) choice.matrix = static_cast<PreconditionerMatrix>(matrix);
  return evaluatorWithSolver(comm, std::move(problem), *linear, "'" + solverFile + "'", choice);
}

}  // namespace perinox
