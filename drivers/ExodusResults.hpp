#pragma once
// Output/Format = Exodus or Both (docs/exodus.md): fields.e in the staging folder, one time step
// per converged load step (time = load factor). A StepObserver: every rank gathers its owned
// particles' fields to rank 0, which writes them (packages/io's ExodusWriter); or, when the
// problem is distributed over more than one rank, each rank writes its own particles to its own
// file, fields.e.<p>.<r> (SEACAS's spread-file names, which ParaView opens as one data set).
#include <Teuchos_Comm.hpp>
#include <Thyra_VectorBase.hpp>
#include <memory>
#include <string>

#include "Simulation.hpp"
#include "perinox/stepping/LoadStepper.hpp"

namespace perinox {

class PeridynamicEvaluator;
class ExodusWriter;

class ExodusRecorder final : public StepObserver {
 public:
  /// Collective. Rank 0 creates dir/fields.e (distributed: every rank its exodusPieceName) with the particles, their blocks and the scene's
  /// regions as node sets. res supplies the probes' values (recorded by the probe observer
  /// before this one).
  ExodusRecorder(const PeridynamicEvaluator& ev, const Scene& scene, const RunResult& res, const std::string& dir);
  ~ExodusRecorder() override;
  void accepted(const StepInfo& s) override { record(s.x, s.loadFactor); }
  /// Collective: appends the state x at load factor lambda as a time step.
  void record(const Thyra::VectorBase<double>& x, double lambda);
  int steps() const { return steps_; }
  /// Collective: closes the file (before the folder is committed).
  void close();

 private:
  const PeridynamicEvaluator& ev_;
  const Scene& scene_;
  const RunResult& res_;
  std::unique_ptr<ExodusWriter> writer_;  // rank 0, or every rank when perRank_
  bool perRank_ = false;
  int steps_ = 0;
};

/// The file of rank r of a run written one Exodus file per rank on p ranks: fields.e.p.r with r
/// zero-padded to p's digits (fields.e.4.0, fields.e.16.03).
std::string exodusPieceName(int ranks, int rank);

}  // namespace perinox
