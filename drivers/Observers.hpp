#pragma once
// The driver's step observers (perinox_app): the scene's probes, the console lines of load
// stepping and of arc-length continuation, and the stability check; the probe values and the
// error against a scene's reference they and the summary use.
#include <Thyra_VectorBase.hpp>
#include <algorithm>
#include <ios>
#include <iostream>
#include <string>
#include <vector>

#include "Simulation.hpp"
#include "perinox/evaluator/PeridynamicEvaluator.hpp"
#include "perinox/stepping/ArcLengthStepper.hpp"
#include "perinox/stepping/LoadStepper.hpp"

namespace perinox {

/// Seconds of a steady clock (differences are wall times).
double wallSeconds();

/// Progress lines set fixed or scientific formats and precisions on std::cout; this restores the
/// stream's format when the line's scope ends, so no line inherits another's (a load factor
/// printed after the "2 decimals" of an elapsed time read 0.24 for 0.2442).
class CoutFormat {
 public:
  CoutFormat() : flags_(std::cout.flags()), precision_(std::cout.precision()) {}
  ~CoutFormat() {
    std::cout.flags(flags_);
    std::cout.precision(precision_);
  }
  CoutFormat(const CoutFormat&) = delete;
  CoutFormat& operator=(const CoutFormat&) = delete;

 private:
  std::ios_base::fmtflags flags_;
  std::streamsize precision_;
};

/// Mean displacement of a probe's particles, the summed reaction, or the largest and the mean
/// plastic strain, at state x (collective). outs: the owned outputs at x, if already computed.
std::vector<double> probeValue(const PeridynamicEvaluator& ev, const ProbeDef& probe,
                               const Thyra::VectorBase<double>& x, const std::vector<double>& uOwned,
                               const std::vector<ParticleOutput>* outs = nullptr);

/// The scene's analytic reference (at load factor 1) as a Displacement probe reads it: the mean of
/// u_ref over the probe's particles (collective).
std::vector<double> referenceProbeValue(const PeridynamicEvaluator& ev, const ProbeDef& probe, const ReferenceDef& ref);

/// e_u = sum_i |u_i - u_ref,i| / |u_ref,i| V_i / sum_i V_i over real particles with u_ref != 0 (collective).
double displacementError(const PeridynamicEvaluator& ev, const ReferenceDef& ref, const std::vector<double>& uOwned);

/// A probe's value's key in summary.json ("displacement", "reaction", "plastic_strain") and the
/// names of its components (x, y, z; max, mean for the plastic strain).
std::string probeKey(const ProbeDef& probe);
std::vector<std::string> probeComponents(const ProbeDef& probe, int dim);

/// The scene's probes, recorded at every accepted step (collective: every rank).
class ProbeRecorder final : public StepObserver {
 public:
  ProbeRecorder(const PeridynamicEvaluator& ev, const Scene& scene, RunResult& res) : ev_(ev), scene_(scene), res_(res) {}
  void accepted(const StepInfo& s) override {
    const auto u = ev_.ownedDisplacements(s.x);
    // The outputs once a step, for all the plastic-strain probes (every rank takes the same branch).
    std::vector<ParticleOutput> outs;
    if (std::any_of(scene_.probes.begin(), scene_.probes.end(), [](const ProbeDef& p) { return p.quantity == "Plastic Strain"; }))
      outs = ev_.ownedOutputs(s.x);
    for (std::size_t k = 0; k < scene_.probes.size(); ++k)
      if (scene_.probes[k].quantity != "Profile")
        res_.probes[k].second.push_back({s.loadFactor, probeValue(ev_, scene_.probes[k], s.x, u, &outs)});
  }

 private:
  const PeridynamicEvaluator& ev_;
  const Scene& scene_;
  RunResult& res_;
};

/// The console: one line per accepted step (load factor, iterations, residual, time) and the
/// stepper's notes (cut-backs, stalls, damage), on rank 0 unless quiet.
class ConsoleLines final : public StepObserver {
 public:
  ConsoleLines(const Scene& scene, bool speak) : adr_(scene.solver.method == "ADR"), speak_(speak) {}
  void note(const std::string& line) override {
    if (speak_) std::cout << line << "\n";
  }
  void accepted(const StepInfo& s) override;

 private:
  bool adr_, speak_;
};

/// 'Solver/Stability Check': the tangent's negative pivots at each converged step; an unstable
/// equilibrium stops the run, the last stable state kept.
class StabilityCheck final : public StepObserver {
 public:
  explicit StabilityCheck(PeridynamicEvaluator& ev) : ev_(ev) {}
  std::string vet(const StepInfo& s, double previous) override;

 private:
  PeridynamicEvaluator& ev_;
};
/// The solve's outcome: the last converged state and its load factor.
/// The arc-length console: one line per converged point (load factor, arc, corrector iterations,
/// residual, deflection, negative pivots, time) and the stepper's notes, on rank 0 unless quiet.
class ArcConsole final : public StepObserver {
 public:
  ArcConsole(const ArcLengthStepper& arc, bool deflection, bool speak) : arc_(arc), deflection_(deflection), speak_(speak) {}
  void note(const std::string& line) override {
    if (speak_) std::cout << line << "\n";
  }
  void accepted(const StepInfo& s) override;

 private:
  const ArcLengthStepper& arc_;
  bool deflection_, speak_;
};

}  // namespace perinox
