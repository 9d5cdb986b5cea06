// host_damage_strip: a host application with its own NOX solve inside perinox's load stepper with
// damage, writing its own output. No scene file.
//
// Sample run:  mpiexec -np 2 host_damage_strip --output DIR    (DIR/summary.json: the reaction per step;
//              DIR/fields.pvtu: displacement, stress and damage for ParaView)
//
// Description: tests/scenes/damage_detach_strip.xml built in C++: a 9 x 3 strip (spacing 1 mm) with two
// square holes at its middle, pulled apart through fictitious layers to +-0.3 mm in 10 load steps;
// Hencky plane strain, Silling's stabilisation G = 0.1 (its micromodulus computed by perinox), damage
// (s_min 0.01, s_cr 0.02, continuous softening, stall breaks), MUMPS. The answer equals
// `perinox run tests/scenes/damage_detach_strip.xml`.
#include <NOX_Solver_Factory.H>
#include <iostream>

#include <perinox/io/HostOutput.hpp>
#include <perinox/solver/EvaluatorSetup.hpp>
#include <perinox/solver/NoxExtensions.hpp>
#include <perinox/stepping/LoadStepper.hpp>
#include <perinox/stepping/PeridynamicDamage.hpp>

using namespace perinox;

/// 1. The problem of damage_detach_strip.xml.
std::shared_ptr<ProblemSpec> strip() {
  LatticeSpec lattice;
  lattice.upper = Vec3(9.0, 3.0, 0.0);
  lattice.counts = {9, 3, 1};
  lattice.horizonFactor = 1.5;
  lattice.fictitiousSides = {Side::XMin, Side::XMax};
  for (double y : {0.5, 2.5})  // the holes take out the middle column's top and bottom particles
    lattice.holes.push_back({Hole::Kind::Rectangle, Vec3(4.5, y, 0.0), 0.0, Vec3(0.3, 0.3, 0.0)});
  auto P = problemOnLattice(lattice, {MaterialKind::Hencky, 2, PlanarMode::PlaneStrain, 1000.0, 0.25});
  P->stabilization = true;
  P->stab.G = 0.1;
  P->damage = true;
  P->damageSpec.sMin = 0.01;
  P->damageSpec.sCr = 0.02;
  P->damageSpec.softening = DamageSpec::Softening::Continuous;
  for (auto [side, ux] : {std::pair{Side::XMin, -0.3}, std::pair{Side::XMax, 0.3}}) {
    prescribe(*P, selectFictitiousSide(P->disc, side), 0, ux);  // u = (ux, 0) at load factor 1
    prescribe(*P, selectFictitiousSide(P->disc, side), 1);
  }
  return P;
}

/// 2. The host's own Newton solve: NOX's line-search solver (full step) on perinox's counting group
/// with its |R| / |reaction| <= 1e-10 test, stopped after 4 iterations without halving (NoxExtensions.hpp).
NewtonResult newtonSolve(const Teuchos::RCP<const Thyra::ModelEvaluator<double>>& model,
                         const Teuchos::RCP<const ResidualScale>& scale, Thyra::VectorBase<double>& x) {
  NewtonOptions options;
  options.floorFactor = 2.0;
  options.stagnationStop = 4;
  const auto tests = newtonStatusTests(scale, options.tolerance, options.maxIterations, options.floorFactor, options.stagnationStop);
  const auto group = countingGroup(model, x, options.linearTolerance);
  auto solver = NOX::Solver::buildSolver(group, tests.combo, newtonParameters(options));
  return solveNox(*solver, tests, group.get(), x, options.maxIterations);
}

int run(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const HostOptions& options) {
  auto evaluator = evaluatorWithSolver(comm, strip(), PERINOX_PRESETS "/mumps.xml");  // MUMPS: any rank count

  // 3. The stepper drives the model through its load factor p(0); perinox's damage is its policy.
  auto model = Teuchos::rcp(new LoadFactorModel(evaluator));
  model->onLoadFactor([ev = evaluator.get()](double lambda) { ev->setLoadFactor(lambda); });
  const auto scale = Teuchos::rcp(new EvaluatorResidualScale(evaluator));
  LoadStepperOptions stepping;
  stepping.predictor = false;  // as the scene: each step starts from the last converged state (10 steps)
  LoadStepper stepper(model, [&](Thyra::VectorBase<double>& x) { return newtonSolve(model, scale, x); }, stepping);
  PeridynamicDamageOptions damageOptions;
  damageOptions.breakOnStalls = true;
  PeridynamicDamage damage(*evaluator, damageOptions);
  stepper.setDamagePolicy(&damage);
  const auto grip = selectFictitiousSide(evaluator->problem().disc, Side::XMax);
  ValueRecorder reaction([&](const Thyra::VectorBase<double>& x) { return evaluator->reactionOn(x, grip); });
  stepper.addObserver(&reaction);
  if (!stepper.run()) throw std::runtime_error(stepper.failure());

  // 4. Output: the fields (VTU per rank, PVTU index) and the reaction per step (summary.json).
  const std::string& dir = options.at("output");
  writeParticleFields(dir, *evaluator, stepper.converged());
  const long long broken = stepper.brokenBonds();
  writeProbeSummary(dir + "/summary.json", *comm, {{"reaction", "reaction", reaction.values()}},
                    "\"broken_bonds_total\": " + std::to_string(broken));
  if (comm->getRank() == 0)
    std::cout << "converged in " << stepper.records().size() << " steps, " << broken << " bonds broken, "
              << evaluator->detachedParticles().size() << " particles detached; results in " << dir << "\n";
  return 0;
}

int main(int argc, char** argv) { return hostMain(argc, argv, "host_damage_strip", {{"output", "host_damage_strip"}}, run); }
