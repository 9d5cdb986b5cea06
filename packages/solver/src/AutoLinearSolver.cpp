// The automatic linear-solver choice (AutoLinearSolver.hpp).
#include "perinox/solver/AutoLinearSolver.hpp"

#include <Teuchos_Comm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "perinox/evaluator/Problem.hpp"

namespace perinox {

namespace {

/// peak = 75 MiB + a w^b MiB and one Newton iteration = c w^d s, with w = particles x (bonds + 1):
/// per kind of choice and dimension, fitted to the runs of docs/choosing-a-solver.md's table ("Estimates").
struct Fit {
  double a, b, c, d;
};
enum Kind { kDirect, kKept, kFree, kAssembled };
constexpr Fit kFits[2][4] = {
    // tools/fit_estimates.py over tools/bench_auto.py's runs (docs/choosing-a-solver.md, "Estimates")
    // 2D (and 1D): direct, kept factorisation, matrix-free, assembled
    {{5.42e-05, 1.26, 7.49e-09, 1.57}, {0.000203, 1.13, 7.86e-09, 1.42}, {0.000507, 0.898, 7.19e-05, 0.699}, {0.00153, 0.873, 3.77e-05, 0.785}},
    // 3D (2D's exponents; coefficients through the 3D runs)
    {{0.000716, 1.26, 2.64e-07, 1.57}, {0.000572, 1.13, 4.42e-08, 1.42}, {0.00176, 0.898, 0.000236, 0.699}, {0.0047, 0.873, 0.000259, 0.785}},
};

std::string count(long long n) {
  char b[32];
  std::snprintf(b, sizeof b, "%lld", n);
  return b;
}

std::string decimal(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

}  // namespace

LinearSolverChoice chooseLinearSolver(const SolverFeatures& f) {
  const long long n = f.freeDofs / std::max(1, f.dim);  // free particles, roughly
  const std::string size = count(f.freeDofs) + " free unknowns in " + count(f.dim) + "D";
  if (f.explicitSolver) return {"direct", "Assembled", "Constant", "ADR is explicit: no linear system is solved"};
  if (f.jacobianGiven == "Jacobian-Free")
    return {"jfnk-ilu", "Jacobian-Free", "Constant", "the Jacobian-free product asked for: GMRES with ILU on the neighbour matrix"};
  // The stress points' product is not affine: their assembled tangent is cheaper than J v.
  const bool assembled = f.mustAssemble || f.jacobianGiven == "Assembled" || (f.stressPoints && f.jacobianGiven.empty());
  const bool matrixFree = f.jacobianGiven == "Matrix-Free";
  const std::string because = f.mustAssemble                    ? " (assembled: arc length and trust regions need the tangent)"
                              : f.jacobianGiven == "Assembled"  ? " (the assembled Jacobian asked for)"
                              : matrixFree                      ? " (the matrix-free Jacobian asked for)"
                              : f.stressPoints                  ? " (assembled: the stress points' product is not affine)"
                                                                : "";
  // Small problems: a factorisation costs less than any preconditioner's set-up. The direct preset
  // (KLU2 on one rank, MUMPS on more) is fastest on a short-horizon lattice; KLU2 fills in fast
  // with irregular particles and long horizons.
  const long long smallLimit = f.dim == 1 ? (1LL << 62) : f.dim == 2 ? 2500 : 1000;
  // Not with plasticity or damage in 2D and 3D: their tangents change every iteration, and the
  // kept factorisation below is faster (xml/plastic_uniaxial_strain.xml: 0.30 s against 0.15 s).
  const bool changing = f.plastic || f.damage;
  if (!matrixFree && (f.dim == 1 || (n <= smallLimit && f.lattice && f.horizonFactor <= 2.0 && !changing)))
    return {"direct", "Assembled", "Constant",
            size + (f.dim == 1 ? ": a banded matrix" : " on a lattice with a short horizon") + ": a sparse direct solve (" +
                (f.ranks == 1 ? "KLU2" : "MUMPS on more than one rank") + ")" + because};
  // Where a direct solve beats the multigrid preconditioner, GMRES preconditioned by a kept MUMPS
  // factorisation (renewed once its extra iterations cost a factorisation) beats it again: it
  // factorises a few times a run instead of every Newton iteration. That is: small problems; in 2D
  // weak stabilisation (G < 0.1: the multigrid needs 3-6x its iterations, MUMPS stays faster to
  // some 50 000 particles), plasticity (tangents soften toward a limit load), particles off a
  // lattice (a weaker multigrid auxiliary), and damage to 30 000 particles.
  const bool weak = f.correspondence && !f.stressPoints && f.weakestG < 0.1;
  std::string what;
  if (weak) what += ", stabilisation G = " + decimal(f.weakestG) + " < 0.1";
  if (f.plastic) what += ", plastic";
  if (f.damage) what += ", damage";
  if (!f.lattice) what += ", particles off a lattice";
  const bool kept = n <= smallLimit || (f.dim == 2 && (weak || f.plastic || !f.lattice) && n <= 60000) ||
                    (f.dim == 2 && f.damage && n <= 30000);
  if (kept)
    return {"gmres-mumps", assembled ? "Assembled" : "Matrix-Free", "Eisenstat-Walker",
            size + what + ": GMRES preconditioned by a kept MUMPS factorisation, Eisenstat-Walker forcing" + because};
  // Weak stabilisation: scalable with a wider smoother on J (scalable-weak), which takes the
  // near-zero-energy modes the auxiliary operator lacks (G = 0.01, 3 200 particles: 208 Krylov
  // iterations against 341).
  const std::string scalable = weak ? "scalable-weak" : "scalable";
  const std::string smoother = weak ? " (a wider smoother for the weak stabilisation)" : "";
  if (assembled)
    return {scalable, "Assembled", "Constant", size + what + ": GMRES with the two-stage multigrid preconditioner" + smoother + because};
  return {scalable, "Matrix-Free", "Eisenstat-Walker",
          size + what + ": matrix-free GMRES with the two-stage multigrid preconditioner" + smoother + ", Eisenstat-Walker forcing"};
}

RunEstimate estimateRun(const SolverFeatures& f, const LinearSolverChoice& c) {
  // Bonds per particle on a lattice with this horizon factor (the ball's lattice sites), and the
  // work measure w = particles x (bonds + 1) the fits below use.
  const double h = f.horizonFactor, pi = 3.141592653589793;
  const double bonds = f.dim == 1 ? 2 * h : f.dim == 2 ? pi * h * h : 4.0 / 3.0 * pi * h * h * h;
  const double w = static_cast<double>(std::max<long long>(f.particles, 1)) * (bonds + 1.0);
  const Kind kind = c.preset == "direct" || c.preset == "mumps" ? kDirect
                    : c.preset == "gmres-mumps"                     ? kKept
                    : c.jacobian != "Assembled"                     ? kFree
                                                                    : kAssembled;
  const Fit& fit = kFits[f.dim == 3 ? 1 : 0][kind];
  return {75.0 + fit.a * std::pow(w, fit.b), fit.c * std::pow(w, fit.d)};
}

SolverFeatures solverFeatures(const Teuchos::Comm<int>& comm, const ProblemSpec& problem, bool lattice, bool mustAssemble,
                              bool explicitSolver) {
  SolverFeatures f;
  f.dim = problem.dim();
  f.particles = problem.particleCount();
  f.freeDofs = problem.particleCount() * f.dim - prescribedDofCount(comm, problem);
  f.ranks = comm.getSize();
  f.lattice = lattice;
  f.horizonFactor = problem.disc.dx > 0 ? problem.disc.horizon / problem.disc.dx : 3.0;
  f.stressPoints = problem.stressPoints;
  f.damage = problem.damage;
  f.plastic = problem.plastic();
  f.correspondence = problem.correspondence;
  // Silling's G in force: a Peridigm hourglass coefficient c acts as about 40 c (docs/peridigm.md:
  // 14-65 c on the families measured there).
  const auto silling = [&](const StabilizationSpec& s) {
    return s.form == StabilizationSpec::Form::PeridigmHourglass ? 40.0 * s.G : s.G;
  };
  f.weakestG = problem.stabilization ? silling(problem.stabilizationSpec()) : 0.0;
  if (problem.stabilization)
    for (const BlockSpec& b : problem.blocks) f.weakestG = std::min(f.weakestG, silling(problem.stabilizationSpec(b)));
  f.mustAssemble = mustAssemble;
  f.explicitSolver = explicitSolver;
  return f;
}

}  // namespace perinox
