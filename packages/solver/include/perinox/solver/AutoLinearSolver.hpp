#pragma once
// The linear solver a problem gets when its scene (or host program) leaves the choice to perinox:
// Solver/Linear Solver Preset = auto, the default. A rule on what the problem is (dimension,
// unknowns, ranks, effects, continuation), from the measurements in docs/performance.md ("Which
// linear solver when") and docs/choosing-a-solver.md (the table of every preset on every scene).
// Free of Trilinos types: a host program can ask for the choice without building anything.

#include <string>

namespace Teuchos {
template <class O> class Comm;
}  // namespace Teuchos

namespace perinox {

struct ProblemSpec;

/// What the rule looks at.
struct SolverFeatures {
  int dim = 2;
  long long particles = 0;       // the whole body's, fictitious ones included
  long long freeDofs = 0;        // unknowns after the prescribed components, whole body
  int ranks = 1;
  bool lattice = true;           // particles on a regular lattice (else a mesh or a particle file)
  double horizonFactor = 3.0;    // horizon / spacing
  bool stressPoints = false;
  bool damage = false;
  bool plastic = false;
  bool correspondence = true;
  double weakestG = 0.0;         // Silling's G of the least stabilised material in force (0: none)
  bool mustAssemble = false;     // arc length or a trust region: the assembled tangent is needed
  std::string jacobianGiven;     // the Jacobian the scene or host fixed (Assembled, Matrix-Free,
                                 // Jacobian-Free), a condition of the choice; empty: free
  bool explicitSolver = false;   // ADR: no linear system is solved
};

/// The choice: a preset of xml/solvers with its Jacobian and forcing term, and why, in a sentence.
struct LinearSolverChoice {
  std::string preset;            // a file name of xml/solvers without .xml
  std::string jacobian;          // Assembled or Matrix-Free
  std::string forcingTerm;       // Constant or Eisenstat-Walker
  std::string reason;
};

/// The rule (deterministic; the same on every rank given the same features).
LinearSolverChoice chooseLinearSolver(const SolverFeatures& f);

/// What a run with a choice costs, roughly: the peak resident memory of one rank's process (on
/// one rank) and the wall time of one Newton iteration on one core, from power laws in the
/// particles times their family size fitted to the measurements of docs/choosing-a-solver.md
/// ("Estimates"), which gives their spread against the measured runs.
struct RunEstimate {
  double peakMiB = 0;
  double secondsPerNewton = 0;
};
RunEstimate estimateRun(const SolverFeatures& f, const LinearSolverChoice& c);

/// A problem's features (collective over comm: the prescribed components are counted over the
/// ranks). lattice, mustAssemble and explicitSolver come from the caller: the problem does not know
/// where its particles came from or how it will be continued.
SolverFeatures solverFeatures(const Teuchos::Comm<int>& comm, const ProblemSpec& problem, bool lattice, bool mustAssemble,
                              bool explicitSolver);

}  // namespace perinox
