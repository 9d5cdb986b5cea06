// Stratimikos set-up: kept in its own translation unit (Ifpack2 and MueLu headers are heavy).
#include "perinox/solver/LinearSolver.hpp"

#include "perinox/solver/LinearSolverValidation.hpp"

#include "perinox/solver/MumpsSolver.hpp"
#include "perinox/solver/TwoStagePreconditioner.hpp"

#include <Stratimikos_DefaultLinearSolverBuilder.hpp>
#include <Stratimikos_MueLuHelpers.hpp>
#include <Teuchos_AbstractFactoryStd.hpp>
#include <Thyra_Ifpack2PreconditionerFactory.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace perinox {

namespace {
using Node = Tpetra::Map<int, long long>::node_type;

/// Stratimikos' validation message in one line of at most 300 characters: Teuchos spreads it
/// over lines (the reason, the sublist, the valid values one a line, a throw count) and, for an
/// unknown key, lists every valid parameter of the sublist.
std::invalid_argument invalidParameters(const std::exception& e) {
  std::string out, line;
  std::istringstream in(e.what());
  while (std::getline(in, line)) {
    const auto b = line.find_first_not_of(" \t{}");
    if (b == std::string::npos || line.compare(b, 12, "Throw number") == 0) continue;
    out += (out.empty() ? "" : " ") + line.substr(b, line.find_last_not_of(" \t{}") - b + 1);
  }
  if (out.size() > 300) out = out.substr(0, 297) + "...";
  return std::invalid_argument("invalid linear solver parameters: " + out);
}

/// The list without perinox's own top-level keys (presetOwnKeys: a preset may name what it is
/// meant for; the scene or evaluatorWithSolver reads them), which Stratimikos would refuse as
/// unknown. params itself when it has none.
Teuchos::RCP<Teuchos::ParameterList> withoutPerinoxKeys(const Teuchos::RCP<Teuchos::ParameterList>& params) {
  const auto& keys = presetOwnKeys();
  if (std::none_of(keys.begin(), keys.end(), [&](const auto& k) { return params->isParameter(k.first); })) return params;
  auto copy = Teuchos::rcp(new Teuchos::ParameterList(*params));
  for (const auto& k : keys) copy->remove(k.first, false);
  return copy;
}

/// Makes the Two-Stage factory with the caller's auxiliary source (Stratimikos asks for a fresh
/// factory object whenever it builds a strategy).
class TwoStageFactoryMaker final : public Teuchos::AbstractFactory<Thyra::PreconditionerFactoryBase<double>> {
 public:
  explicit TwoStageFactoryMaker(std::shared_ptr<AuxiliarySource> source) : source_(std::move(source)) {}
  Teuchos::RCP<Thyra::PreconditionerFactoryBase<double>> create() const override {
    return twoStagePreconditionerFactory(source_);
  }

 private:
  std::shared_ptr<AuxiliarySource> source_;
};

void registerSolvers(Stratimikos::DefaultLinearSolverBuilder& builder,
                     const std::shared_ptr<AuxiliarySource>& auxiliary = nullptr) {
  using Base = Thyra::PreconditionerFactoryBase<double>;
  using Impl = Thyra::Ifpack2PreconditionerFactory<Tpetra::CrsMatrix<double, int, long long, Node>>;
  builder.setPreconditioningStrategyFactory(Teuchos::abstractFactoryStd<Base, Impl>(), "Ifpack2");
  Stratimikos::enableMueLu<int, long long, Node>(builder);
  builder.setLinearSolveStrategyFactory(
      Teuchos::abstractFactoryStd<Thyra::LinearOpWithSolveFactoryBase<double>, MumpsLinearOpWithSolveFactory>(),
      "MUMPS");
  builder.setPreconditioningStrategyFactory(Teuchos::abstractFactoryStd<Base, MumpsPreconditionerFactory>(), "MUMPS");
  builder.setPreconditioningStrategyFactory(Teuchos::rcp(new TwoStageFactoryMaker(auxiliary)), twoStageName());
}
}  // namespace

Teuchos::RCP<Teuchos::ParameterList> defaultLinearSolverParameters() {
  auto p = Teuchos::rcp(new Teuchos::ParameterList("Linear Solver"));
  p->set("Linear Solver Type", "Belos");
  auto& belos = p->sublist("Linear Solver Types").sublist("Belos");
  belos.set("Solver Type", "Block GMRES");
  auto& gm = belos.sublist("Solver Types").sublist("Block GMRES");
  gm.set("Convergence Tolerance", 1e-12);
  gm.set("Maximum Iterations", 2000);
  gm.set("Num Blocks", 200);
  p->set("Preconditioner Type", "Ifpack2");
  auto& ifp = p->sublist("Preconditioner Types").sublist("Ifpack2");
  ifp.set("Prec Type", "RILUK");
  ifp.sublist("Ifpack2 Settings").set("fact: iluk level-of-fill", 2);
  return p;
}

Teuchos::RCP<const Teuchos::ParameterList> validLinearSolverParameters() {
  Stratimikos::DefaultLinearSolverBuilder builder;
  registerSolvers(builder);
  return builder.getValidParameters();
}

Teuchos::RCP<Thyra::LinearOpWithSolveFactoryBase<double>> buildLinearSolverFactory(
    const Teuchos::RCP<Teuchos::ParameterList>& params, int nranks, const std::shared_ptr<AuxiliarySource>& auxiliary) {
  std::string type = params->get<std::string>("Linear Solver Type", "Belos");
  if (type == "Amesos2" && nranks > 1) {
    // This Trilinos build's KLU2 returns wrong solutions on more than one rank
    // (docs/trilinos-notes.md): a direct solve there is MUMPS's (the preset mumps).
    auto mumps = Teuchos::rcp(new Teuchos::ParameterList(params->name()));
    mumps->set("Linear Solver Type", "MUMPS");
    mumps->sublist("Linear Solver Types").sublist("MUMPS").set("Ordering", "Auto");
    mumps->set("Preconditioner Type", "None");
    return buildLinearSolverFactory(mumps, nranks, auxiliary);
  }
  if (type == "Amesos" || params->get<std::string>("Preconditioner Type", "None") == "Ifpack" ||
      params->get<std::string>("Preconditioner Type", "None") == "ML")
    throw std::invalid_argument(
        "Linear Solver Type 'Amesos' and preconditioners 'Ifpack'/'ML' work on Epetra only; "
        "use Amesos2, Ifpack2 or MueLu");
  Stratimikos::DefaultLinearSolverBuilder builder;
  registerSolvers(builder, auxiliary);
  try {
    builder.setParameterList(withoutPerinoxKeys(params));
  } catch (const std::exception& e) {
    throw invalidParameters(e);
  }
  return builder.createLinearSolveStrategy("");
}

SplitLinearSolver buildSplitLinearSolver(const Teuchos::RCP<Teuchos::ParameterList>& params, int nranks,
                                         const std::shared_ptr<AuxiliarySource>& auxiliary) {
  if (params->get<std::string>("Linear Solver Type", "Belos") != "Belos")
    throw std::invalid_argument(
        "a matrix-free or Jacobian-free Newton solve needs a Krylov solver: 'Linear Solver Type' must "
        "be Belos (a direct solver needs the assembled matrix)");
  SplitLinearSolver s;
  auto krylov = Teuchos::rcp(new Teuchos::ParameterList(*withoutPerinoxKeys(params)));
  krylov->set("Preconditioner Type", "None");
  s.krylov = buildLinearSolverFactory(krylov, nranks);
  if (params->get<std::string>("Preconditioner Type", "None") != "None") {
    Stratimikos::DefaultLinearSolverBuilder builder;
    registerSolvers(builder, auxiliary);
    try {
      builder.setParameterList(Teuchos::rcp(new Teuchos::ParameterList(*withoutPerinoxKeys(params))));
    } catch (const std::exception& e) {
      throw invalidParameters(e);
    }
    s.preconditioner = builder.createPreconditioningStrategy("");
  }
  return s;
}

}  // namespace perinox
