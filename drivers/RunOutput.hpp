#pragma once
// The output folder's contents (perinox_app): the particle fields of every rank, summary.json,
// path.csv, newton.csv, fields.csv, the profiles and the plots, and the console's residual table.
#include <Thyra_VectorBase.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "Simulation.hpp"
#include "perinox/evaluator/PeridynamicEvaluator.hpp"
#include "perinox/solver/MumpsSolver.hpp"
#include "perinox/solver/TwoStagePreconditioner.hpp"

namespace perinox {

/// What summary.json reports beyond the run's result: where it ran and what it held.
struct RunFacts {
  int ranks = 1;
  int segment = 1;                 // 1, or the runs a checkpointed run was split into
  nlohmann::json resumedFrom;      // null unless resumed
  std::vector<std::string> effects;
  long long matrixBytes = 0;       // sparse matrices held, all ranks
  double rssMax = 0, rssSum = 0;   // peak resident memory, MiB: the largest rank's and the sum
  std::vector<long long> detached;
  // Wall times (rank 0's clock after barriers): the set-up (evaluator, maps, before the first
  // solve), the solve (every load step), and one residual evaluation at the final state (median
  // of three), the unit of the machine-independent cost ratios in docs/performance.md.
  double setupSeconds = 0, solveSeconds = 0, residualSeconds = 0;
  double newtonSeconds = 0;        // the part of the solve inside Newton's solves (load stepping)
  MumpsPreconditionerStatistics mumps;  // the MUMPS preconditioner's set-ups (zeros for others)
  TwoStageStatistics twoStage;     // the Two-Stage preconditioner's set-ups (zeros for others)
  nlohmann::json partition;        // the partition: method, owned and ghost particles per rank
};

/// This rank's particles (fields_<rank>.vtu when vtk, rank 0 the PVTU index; fields_<rank>.csv.part
/// and, for each Profile probe, profile_<name>_<rank>.csv.part, in id order) into dir; rank 0
/// merges the parts (writeResults) without holding the whole body.
void writeFields(const PeridynamicEvaluator& ev, const Thyra::VectorBase<double>& x, const std::string& dir,
                 bool vtk, int rank, int nranks, const std::vector<ProbeDef>& probes);

/// One step's record as summary.json writes it (and a checkpoint keeps it), and back.
nlohmann::json stepJson(const StepRecord& s, bool damage, bool arcLength);
StepRecord stepFromJson(const nlohmann::json& j);

/// The sentence a run that converged with unconverged linear solves ends with ("" when none did).
std::string inexactSolvesWarning(const std::vector<StepRecord>& steps);

/// summary.json: the run, its steps and totals, the probes, the errors against the reference.
nlohmann::json summaryJson(const Scene& scene, const RunResult& res, const RunFacts& facts);

/// Rank 0: everything the output folder holds besides the per-rank fields, into the staging folder.
void writeResults(const Scene& scene, const RunResult& res, const RunFacts& facts, const RunOptions& options,
                  const std::string& staging, int nranks);

}  // namespace perinox
