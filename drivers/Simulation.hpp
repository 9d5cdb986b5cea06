#pragma once
// One run of a scene: load stepping around Newton, probes, errors against a reference, and
// the output folder (summary.json, newton.csv, VTK, plots). The folder is staged and renamed
// into place at the end, so a run never leaves a half-written result.
#include <Teuchos_Comm.hpp>
#include <Teuchos_RCP.hpp>
#include <limits>
#include <string>
#include <vector>

#include "perinox/io/Scene.hpp"
#include "perinox/stepping/LoadStepper.hpp"  // StepRecord

namespace perinox {

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
  // Load stepping stopped at a limit load (LoadStepper::limitLoad): its load factor; NaN otherwise.
  double limitLoad = std::numeric_limits<double>::quiet_NaN();
  bool hasError = false;
  double errorU = 0;   // e_u of seed 000 eq. 56 at the final state
  // Displacement probe name -> the scene's reference read as that probe (load factor 1).
  std::vector<std::pair<std::string, std::vector<double>>> probeReferences;
  double wallTime = 0;
  long long particles = 0, dofs = 0;
  std::string outputDir;
};

struct RunOptions {
  std::string outputDir = "out";
  bool quiet = false;       // no progress lines
  std::string plotScript;   // python script that draws PNGs from the output folder ("" = none)
  // Checkpoints of load stepping (for runs longer than a batch job may last): after a converged
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
