// piro_tension: perinox inside a Trilinos application, without a scene file.
//
// Sample run:  mpiexec -np 2 piro_tension [--solver <prefix>/share/perinox/xml/solvers/mumps.xml] [--output out.json]
//              mpiexec -np 2 piro_tension --loca yes     (LOCA arc-length continuation in lambda from 0 to 1)
//              mpiexec -np 3 piro_tension --distributed yes --solver .../scalable.xml  (each rank builds its share only)
//
// Description: the displacement-driven tension block of xml/tension_block.xml is built in C++ as a
// perinox::ProblemSpec, turned into perinox's Thyra model evaluator, and solved by Piro's NOX
// solver in one Newton solve at load factor 1, or (--loca yes) by Piro's LOCA solver: pseudo-arc-length
// continuation in the load factor p(0) from 0 to 1 along the path. out.json holds the mean displacement of the pulled
// end and the reaction on the pulled layer in summary.json's layout: they equal
// `perinox run xml/tension_block.xml --set "Solver/Load Steps=1"` (tests/compare_runs.py).
// With --distributed yes the problem is built distributed (problemOnLocalLattice): each rank
// generates and keeps only its owned particles and those within two horizons of them, selects the
// regions on that share, and hands the evaluator the regions' global ids; the answer is the same.
#include <LOCA_Stepper.H>
#include <Piro_LOCASolver.hpp>
#include <Piro_NOXSolver.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <iostream>

#include <perinox/io/HostOutput.hpp>
#include <perinox/solver/EvaluatorSetup.hpp>
#include <perinox/solver/NoxExtensions.hpp>

using namespace perinox;

/// LOCA through Piro: arc-length continuation in p(0) ("Load Factor") from the unloaded state to 1,
/// each point corrected by NOX with the status tests above; the probes at the last point.
int continuation(Teuchos::ParameterList& piro, const Teuchos::RCP<PeridynamicEvaluator>& evaluator, const std::vector<int>& end,
                 const std::vector<int>& right, const std::string& outputFile) {
  auto& stepper = piro.sublist("LOCA").sublist("Stepper");
  stepper.set("Continuation Method", "Arc Length");
  stepper.set("Continuation Parameter", "Load Factor");  // the evaluator's get_p_names(0)
  stepper.set("Initial Value", 0.0);
  stepper.set("Min Value", -1.0);  // LOCA requires both bounds (an exception without "Min Value")
  stepper.set("Max Value", 1.0);
  stepper.set("Max Steps", 50);
  stepper.set("Compute Eigenvalues", false);
  piro.sublist("LOCA").sublist("Predictor").set("Method", "Tangent");  // dx/dlambda from DfDp
  piro.sublist("LOCA").sublist("Step Size").set("Initial Step Size", 0.05);
  piro.sublist("LOCA").sublist("Step Size").set("Max Step Size", 0.25);
  evaluator->setLoadFactor(0.0);  // LOCA starts from the nominal values: x = 0 at lambda = 0
  Piro::LOCASolver<double> solver(Teuchos::rcpFromRef(piro), evaluator, Teuchos::null);
  auto out = solver.createOutArgs();
  auto x = Thyra::createMember(solver.get_g_space(solver.Ng() - 1));
  out.set_g(solver.Ng() - 1, x);
  solver.evalModel(solver.getNominalValues(), out);
  const double lambda = solver.getStepper()->getSolutionGroup()->getParam(0);
  evaluator->setLoadFactor(lambda);  // the diagnostics below (the reaction) at the last point
  const int steps = solver.getStepper()->getStepNumber();
  writeProbeSummary(outputFile, *evaluator->comm(),
                    {{"right end", "displacement", {{lambda, evaluator->meanDisplacement(*x, end)}}},
                     {"reaction", "reaction", {{lambda, evaluator->reactionOn(*x, right)}}}},
                    "\"continuation_steps\": " + std::to_string(steps));
  if (evaluator->comm()->getRank() == 0) std::cout << "LOCA: " << steps << " continuation steps to load factor " << lambda << "\n";
  return std::abs(lambda - 1.0) <= 1e-12 ? 0 : 3;  // 3: the path did not reach load factor 1
}

int run(const std::string& solverFile, const std::string& outputFile, bool loca, bool distributed,
        const Teuchos::RCP<const Teuchos::Comm<int>>& comm) {
  // 1. The problem: [0,1] x [0,0.5] m, 20 x 10 particles, fictitious layers outside both ends; rollers
  //    u_x = 0 on the left layer, u_y = 0 on its bottom rows, the pull u_x = 0.1 X on the right layer.
  LatticeSpec lattice;
  lattice.upper = Vec3(1.0, 0.5, 0.0);
  lattice.counts = {20, 10, 1};
  lattice.horizonFactor = 1.015;
  lattice.fictitiousSides = {Side::XMin, Side::XMax};
  const MaterialSpec material{MaterialKind::Hencky, 2, PlanarMode::PlaneStrain, 1.0e9, 0.3};
  auto problem = distributed ? problemOnLocalLattice(comm, lattice, material) : problemOnLattice(lattice, material);
  const Discretization& d = problem->disc;
  const auto rightLayer = selectFictitiousSide(d, Side::XMax);
  prescribe(*problem, selectFictitiousSide(d, Side::XMin), 0);
  prescribe(*problem, selectBox(d, Vec3(-1.0, 0.0, 0.0), Vec3(0.0, 0.03, 0.0), Population::Fictitious), 1);
  prescribe(*problem, rightLayer, 0, [](const Vec3& X) { return 0.1 * X[0]; });
  // The probes' regions as the evaluator names particles (global ids; the same ids unless distributed).
  const auto right = problem->globalIds(rightLayer);
  const auto end = problem->globalIds(selectSideLayer(d, Side::XMax, d.dx * (1 - 1e-9)));

  // 2. The model evaluator (it validates the problem) with the linear solver of the preset file
  //    (checked first: one sentence for a misspelt key, before any work).
  auto evaluator = evaluatorWithSolver(comm, problem, solverFile);

  // 3. Piro's NOX solver: full Newton until |F| < 1e-12 |F(x0)| or |F| at twice its round-off scale
  //    (NOX's default |F| < 1e-8 means nothing for forces of 1e7 N), at most 30 iterations.
  NewtonOptions newton;
  newton.maxIterations = 30;
  newton.floorFactor = 2.0;
  auto piro = Teuchos::rcp(new Teuchos::ParameterList("Piro"));
  piro->set("Exit on Failed NOX Solve", true);
  piro->sublist("NOX").setParameters(*newtonParametersWithStatusTests(newton, 1e-12, evaluator->roundoffScale()));
  if (loca) return continuation(*piro, evaluator, end, right, outputFile);
  evaluator->setLoadFactor(1.0);  // the parameter p(0): Piro passes on its nominal value, this one
  Piro::NOXSolver<double> solver(piro, evaluator);

  // 4. Solve. Piro's input x is Newton's initial guess, the solution its last response. From zero the
  //    whole pull sits on the bonds next to the right layer and Newton inverts particles: start from
  //    the uniform stretch u = (0.1 X, 0) (DOFs named particle * dim + component; prescribed ones
  //    are skipped).
  auto guess = Thyra::createMember(evaluator->get_x_space());
  Thyra::assign(guess.ptr(), 0.0);
  std::vector<std::pair<long long, double>> stretch;
  for (long long p : evaluator->ownedParticles()) stretch.push_back({p * d.dim + 0, 0.1 * d.X[problem->index(p)][0]});
  evaluator->setOwnedDofValues(*guess, stretch);
  auto in = solver.createInArgs();
  in.set_x(guess);
  auto out = solver.createOutArgs();
  auto x = Thyra::createMember(solver.get_g_space(solver.Ng() - 1));
  out.set_g(solver.Ng() - 1, x);
  solver.evalModel(in, out);

  // 5. Results (global values): the probes as summary.json holds them.
  const auto mean = evaluator->meanDisplacement(*x, end), reaction = evaluator->reactionOn(*x, right);
  const int iterations = solver.getSolver()->getNOXSolver()->getNumIterations();
  writeProbeSummary(outputFile, *comm, {{"right end", "displacement", {{1.0, mean}}}, {"reaction", "reaction", {{1.0, reaction}}}},
                    "\"newton_iterations\": " + std::to_string(iterations));
  if (comm->getRank() == 0)
    std::cout << std::setprecision(12) << "Newton iterations " << iterations << "\nmean u_x of the pulled end " << mean[0]
              << " m\nreaction on the pulled layer " << reaction[0] << " N\n";
  return 0;
}

int main(int argc, char** argv) {
  return hostMain(argc, argv, "piro_tension",
                  {{"solver", PERINOX_PRESETS "/mumps.xml"}, {"output", "piro_tension.json"}, {"loca", "no"}, {"distributed", "no"}},
                  [](const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const HostOptions& o) {
                    for (const char* flag : {"loca", "distributed"})
                      if (o.at(flag) != "yes" && o.at(flag) != "no")
                        throw std::invalid_argument(std::string("--") + flag + " must be yes or no, not '" + o.at(flag) + "'");
                    return run(o.at("solver"), o.at("output"), o.at("loca") == "yes", o.at("distributed") == "yes", comm);
                  });
}
