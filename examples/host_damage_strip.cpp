// host_damage_strip: a host application that embeds perinox with its own NOX + Stratimikos set-up
// and perinox's load stepper with damage, and writes its own VTU output. No scene file.
//
// The problem is tests/scenes/damage_detach_strip.xml built in C++: a 9 x 3 strip (spacing 1 mm)
// with two square holes at its middle, pulled apart through fictitious layers to +-0.3 mm in 10
// load steps; Hencky plane strain, Silling's stabilisation G = 0.1, damage (s_min 0.01, s_cr 0.02,
// continuous softening, stall breaks). The answer equals `perinox run tests/scenes/damage_detach_strip.xml`.
//
//   mpiexec -np 2 host_damage_strip --output DIR      (DIR/summary.json: the reaction per step)
#include <NOX_Solver_Factory.H>
#include <NOX_Solver_Generic.H>
#include <NOX_StatusTest_Combo.H>
#include <NOX_StatusTest_FiniteValue.H>
#include <NOX_StatusTest_MaxIters.H>
#include <NOX_Thyra_Vector.H>
#include <Teuchos_DefaultComm.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <Tpetra_Core.hpp>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>

#include <perinox/evaluator/PeridynamicEvaluator.hpp>
#include <perinox/io/Output.hpp>
#include <perinox/solver/LinearSolver.hpp>
#include <perinox/solver/NoxExtensions.hpp>
#include <perinox/stepping/LoadStepper.hpp>
#include <perinox/stepping/PeridynamicDamage.hpp>

using namespace perinox;

/// The problem of damage_detach_strip.xml as a ProblemSpec.
std::shared_ptr<ProblemSpec> strip() {
  auto P = std::make_shared<ProblemSpec>();
  LatticeSpec lattice;
  lattice.dim = 2;
  lattice.upper = Vec3(9.0, 3.0, 0.0);
  lattice.counts = {9, 3, 1};
  lattice.horizonFactor = 1.5;
  lattice.fictitiousSides = {Side::XMin, Side::XMax};
  for (double y : {0.5, 2.5}) {  // the holes take out the middle column's top and bottom particles
    Hole h;
    h.kind = Hole::Kind::Rectangle;
    h.center = Vec3(4.5, y, 0.0);
    h.halfWidths = Vec3(0.3, 0.3, 0.0);
    lattice.holes.push_back(h);
  }
  P->disc = buildLattice(lattice);
  P->material = MaterialSpec{MaterialKind::Hencky, 2, PlanarMode::PlaneStrain, 1000.0, 0.25};
  P->stabilization = true;
  P->stab = {0.1, micromodulusC(P->material, P->disc.horizon, P->disc.thickness)};
  P->damage = true;
  P->damageSpec.sMin = 0.01;
  P->damageSpec.sCr = 0.02;
  P->damageSpec.softening = DamageSpec::Softening::Continuous;
  const int n = P->disc.size();
  P->fixedMask.assign(n, 0);
  P->prescribed.assign(2 * n, 0.0);
  P->bodyForce.assign(2 * n, 0.0);
  for (auto [side, ux] : {std::pair{Side::XMin, -0.3}, std::pair{Side::XMax, 0.3}})
    for (int p : selectFictitiousSide(P->disc, side)) {
      P->fixedMask[p] = 3;  // x and y prescribed: u = (ux, 0) at load factor 1
      P->prescribed[2 * p] = ux;
    }
  return P;
}

/// The host's own Newton solve: NOX's line-search solver on the model, with perinox's counting
/// group and its |R| / |reaction| <= 1e-10 test (NoxExtensions.hpp).
NewtonResult newtonSolve(const Teuchos::RCP<const Thyra::ModelEvaluator<double>>& model,
                         const Teuchos::RCP<const ResidualScale>& scale, Thyra::VectorBase<double>& x) {
  auto params = Teuchos::rcp(new Teuchos::ParameterList("NOX"));
  params->set("Nonlinear Solver", "Line Search Based");
  params->sublist("Line Search").set("Method", "Full Step");
  auto& newton = params->sublist("Direction").sublist("Newton");
  newton.set("Forcing Term Method", "Constant");
  newton.sublist("Linear Solver").set("Tolerance", 1e-12);
  newton.set("Rescue Bad Newton Solve", true);
  params->sublist("Printing").set("Output Information", NOX::Utils::Error);
  auto group = Teuchos::rcp(new CountingGroup(NOX::Thyra::Vector(x.clone_v()), model));
  group->setTolerance(1e-12);
  auto residual = Teuchos::rcp(new NormalizedResidualTest(scale, 1e-10, 2.0, 4));
  auto tests = Teuchos::rcp(new NOX::StatusTest::Combo(NOX::StatusTest::Combo::OR));
  tests->addStatusTest(Teuchos::rcp(new NOX::StatusTest::FiniteValue));
  tests->addStatusTest(residual);
  tests->addStatusTest(Teuchos::rcp(new NOX::StatusTest::MaxIters(25)));
  NewtonResult r;
  try {
    group->computeF();
    auto solver = NOX::Solver::buildSolver(group, tests, params);
    const auto status = solver->solve();
    Thyra::copy(dynamic_cast<const NOX::Thyra::Vector&>(solver->getSolutionGroup().getX()).getThyraVector(),
                Teuchos::ptrFromRef(x));
    r.iterations = solver->getNumIterations();
    r.converged = status == NOX::StatusTest::Converged && residual->getStatus() == NOX::StatusTest::Converged;
  } catch (const std::exception& e) {
    r.failure = e.what();  // an inverted particle, a singular tangent: the stepper cuts back
  }
  r.residuals = residual->history();
  r.reactionNormalised = residual->reactionNormalised();
  r.work = std::max<long long>(r.iterations, static_cast<long long>(r.residuals.size()) - 1);
  r.linear = group->counts();
  if (!r.converged && r.failure.empty()) r.failure = residual->stagnation().empty() ? "no convergence" : residual->stagnation();
  return r;
}

/// Records the reaction on the right grip after every accepted step.
class ReactionProbe : public StepObserver {
 public:
  ReactionProbe(const PeridynamicEvaluator& ev, std::vector<int> grip) : ev_(ev), grip_(std::move(grip)) {}
  void accepted(const StepInfo& s) override { history.push_back({s.loadFactor, ev_.reactionOn(s.x, grip_)}); }
  std::vector<std::pair<double, std::vector<double>>> history;

 private:
  const PeridynamicEvaluator& ev_;
  std::vector<int> grip_;
};

int run(const std::string& outDir, const Teuchos::RCP<const Teuchos::Comm<int>>& comm) {
  const auto problem = strip();
  auto evaluator = Teuchos::rcp(new PeridynamicEvaluator(comm, problem));
  auto linear = Teuchos::rcp(new Teuchos::ParameterList("Linear Solver"));  // MUMPS: any rank count
  linear->set("Linear Solver Type", "MUMPS");
  linear->set("Preconditioner Type", "None");
  evaluator->set_W_factory(buildLinearSolverFactory(linear, comm->getSize()));

  // The stepper drives the model through its load factor p(0); perinox's damage is its policy.
  auto model = Teuchos::rcp(new LoadFactorModel(evaluator));
  model->onLoadFactor([ev = evaluator.get()](double lambda) { ev->setLoadFactor(lambda); });
  const auto scale = Teuchos::rcp(new EvaluatorResidualScale(evaluator));
  LoadStepperOptions options;
  options.loadSteps = 10;
  options.predictor = false;  // as the scene: each step starts from the last converged state
  LoadStepper stepper(model, [&](Thyra::VectorBase<double>& x) { return newtonSolve(model, scale, x); }, options);
  PeridynamicDamageOptions damageOptions;
  damageOptions.breakOnStalls = true;
  PeridynamicDamage damage(*evaluator, damageOptions);
  stepper.setDamagePolicy(&damage);
  ReactionProbe probe(*evaluator, selectFictitiousSide(problem->disc, Side::XMax));
  stepper.addObserver(&probe);
  if (!stepper.run()) {
    if (comm->getRank() == 0) std::cerr << "host_damage_strip: " << stepper.failure() << "\n";
    return 3;
  }

  // Output: this rank's particles with their displacements as VTU, the reaction per step as JSON.
  std::filesystem::create_directories(outDir);
  const auto u = evaluator->ownedDisplacements(stepper.converged());
  std::vector<Eigen::Vector3d> points;
  PointField displacement{"displacement", 3, {}};
  for (long long p = evaluator->firstOwned(); p < evaluator->endOwned(); ++p) {
    points.push_back(problem->disc.X[p]);
    const long long l = p - evaluator->firstOwned();
    displacement.values.insert(displacement.values.end(), {u[2 * l], u[2 * l + 1], 0.0});
  }
  PointField damageIndex{"damage", 1, evaluator->ownedDamage()};
  writeVtu(outDir + "/fields_" + std::to_string(comm->getRank()) + ".vtu", points, {displacement, damageIndex});
  long long broken = 0;
  for (const auto& r : stepper.records()) broken += r.brokenBonds;
  if (comm->getRank() == 0) {
    std::ofstream f(outDir + "/summary.json");
    f << std::setprecision(17) << "{\"ranks\": " << comm->getSize() << ", \"broken_bonds_total\": " << broken
      << ", \"probes\": {\"reaction\": [";
    for (std::size_t k = 0; k < probe.history.size(); ++k)
      f << (k ? ", " : "") << "{\"load_factor\": " << probe.history[k].first << ", \"reaction\": ["
        << probe.history[k].second[0] << ", " << probe.history[k].second[1] << "]}";
    f << "]}}\n";
    std::cout << "converged in " << stepper.records().size() << " steps, " << broken << " bonds broken, "
              << evaluator->detachedParticles().size() << " particles detached; results in " << outDir << "\n";
  }
  return 0;
}

int main(int argc, char** argv) {
  Tpetra::ScopeGuard mpi(&argc, &argv);
  auto comm = Teuchos::DefaultComm<int>::getComm();
  const std::string outDir = argc == 3 && std::string(argv[1]) == "--output" ? argv[2] : "host_damage_strip";
  try {
    return run(outDir, comm);
  } catch (const std::exception& e) {  // perinox's errors are one sentence
    if (comm->getRank() == 0) std::cerr << "host_damage_strip: " << e.what() << "\n";
    return 1;
  }
}
