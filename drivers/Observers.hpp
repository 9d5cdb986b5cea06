#pragma once
// The driver's step observers (perinox_app): the scene's probes, the console lines of load
// stepping and of arc-length continuation, and the stability check; the probe values and the
// error against a scene's reference they and the summary use.
#include <Thyra_VectorBase.hpp>
#include <iomanip>
#include <ios>
#include <iostream>
#include <sstream>
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

/// Mean displacement of a probe's particles, or the summed reaction, at state x (collective).
std::vector<double> probeValue(const PeridynamicEvaluator& ev, const ProbeDef& probe,
                               const Thyra::VectorBase<double>& x, const std::vector<double>& uOwned);

/// e_u = sum_i |u_i - u_ref,i| / |u_ref,i| V_i / sum_i V_i over real particles with u_ref != 0 (collective).
double displacementError(const PeridynamicEvaluator& ev, const ReferenceDef& ref, const std::vector<double>& uOwned);

/// The scene's probes, recorded at every accepted step (collective: every rank).
class ProbeRecorder final : public StepObserver {
 public:
  ProbeRecorder(const PeridynamicEvaluator& ev, const Scene& scene, RunResult& res) : ev_(ev), scene_(scene), res_(res) {}
  void accepted(const StepInfo& s) override {
    const auto u = ev_.ownedDisplacements(s.x);
    for (std::size_t k = 0; k < scene_.probes.size(); ++k)
      if (scene_.probes[k].quantity != "Profile")
        res_.probes[k].second.push_back({s.loadFactor, probeValue(ev_, scene_.probes[k], s.x, u)});
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
  void accepted(const StepInfo& s) override {
    if (!speak_) return;
    CoutFormat keep;
    const auto& nr = s.result;
    const auto& rec = s.record;
    std::cout << "step " << std::setw(3) << rec.step << "  load " << std::fixed << std::setprecision(4) << s.loadFactor
              << (adr_ ? "  adr " : "  newton ") << std::setw(2) << nr.iterations
              << (adr_ ? "  e1, e2 " : (nr.reactionNormalised ? "  |R|/|reaction| " : "  |R|/|f_ext| "))
              << std::scientific << std::setprecision(3)
              << (nr.residuals.empty() ? 0.0 : (adr_ ? nr.residuals.front() : nr.residuals.back())) << (adr_ ? ", " : "")
              << (adr_ ? std::to_string(nr.residuals.back()) : std::string())
              << (rec.krylovIterations > 0 ? "  krylov " + std::to_string(rec.krylovIterations) : std::string())
              << (rec.linearFailures > 0 ? "  unconverged linear solves " + std::to_string(rec.linearFailures) : std::string())
              << "  " << std::fixed << std::setprecision(2) << rec.elapsed << " s"
              << (nr.atRoundoffFloor ? "  (at the round-off floor)" : "") << std::endl;  // flushed: a log can be followed
  }

 private:
  bool adr_, speak_;
};

/// 'Solver/Stability Check': the tangent's negative pivots at each converged step; an unstable
/// equilibrium stops the run, the last stable state kept.
class StabilityCheck final : public StepObserver {
 public:
  explicit StabilityCheck(PeridynamicEvaluator& ev) : ev_(ev) {}
  std::string vet(const StepInfo& s, double previous) override {
    const int neg = ev_.negativePivots(s.x);
    if (neg == 0) return "";
    std::ostringstream m;
    if (neg > 0)
      m << "loss of stability: the equilibrium found at load factor " << s.loadFactor << " is unstable (the tangent has "
        << neg << " negative pivot(s)): the path passed a bifurcation or limit point between load factors " << previous
        << " and " << s.loadFactor << "; the last stable state is written";
    else
      m << "stability check impossible at load factor " << s.loadFactor << ": the tangent is not symmetric or its LDL^T failed";
    return m.str();
  }

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
  void accepted(const StepInfo& s) override {
    if (!speak_) return;
    CoutFormat keep;
    const auto& rec = s.record;
    std::cout << "step " << std::setw(3) << rec.step << "  load " << std::fixed << std::setprecision(6) << s.loadFactor
              << "  arc " << std::scientific << std::setprecision(3) << rec.arcLength << "  corrector " << std::setw(2)
              << s.result.iterations << "  residual " << s.result.residuals.back()
              << (deflection_ ? "  deflection " + std::to_string(arc_.monitorHistory().back()) : std::string())
              << (rec.negativePivots >= 0 ? "  negative pivots " + std::to_string(rec.negativePivots) : "") << "  "
              << std::fixed << std::setprecision(2) << rec.elapsed << " s" << std::endl;
  }

 private:
  const ArcLengthStepper& arc_;
  bool deflection_, speak_;
};

}  // namespace perinox
