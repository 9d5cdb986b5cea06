#pragma once
// One run of a scene: load stepping around Newton, probes, errors against a reference, and
// the output folder (summary.json, newton.csv, VTK, plots). The folder is staged and renamed
// into place at the end, so a run never leaves a half-written result.
#include <Teuchos_Comm.hpp>
#include <Teuchos_RCP.hpp>
#include <string>
#include <vector>

#include "perinox/io/Scene.hpp"

namespace perinox {

struct StepRecord {
  int step = 0;
  double loadFactor = 0;
  int newtonIterations = 0;        // iterations of the solve that converged the step (and its
                                   // re-equilibrations)
  long long newtonIterationsAll = 0;  // every attempt of the step, cut-backs included
  long long linearSolves = 0;      // linear systems solved in the step, all attempts
  long long krylovIterations = 0;  // Krylov iterations spent on them (0 with a direct solver)
  long long linearFailures = 0;    // of those, solves the linear solver reported unconverged
                                   // (Newton went on with the inexact direction)
  std::vector<double> residuals;
  bool reactionNormalised = false;
  bool atRoundoffFloor = false;    // converged on the round-off floor rather than the tolerance
  double floor = 0;                // that floor, normalised
  int cutbacks = 0;
  double elapsed = 0;
  long long brokenBonds = 0;       // damage: bonds broken after this step converged
  int breakRounds = 0;             // damage: re-equilibrations after breaking
  std::vector<long long> detached; // particles detached in this step
  long long fragmentParticles = 0; // of those, particles of free-floating fragments
  long long stallBrokenBonds = 0;  // damage, On Stall = Break Most Stretched: bonds broken because
                                   // the step could not be converged (included in brokenBonds)
  double stallStretch = 0;         // the largest stretch at that break
  int reloadSteps = 0;             // damage: sub-steps of reloading the damaged body when Newton could
                                   // not re-equilibrate directly after a break
  double arcLength = 0;            // arc-length continuation: the arc of this step
  int negativePivots = -2;         // arc-length continuation with Stability Check: the tangent's
                                   // negative pivots at the converged point (-2: not computed)
};

struct LimitPoint {
  int step = 0;                    // the step at which the load factor peaked
  double loadFactor = 0;
  double deflection = 0;
};

struct RunResult {
  bool converged = false;
  std::string failure;
  std::vector<StepRecord> steps;
  // probe name -> per converged step: load factor and values (displacement or reaction)
  std::vector<std::pair<std::string, std::vector<std::pair<double, std::vector<double>>>>> probes;
  std::vector<double> pathLoadFactors;  // load factor of every converged step (path.csv)
  std::vector<LimitPoint> limitPoints;  // arc-length continuation: local maxima of the load factor
  bool hasError = false;
  double errorU = 0;   // e_u of seed 000 eq. 56 at the final state
  double wallTime = 0;
  long long particles = 0, dofs = 0;
  std::string outputDir;
};

struct RunOptions {
  std::string outputDir = "out";
  bool quiet = false;       // no progress lines
  std::string plotScript;   // python script that draws PNGs from the output folder ("" = none)
  // Checkpoints of load stepping (for runs longer than a job or a session): after a converged
  // step, every checkpointSteps steps and/or once checkpointSeconds of wall time have passed
  // since the last one, into checkpointDir (default: the output folder + ".checkpoint"). Each
  // replaces the previous one only when complete.
  int checkpointSteps = 0;
  double checkpointSeconds = 0;
  std::string checkpointDir;
  std::string restartFrom;  // a checkpoint folder to resume from ("" = start at load factor 0)
};

/// Runs the scene on comm. Throws SceneError / std::invalid_argument for set-up problems
/// found before any output is written; solver failures are reported in the result.
RunResult runScene(const Scene& scene, const Teuchos::RCP<const Teuchos::Comm<int>>& comm,
                   const RunOptions& options);

}  // namespace perinox
