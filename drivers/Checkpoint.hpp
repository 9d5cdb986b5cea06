#pragma once
// Checkpoints of load stepping (perinox_app; README, "Checkpoints"): a folder written after a
// converged step, read back (and checked against the scene) to resume a run on any number of ranks.
#include <Teuchos_Comm.hpp>
#include <Thyra_VectorBase.hpp>
#include <nlohmann/json.hpp>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "Simulation.hpp"
#include "perinox/evaluator/PeridynamicEvaluator.hpp"
#include "perinox/io/OutputFolder.hpp"
#include "Observers.hpp"  // wallSeconds
#include "perinox/stepping/LoadStepper.hpp"

namespace perinox {

/// Everything a load-stepping run needs to go on from a converged step. Vectors and frozen DOFs
/// are by DOF name (particle id * dim + component), bonds by particle ids, so a checkpoint can be
/// resumed on any number of ranks and any partition (the solution map's free-DOF numbers follow
/// the ranks and are not kept). Files: state.json (rank 0: format 2, counters, step records,
/// probes) and rank_R.txt per writing rank (lines "x DOF X XPREV", "bond GID_I GID_J", "frozen
/// DOF VALUE", and with a material with history "state GID V1 ... VN", the committed state of a
/// particle; doubles in hexadecimal, so a resumed run starts from bit-identical numbers).
struct Checkpoint {
  nlohmann::json state;
  std::vector<std::pair<long long, double>> x, xPrevious, frozen;
  std::vector<std::pair<long long, long long>> broken;
  std::vector<std::pair<long long, std::vector<double>>> history;  // per owned particle (after reading)
};

/// A hash (FNV-1a, 16 hex digits) of the scene's particle file or mesh, "" for a lattice: a
/// checkpoint is tied to the body it was written for by content, not only by its counts.
std::string inputFileHash(const Scene& scene);
/// The resolved scene as XML text (a checkpoint keeps it; a resumed run must match it).
std::string resolvedSceneText(const Scene& scene);

/// Writes a checkpoint (state on rank 0, the rank files on every rank) into plan's staging folder
/// and moves it into place. Collective.
void writeCheckpoint(const FolderPlan& plan, const nlohmann::json& state, const PeridynamicEvaluator& ev,
                     const Thyra::VectorBase<double>& x, const Thyra::VectorBase<double>& xPrevious,
                     const Teuchos::Comm<int>& comm);

/// Reads a checkpoint written for this scene (freeDofs unknowns); throws std::invalid_argument
/// naming the problem, on every rank. Collective. A replicated scene reads every rank file on
/// every rank; a distributed one (Construction = Distributed) reads rank file f on rank f mod q
/// only and sends each value and broken bond to the owners of its particles through the id-slab
/// rendezvous, so each rank receives its share alone (owned DOFs' values, frozen DOFs, and the
/// broken bonds with an owned end).
/// stateDoubles: the doubles of committed state per particle of this scene's model (0: none);
/// every particle this rank owns (owned, sorted global ids) must then receive its state.
Checkpoint readCheckpoint(const std::string& dir, const Scene& scene, long long freeDofs, long long particles,
                          int stateDoubles, const std::vector<long long>& owned, const Teuchos::Comm<int>& comm);

/// Calls f with each preconditioner factory of the evaluator's linear solver: the W factory's
/// (assembled Jacobian) and the evaluator's own (matrix-free and Jacobian-free runs).
void forPreconditionerFactories(const PeridynamicEvaluator& ev,
                                const std::function<void(const Thyra::PreconditionerFactoryBase<double>&)>& f);

/// Checkpoints after accepted steps, every --checkpoint-steps steps and/or --checkpoint-seconds.
class CheckpointWriter final : public StepObserver {
 public:
  CheckpointWriter(const RunOptions& options, const FolderPlan& folder, const Scene& scene, const PeridynamicEvaluator& ev,
                   const Teuchos::Comm<int>& comm, const LoadStepper& stepper, const RunResult& res, double t0,
                   double elapsedBefore, int segment)
      : options_(options), folder_(folder), scene_(scene), ev_(ev), comm_(comm), stepper_(stepper), res_(res), t0_(t0),
        elapsedBefore_(elapsedBefore), segment_(segment), last_(wallSeconds()) {}
  void accepted(const StepInfo& s) override;

 private:
  const RunOptions& options_;
  const FolderPlan& folder_;
  const Scene& scene_;
  const PeridynamicEvaluator& ev_;
  const Teuchos::Comm<int>& comm_;
  const LoadStepper& stepper_;
  const RunResult& res_;
  double t0_, elapsedBefore_;
  int segment_;
  double last_;
  std::optional<std::string> inputHash_;  // of the particle file or mesh, at the first checkpoint (rank 0)
};

}  // namespace perinox
