// piro_tension: perinox inside a Trilinos application, without a scene file.
//
// The displacement-driven tension block of xml/tension_block.xml is built in C++ as a
// perinox::ProblemSpec, turned into perinox's Thyra model evaluator, and solved by Piro's NOX
// solver in one Newton solve at load factor 1, with a linear solver from perinox's Stratimikos
// factory. The answer equals `perinox run xml/tension_block.xml --set "Solver/Load Steps=1"`.
//
//   mpiexec -np 2 piro_tension --solver <prefix>/share/perinox/xml/solvers/mumps.xml --output out.json
//
// Prints and writes (as summary.json's "probes", which tests/compare_runs.py reads) the mean
// displacement of the pulled end (the last column of real particles) and the reaction on the pulled layer.
#include <Piro_NOXSolver.hpp>
#include <Teuchos_CommHelpers.hpp>
#include <Teuchos_DefaultComm.hpp>
#include <Teuchos_XMLParameterListHelpers.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <Tpetra_Core.hpp>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <string>

#include <perinox/evaluator/PeridynamicEvaluator.hpp>
#include <perinox/solver/LinearSolver.hpp>
#include <perinox/solver/LinearSolverValidation.hpp>

int run(int argc, char** argv, const Teuchos::RCP<const Teuchos::Comm<int>>& comm) {
  std::string solverFile, outputFile = "piro_tension.json";
  for (int i = 1; i < argc; i += 2) {
    const std::string option = argv[i];
    if (i + 1 < argc && (option == "--solver" || option == "--output")) {
      (option == "--solver" ? solverFile : outputFile) = argv[i + 1];
    } else {
      if (comm->getRank() == 0) std::cerr << "usage: piro_tension [--solver STRATIMIKOS.xml] [--output FILE.json]\n";
      return 2;
    }
  }

  // --- the problem (xml/tension_block.xml): block [0,1] x [0,0.5] m, 20 x 10 particles, delta = 1.015 dx,
  // fictitious layers (prescribed particles) outside the left and right ends; Hencky, plane strain.
  using namespace perinox;
  auto problem = std::make_shared<ProblemSpec>();
  LatticeSpec lattice;
  lattice.dim = 2;
  lattice.upper = Vec3(1.0, 0.5, 0.0);
  lattice.counts = {20, 10, 1};
  lattice.horizonFactor = 1.015;
  lattice.fictitiousSides = {Side::XMin, Side::XMax};
  problem->disc = buildLattice(lattice);
  problem->material = MaterialSpec{MaterialKind::Hencky, 2, PlanarMode::PlaneStrain, 1.0e9, 0.3};
  // (Silling's stabilisation would be: problem->stabilization = true;
  //  problem->stab = {G, micromodulusC(problem->material, problem->disc.horizon, problem->disc.thickness)};)
  const Discretization& d = problem->disc;
  const auto left = selectFictitiousSide(d, Side::XMin), right = selectFictitiousSide(d, Side::XMax);
  const auto pin = selectBox(d, Vec3(-1.0, 0.0, 0.0), Vec3(0.0, 0.03, 0.0), Population::Fictitious);
  const auto rightEnd = selectSideLayer(d, Side::XMax, d.dx * (1 - 1e-9));
  // Loading at load factor 1: bit c of fixedMask[p] prescribes component c of particle p to prescribed[2p + c].
  problem->fixedMask.assign(d.size(), 0);
  problem->prescribed.assign(2 * d.size(), 0.0);
  problem->bodyForce.assign(2 * d.size(), 0.0);  // no external force: the load is the prescribed pull
  auto prescribe = [&](const std::vector<int>& ids, int c, double gradient) {
    for (int p : ids) {
      problem->fixedMask[p] |= 1u << c;
      problem->prescribed[2 * p + c] = gradient * d.X[p][0];
    }
  };
  prescribe(left, 0, 0.0);   // left rollers: u_x = 0
  prescribe(pin, 1, 0.0);    // the pin, the left layer's bottom row: u_y = 0 (no rigid motion)
  prescribe(right, 0, 0.1);  // the pull: u_x = 0.1 X on the right layer

  // --- the model evaluator with a Stratimikos linear solver (perinox registers Ifpack2, MueLu, MUMPS)
  auto evaluator = Teuchos::rcp(new PeridynamicEvaluator(comm, problem));  // validates the problem
  Teuchos::RCP<Teuchos::ParameterList> linear = Teuchos::rcp(new Teuchos::ParameterList("Linear Solver"));
  if (solverFile.empty()) {  // the mumps preset, in code
    linear->set("Linear Solver Type", "MUMPS");
    linear->sublist("Linear Solver Types").sublist("MUMPS").set("Ordering", "Auto");
    linear->set("Preconditioner Type", "None");
  } else {
    linear = Teuchos::getParametersFromXmlFile(solverFile);
  }
  validateLinearSolverList(*linear, solverFile);  // one sentence for a misspelt key, before any work
  evaluator->set_W_factory(buildLinearSolverFactory(linear, comm->getSize()));
  evaluator->setLoadFactor(1.0);  // the model's parameter p(0): Piro passes on its nominal value, this one

  // --- Piro's NOX solver: full Newton until |F| < 1e-12 |F(x0)| (or F at its round-off floor)
  auto piroParams = Teuchos::rcp(new Teuchos::ParameterList("Piro"));
  piroParams->set("Exit on Failed NOX Solve", true);  // throw instead of returning an unconverged state
  auto& nox = piroParams->sublist("NOX");
  nox.set("Nonlinear Solver", "Line Search Based");
  nox.sublist("Line Search").set("Method", "Full Step");
  nox.sublist("Printing").set("Output Information", 0);
  auto& tests = nox.sublist("Status Tests");
  tests.set("Test Type", "Combo");
  tests.set("Combo Type", "OR");
  tests.set("Number of Tests", 4);
  tests.sublist("Test 0").set("Test Type", "RelativeNormF");
  tests.sublist("Test 0").set("Tolerance", 1e-12);
  tests.sublist("Test 1").set("Test Type", "NormF");  // absolute: twice the residual's round-off scale
  tests.sublist("Test 1").set("Tolerance", 2 * evaluator->roundoffScale());
  tests.sublist("Test 2").set("Test Type", "MaxIters");
  tests.sublist("Test 2").set("Maximum Iterations", 30);
  tests.sublist("Test 3").set("Test Type", "FiniteValue");
  Piro::NOXSolver<double> piro(piroParams, evaluator);

  // Piro's solver is itself a model evaluator; its input x is Newton's initial guess and the
  // solution comes back as its last response. Zero displacements would put the whole pull on the
  // bonds next to the right layer, and the first Newton step inverts particles; start instead from
  // the uniform stretch u = (0.1 X, 0) (free DOFs are numbered by the evaluator: freeDof).
  auto guess = Thyra::createMember(evaluator->get_x_space());
  std::vector<std::pair<long long, double>> stretch;
  for (long long p = evaluator->firstOwned(); p < evaluator->endOwned(); ++p)
    if (evaluator->freeDof(p, 0) >= 0) stretch.push_back({evaluator->freeDof(p, 0), 0.1 * d.X[p][0]});
  Thyra::assign(guess.ptr(), 0.0);
  evaluator->setOwnedFreeValues(*guess, stretch);
  auto in = piro.createInArgs();
  in.set_x(guess);
  auto out = piro.createOutArgs();
  const int solutionIndex = piro.Ng() - 1;
  auto x = Thyra::createMember(piro.get_g_space(solutionIndex));
  out.set_g(solutionIndex, x);
  piro.evalModel(in, out);

  // --- results: mean displacement of the pulled end, reaction on the pulled layer (global values)
  const auto u = evaluator->ownedDisplacements(*x);  // owned particles, interleaved x, y
  double sum[3] = {0, 0, 0}, mean[3] = {0, 0, 0};
  for (int p : rightEnd)
    if (p >= evaluator->firstOwned() && p < evaluator->endOwned()) {
      for (int c = 0; c < 2; ++c) sum[c] += u[2 * (p - evaluator->firstOwned()) + c];
      sum[2] += 1;
    }
  Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, 3, sum, mean);
  for (int c = 0; c < 2; ++c) mean[c] /= mean[2];
  const auto reaction = evaluator->reactionOn(*x, right);
  const int iterations = piro.getSolver()->getNOXSolver()->getNumIterations();
  auto f = Thyra::createMember(evaluator->get_f_space());  // the driver's measure: |f(x)| / |reaction|
  auto fin = evaluator->createInArgs();
  auto fout = evaluator->createOutArgs();
  fin.set_x(x);
  fout.set_f(f);
  evaluator->evalModel(fin, fout);
  const double normalised = Thyra::norm_2(*f) / evaluator->reactionNorm(*x);
  if (comm->getRank() == 0) {
    std::cout << std::setprecision(12) << "Newton iterations " << iterations << ", |R|/|reaction| " << normalised
              << "\nmean u_x of the pulled end " << mean[0] << " m\nreaction on the pulled layer " << reaction[0] << " N\n";
    const auto folder = std::filesystem::path(outputFile).parent_path();
    if (!folder.empty()) std::filesystem::create_directories(folder);
    std::ofstream f(outputFile);
    f << std::setprecision(17) << "{\"ranks\": " << comm->getSize() << ", \"newton_iterations\": " << iterations
      << ",\n \"probes\": {\"right end\": [{\"load_factor\": 1.0, \"displacement\": [" << mean[0] << ", " << mean[1]
      << "]}],\n            \"reaction\": [{\"load_factor\": 1.0, \"reaction\": [" << reaction[0] << ", "
      << reaction[1] << "]}]}}\n";
    if (!f) return 1;
  }
  return 0;
}

int main(int argc, char** argv) {
  Tpetra::ScopeGuard mpi(&argc, &argv);  // MPI and Kokkos, as for any Tpetra program
  auto comm = Teuchos::DefaultComm<int>::getComm();
  try {
    return run(argc, argv, comm);
  } catch (const std::exception& e) {  // perinox's errors are one sentence (a bad problem, a bad list)
    std::cerr << "piro_tension: " << e.what() << "\n";
    return 1;
  }
}
