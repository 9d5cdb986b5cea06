// The automatic linear-solver choice (AutoLinearSolver.hpp): each case is a problem measured in
// docs/performance.md or docs/choosing-a-solver.md, with the choice those measurements call for.
#include <gtest/gtest.h>

#include "perinox/solver/AutoLinearSolver.hpp"

using perinox::chooseLinearSolver;
using perinox::LinearSolverChoice;
using perinox::SolverFeatures;

namespace {

SolverFeatures features(int dim, long long freeParticles, double G = 0.5) {
  SolverFeatures f;
  f.dim = dim;
  f.freeDofs = freeParticles * dim;
  f.weakestG = G;
  f.horizonFactor = 3.015;
  return f;
}

void expectChoice(const LinearSolverChoice& c, const std::string& preset, const std::string& jacobian, const std::string& forcing) {
  EXPECT_EQ(c.preset, preset) << c.reason;
  EXPECT_EQ(c.jacobian, jacobian) << c.reason;
  EXPECT_EQ(c.forcingTerm, forcing) << c.reason;
  EXPECT_FALSE(c.reason.empty());
}

}  // namespace

TEST(AutoChoice, SmallProblemsGetADirectSolve) {
  SolverFeatures bar = features(1, 500, 0.0);
  expectChoice(chooseLinearSolver(bar), "direct", "Assembled", "Constant");  // 1D: a banded matrix
  SolverFeatures beam = features(2, 250, 0.0);
  beam.horizonFactor = 1.015;
  expectChoice(chooseLinearSolver(beam), "direct", "Assembled", "Constant");  // KLU2 on a short-horizon lattice
  beam.plastic = true;  // a tangent that changes every iteration: a kept MUMPS factorisation
  expectChoice(chooseLinearSolver(beam), "gmres-mumps", "Matrix-Free", "Eisenstat-Walker");
  beam.plastic = false;
  beam.ranks = 2;  // direct is MUMPS on more ranks: the same exact solves
  expectChoice(chooseLinearSolver(beam), "direct", "Assembled", "Constant");
  SolverFeatures plate = features(2, 1200);  // a horizon of 3 spacings: KLU2 fills in, MUMPS does not
  expectChoice(chooseLinearSolver(plate), "gmres-mumps", "Matrix-Free", "Eisenstat-Walker");
  plate.horizonFactor = 1.015;
  plate.lattice = false;  // irregular particles fill in too
  expectChoice(chooseLinearSolver(plate), "gmres-mumps", "Matrix-Free", "Eisenstat-Walker");
}

TEST(AutoChoice, LargeStabilisedProblemsGetTheMatrixFreeScalableSolver) {
  // docs/performance.md: the tension block at G = 0.5 from 3 200 particles on, 2D and 3D.
  expectChoice(chooseLinearSolver(features(2, 12800)), "scalable", "Matrix-Free", "Eisenstat-Walker");
  expectChoice(chooseLinearSolver(features(2, 819200)), "scalable", "Matrix-Free", "Eisenstat-Walker");
  expectChoice(chooseLinearSolver(features(3, 8000)), "scalable", "Matrix-Free", "Eisenstat-Walker");
  // Peridigm's tensile test: 12 625 particles in 3D, weakly stabilised (MUMPS fills in badly in
  // 3D): the scalable preconditioner with the wider smoother.
  expectChoice(chooseLinearSolver(features(3, 12625, 0.02)), "scalable-weak", "Matrix-Free", "Eisenstat-Walker");
}

TEST(AutoChoice, WeakStabilisationIn2DKeepsAMumpsFactorisationToFiftyThousandParticles) {
  expectChoice(chooseLinearSolver(features(2, 51200, 0.01)), "gmres-mumps", "Matrix-Free", "Eisenstat-Walker");
  expectChoice(chooseLinearSolver(features(2, 204800, 0.01)), "scalable-weak", "Matrix-Free", "Eisenstat-Walker");
}

TEST(AutoChoice, StressPointsAndArcLengthAssemble) {
  SolverFeatures brick = features(3, 18513, 0.0);  // xml/brick3d.xml
  brick.stressPoints = true;
  expectChoice(chooseLinearSolver(brick), "scalable", "Assembled", "Constant");
  SolverFeatures arc = features(2, 20000);
  arc.mustAssemble = true;
  expectChoice(chooseLinearSolver(arc), "scalable", "Assembled", "Constant");
  arc.freeDofs = 2 * 300;
  expectChoice(chooseLinearSolver(arc), "gmres-mumps", "Assembled", "Eisenstat-Walker");
}

TEST(AutoChoice, DamageIn2DKeepsAMumpsFactorisationUnderGmres) {
  SolverFeatures plate = features(2, 7500);  // the 150 x 50 damaged plate
  plate.damage = true;
  expectChoice(chooseLinearSolver(plate), "gmres-mumps", "Matrix-Free", "Eisenstat-Walker");
  plate.mustAssemble = true;
  expectChoice(chooseLinearSolver(plate), "gmres-mumps", "Assembled", "Eisenstat-Walker");
  SolverFeatures large = features(2, 100000);
  large.damage = true;
  expectChoice(chooseLinearSolver(large), "scalable", "Matrix-Free", "Eisenstat-Walker");
}

TEST(AutoChoice, AGivenJacobianIsACondition) {
  SolverFeatures f = features(2, 12800);
  f.jacobianGiven = "Assembled";
  expectChoice(chooseLinearSolver(f), "scalable", "Assembled", "Constant");
  f.jacobianGiven = "Jacobian-Free";
  expectChoice(chooseLinearSolver(f), "jfnk-ilu", "Jacobian-Free", "Constant");
  SolverFeatures small = features(2, 300);
  small.jacobianGiven = "Matrix-Free";  // no direct solver takes a matrix-free operator
  expectChoice(chooseLinearSolver(small), "gmres-mumps", "Matrix-Free", "Eisenstat-Walker");
}

TEST(AutoChoice, ExplicitRunsSolveNoLinearSystem) {
  SolverFeatures f = features(2, 100000);
  f.explicitSolver = true;
  const LinearSolverChoice c = chooseLinearSolver(f);
  EXPECT_EQ(c.preset, "direct");
  EXPECT_NE(c.reason.find("ADR"), std::string::npos);
}

TEST(AutoChoice, PlasticOrIrregular2DProblemsKeepAMumpsFactorisationToFiftyThousandParticles) {
  SolverFeatures cylinder = features(2, 3764, 2.0);  // xml/plastic_cylinder.xml: polar particles, J2
  cylinder.plastic = true;
  cylinder.lattice = false;
  expectChoice(chooseLinearSolver(cylinder), "gmres-mumps", "Matrix-Free", "Eisenstat-Walker");
  cylinder.lattice = true;
  expectChoice(chooseLinearSolver(cylinder), "gmres-mumps", "Matrix-Free", "Eisenstat-Walker");
  cylinder.plastic = false;
  expectChoice(chooseLinearSolver(cylinder), "scalable", "Matrix-Free", "Eisenstat-Walker");
  cylinder.lattice = false;
  expectChoice(chooseLinearSolver(cylinder), "gmres-mumps", "Matrix-Free", "Eisenstat-Walker");
  cylinder.freeDofs = 2 * 100000;
  expectChoice(chooseLinearSolver(cylinder), "scalable", "Matrix-Free", "Eisenstat-Walker");
}
