// host_plastic_block: a host application driving an elastic-plastic perinox model along a load
// path with perinox's load stepper, committing the material history itself. No scene file.
//
// Sample run:  mpiexec -np 2 host_plastic_block --output DIR   (DIR/summary.json: the reaction per
//              step; DIR/fields.pvtu: displacement, stress, equivalent plastic strain, yield flag)
//
// Description: xml/plastic_uniaxial_strain.xml with Solver/Load Path = {1, 0, 1.5} built in C++: a
// 1 x 0.5 block (40 x 20 particles, delta = 1.015 dx, G = 0.05) in plane strain, J2 plasticity
// at finite strain (E = 200 GPa, nu = 0.3, sigma_y0 = 250 MPa, H = 2 GPa), fictitious layers on
// all sides: u_x = 0 left, u_x = 0.01 X right at load factor 1, u_y = 0 top and bottom. The load
// goes 0 -> 1 -> 0 -> 1.5 in four steps a segment. The answer equals the driver's run of the scene.
#include <iostream>

#include <perinox/io/HostOutput.hpp>
#include <perinox/solver/EvaluatorSetup.hpp>
#include <perinox/solver/NewtonSolver.hpp>
#include <perinox/stepping/LoadStepper.hpp>

using namespace perinox;

/// 1. The problem: a plastic material is an elastic one with MaterialSpec::plastic filled.
std::shared_ptr<ProblemSpec> block() {
  LatticeSpec lattice;
  lattice.upper = Vec3(1.0, 0.5, 0.0);
  lattice.counts = {40, 20, 1};
  lattice.horizonFactor = 1.015;
  lattice.fictitiousSides = {Side::XMin, Side::XMax, Side::YMin, Side::YMax};
  MaterialSpec steel{MaterialKind::Hencky, 2, PlanarMode::PlaneStrain, 200.0e9, 0.3};
  steel.plastic.enabled = true;
  steel.plastic.yieldStress = 250.0e6;
  steel.plastic.hardeningModulus = 2.0e9;
  auto P = problemOnLattice(lattice, steel);
  P->stabilization = true;
  P->stab.G = 0.05;
  prescribe(*P, selectFictitiousSide(P->disc, Side::XMin), 0);
  prescribe(*P, selectFictitiousSide(P->disc, Side::XMax), 0, [](const Vec3& X) { return 0.01 * X[0]; });
  for (Side s : {Side::YMin, Side::YMax}) prescribe(*P, selectFictitiousSide(P->disc, s), 1);
  return P;
}

int run(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const HostOptions& options) {
  auto evaluator = evaluatorWithSolver(comm, block(), PERINOX_PRESETS "/mumps.xml");

  // 2. The load path: the stepper's load factor becomes a pseudo-time in [0, 1]; steps land on
  // the path's corners (stops) and do not extrapolate across them.
  const std::vector<double> path{1.0, 0.0, 1.5};
  auto model = Teuchos::rcp(new LoadFactorModel(evaluator));
  model->setLoadPath(path);
  model->onLoadFactor([ev = evaluator.get()](double lambda) { ev->setLoadFactor(lambda); });
  NewtonOptions newton;
  newton.lineSearch = "Backtrack";  // points switch between elastic and plastic where the load reverses
  auto solver = Teuchos::rcp(new NewtonSolver(model, Teuchos::rcp(new EvaluatorResidualScale(evaluator)), newton));
  LoadStepperOptions stepping;
  stepping.loadSteps = 4 * static_cast<int>(path.size());
  stepping.stops = LoadFactorModel::pathStops(static_cast<int>(path.size()));
  LoadStepper stepper(model, [&](Thyra::VectorBase<double>& x) { return solver->solve(x); }, stepping);

  // 3. The history: every evaluation is a pure function of (x, committed state); the stepper calls
  // this once per accepted step, before its observers. A host stepping by itself calls
  // evaluator->commitHistory(x) after each step it accepts, and never after a failed one.
  stepper.setHistoryCommit([&](const Thyra::VectorBase<double>& x) { evaluator->commitHistory(x); });
  const auto grip = selectFictitiousSide(evaluator->problem().disc, Side::XMax);
  ValueRecorder reaction([&](const Thyra::VectorBase<double>& x) { return evaluator->reactionOn(x, grip); });
  stepper.addObserver(&reaction);
  if (!stepper.run()) throw std::runtime_error(stepper.failure());

  // 4. Output: the fields (with the plastic strain) and the reaction against the load factor.
  const std::string& dir = options.at("output");
  writeParticleFields(dir, *evaluator, stepper.converged());
  // Observers see the model's load factor (the path's), the step records the pseudo-time.
  writeProbeSummary(dir + "/summary.json", *comm, {{"reaction", "reaction", reaction.values()}}, "\"steps\": " +
                    std::to_string(stepper.records().size()));
  if (comm->getRank() == 0)
    std::cout << "converged in " << stepper.records().size() << " steps along the load path; results in " << dir << "\n";
  return 0;
}

int main(int argc, char** argv) { return hostMain(argc, argv, "host_plastic_block", {{"output", "host_plastic_block"}}, run); }
