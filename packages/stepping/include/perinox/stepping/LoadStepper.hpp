#pragma once
// Load stepping for any Thyra::ModelEvaluator whose parameter p(0) is the load factor lambda:
// lambda goes from 0 (or a resumed state) to 1 in increments, each solved by a step solver
// (Newton), with a predictor, cut-backs, growth after easy steps, an optional damage policy
// (bonds broken after a converged step, a stall break and a reload when a step cannot be
// converged) and step observers (probes, console lines, checkpoints, result writers). Nothing here
// knows peridynamics: perinox's evaluator is one model it drives (drivers/Simulation.cpp), a test
// double is another (packages/stepping/tests).
#include <Teuchos_ParameterList.hpp>
#include <Teuchos_RCP.hpp>
#include <Thyra_ModelEvaluatorDelegatorBase.hpp>
#include <Thyra_VectorBase.hpp>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "perinox/solver/NewtonSolver.hpp"

namespace perinox {

/// One load step as it is reported (summary.json) and checkpointed.
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
  long long stallBrokenBonds = 0;  // damage, stall break: bonds broken because the step could not
                                   // be converged (included in brokenBonds)
  double stallStretch = 0;         // the largest stretch at that break
  bool pastLimit = false;          // the last attempt converged past a limit load (limitLoadRatio): not recorded
  bool stallAtLimit = false;       // that break was made at a snap-back's limit load, without a failed step
  int reloadSteps = 0;             // damage: sub-steps of reloading the damaged body when Newton could
                                   // not re-equilibrate directly after a break
  double arcLength = 0;            // arc-length continuation: the arc of this step
  int negativePivots = -2;         // arc-length continuation with Stability Check: the tangent's
                                   // negative pivots at the converged point (-2: not computed)
};

/// The load factor of a load path (LoadFactorModel::setLoadPath) at pseudo-time s: 0 at s = 0,
/// knots[k] at s = (k + 1) / knots.size(), linear between; s itself when knots is empty.
double loadOnPath(const std::vector<double>& knots, double s);

/// A model whose parameter p(0) is the load factor, evaluated at the load factor set here: every
/// evaluation is given p(0) = lambda unless its caller gave one (NOX's group gives none).
class LoadFactorModel : public Thyra::ModelEvaluatorDelegatorBase<double> {
 public:
  /// Refuses (std::invalid_argument, one sentence) a model without a one-value parameter p(0).
  explicit LoadFactorModel(const Teuchos::RCP<Thyra::ModelEvaluator<double>>& model);
  void setLoadFactor(double lambda);
  double loadFactor() const { return lambda_; }
  /// A load path: the stepper's load factor becomes a pseudo-time s in [0, 1], and the model is
  /// evaluated at the piecewise-linear load factor through 0 = knots... at s = 0 and knots[k] at
  /// s = (k + 1) / knots.size() (e.g. {1, 0, 1.2}: load, unload, reload past the first peak).
  /// Empty: the identity (s is the load factor). Pair it with LoadStepperOptions::stops =
  /// pathStops(knots.size()) so that steps land on the path's corners.
  void setLoadPath(std::vector<double> knots) { path_ = std::move(knots); }
  /// The model's load factor at pseudo-time s, and d(load factor)/ds on the segment that starts at
  /// or contains s.
  double loadAt(double s) const { return loadOnPath(path_, s); }
  double pathSlope(double s) const;
  /// The corners of a path of `segments` segments: k / segments, k = 1 .. segments - 1.
  static std::vector<double> pathStops(int segments);
  /// Called with every new load factor (a model that keeps its own, e.g. for diagnostics).
  void onLoadFactor(std::function<void(double)> listener) { listener_ = std::move(listener); }
  /// df/dlambda at x and the current load factor: the model's DfDp(0) if it supports it by
  /// column, else the central difference (f(lambda + h) - f(lambda - h)) / 2h, h = 1e-6 max(1, |lambda|).
  void loadDerivative(const Thyra::VectorBase<double>& x, Thyra::VectorBase<double>& dfdl) const;

 private:
  void evalModelImpl(const Thyra::ModelEvaluatorBase::InArgs<double>& in,
                     const Thyra::ModelEvaluatorBase::OutArgs<double>& out) const override;
  double lambda_ = 0.0;
  std::function<void(double)> listener_;
  std::vector<double> path_;
};

/// The stepping controls (validated; validParameters() documents them).
struct LoadStepperOptions {
  int loadSteps = 10;             // equal nominal increments 1 / loadSteps
  int maxCutbacks = 4;            // halvings of a failing step before the run stops
  double minIncrement = 1e-6;     // smallest increment, as a fraction of the nominal one
  int maxTotalSteps = 0;          // steps in all (0: 20 x loadSteps)
  bool adaptive = false;          // grow by 1.5 after easy steps up to maxIncrement
  int easyIterations = 4;
  double maxIncrement = 0.25;
  bool predictor = true;          // extrapolate the last increment (and, for the first step with
                                  // prescribed motion, the tangent dx/dlambda: tangentPredictor)
  bool tangentPredictor = false;  // first step: x = x0 + dlambda dx/dlambda, J dx/dlambda = -df/dlambda
  double linearTolerance = 1e-12; // relative residual of the tangent predictor's linear solve
  double limitLoadRatio = 100;    // without a damage policy: a converged step whose displacement
                                  // per unit load (|dx| / |d load factor|) exceeds this multiple of
                                  // the first accepted step's jumped past a limit load (to a far
                                  // equilibrium, e.g. one only the stabilisation holds): it is cut
                                  // back like a failed one, and a run that cannot go on stops at the
                                  // limit load (limitLoad()); 0: no check
  std::vector<double> stops;      // load factors in (0, 1), ascending, that steps land on exactly;
                                  // the step after one starts from the converged state (no
                                  // extrapolation across a corner of a load path)
  std::string keyPrefix;          // how messages name the keys ("Solver/" in a scene)

  /// The parameter list the options are read from: "Load Steps", "Max Cutbacks", "Min Increment",
  /// "Max Total Steps", "Adaptive Steps", "Easy Iterations", "Max Increment", "Predictor",
  /// "Tangent Predictor", "Limit Load Ratio".
  static Teuchos::RCP<const Teuchos::ParameterList> validParameters();
  /// Reads and checks a list (unknown keys, wrong types, values out of range): throws
  /// std::invalid_argument with one sentence starting with `where`.
  static LoadStepperOptions fromParameterList(const Teuchos::ParameterList& list, const std::string& where);
};

/// What breaks, and how the stepper re-equilibrates after it. perinox's damage effect is one.
class DamagePolicy {
 public:
  struct Breaks {
    long long brokenBonds = 0;
    std::vector<long long> detached;
    long long fragmentParticles = 0;
    double maxStretch = 0;        // a stall break: the largest stretch broken at
    std::string note;             // a line for the console (empty: none)
  };
  virtual ~DamagePolicy() = default;
  /// After a converged step, at x and the model's load factor: break what the criterion says.
  virtual Breaks breakAfterStep(const Thyra::VectorBase<double>& x) = 0;
  /// A step that could not be converged, at the last converged state x: break to go on (nothing
  /// broken: the run stops). `why` is the failed step's reason.
  virtual Breaks breakOnStall(const Thyra::VectorBase<double>& x, const std::string& why) = 0;
  /// The reason a stall could not be broken (appended to the failure).
  virtual std::string nothingToBreak() const { return "nothing to break at the stall"; }
  /// Appended to the failure when maxStallBreaks stall breaks have been made.
  virtual std::string stallLimitReached() const {
    return "the limit of " + std::to_string(maxStallBreaks) + " stall breaks was reached";
  }
  /// The console line of a step in which something broke.
  virtual std::string describeStep(const StepRecord& record) const;

  int maxBreakRounds = 50;        // re-equilibrations per step
  bool breakOnStalls = false;     // call breakOnStall when a step fails for good
  int maxStallBreaks = 200;
  double reloadTolerance = 0.01;  // a snap-back's limit load is found to this fraction
  // At a snap-back's limit load (found by the reload): break there at once, as a stall break would
  // after the cut-backs of the next step had failed (needs breakOnStalls), instead of stepping on.
  bool breakAtSnapBackLimit = false;
};

/// A step as observers see it.
struct StepInfo {
  const StepRecord& record;
  const NewtonResult& result;     // the solve that converged it
  const Thyra::VectorBase<double>& x;
  double loadFactor;              // the model's load factor: with a load path (LoadFactorModel::setLoadPath)
                                  // the path's value at the record's pseudo-time record.loadFactor
};

class StepObserver {
 public:
  virtual ~StepObserver() = default;
  /// A line about the run's progress (cut-backs, stall breaks, snap-backs, damage).
  virtual void note(const std::string&) {}
  /// Before a converged step is accepted: a non-empty sentence stops the run with that failure,
  /// and the run's result is the previous step's state (e.g. a stability check).
  virtual std::string vet(const StepInfo&, double /*previousLoadFactor*/) { return ""; }
  /// A step was accepted.
  virtual void accepted(const StepInfo&) {}
};

/// Records a value of the state (a probe: a mean displacement, a reaction) at every accepted step,
/// with its load factor. The value function is called on every rank (it may be collective).
class ValueRecorder final : public StepObserver {
 public:
  using Value = std::function<std::vector<double>(const Thyra::VectorBase<double>& x)>;
  explicit ValueRecorder(Value value) : value_(std::move(value)) {}
  void accepted(const StepInfo& s) override { values_.push_back({s.loadFactor, value_(s.x)}); }
  const std::vector<std::pair<double, std::vector<double>>>& values() const { return values_; }

 private:
  Value value_;
  std::vector<std::pair<double, std::vector<double>>> values_;
};

/// How a stepper commits a model's history (the internal variables of materials with history, such
/// as plastic strain). The model's residual, tangent and J v at x are pure functions of x and its
/// committed state: every evaluation (Newton iterations, line searches, J v products, cut-backs,
/// re-equilibrations after bond breaks) computes a trial state from the committed one and never
/// writes it back. The stepper calls this once per accepted step, with the accepted solution at the
/// model's load factor: after the step's solve and its damage re-equilibrations converged and the
/// observers' veto passed, before the observers see the step. A failed, cut back or vetoed step
/// commits nothing. A host that drives the model itself commits through the same call. Collective.
using HistoryCommit = std::function<void(const Thyra::VectorBase<double>& x)>;

/// The stepper's own state, for checkpoints and restarts.
struct StepperState {
  int step = 0;
  double loadFactor = 0.0;
  double increment = 0.0;        // the next increment
  double lastIncrement = 0.0;    // of the last accepted step (the predictor's)
  int stallBreaks = 0;
  // The last re-equilibration found the damaged body's limit load (a snap-back): the state is at
  // that limit, to the damage policy's reload tolerance.
  bool atLimit = false;
  // |dx| / |d load factor| of the first accepted step that moved the load (0: none yet), the
  // reference of LoadStepperOptions::limitLoadRatio.
  double initialCompliance = 0.0;
};

class LoadStepper {
 public:
  /// solve: one step's nonlinear solve at the model's load factor (NewtonSolver::solve, ADR, ...);
  /// reequilibrate: the solve after a damage break (default: solve).
  LoadStepper(Teuchos::RCP<LoadFactorModel> model, std::function<NewtonResult(Thyra::VectorBase<double>&)> solve,
              const LoadStepperOptions& options);
  void setReequilibrationSolve(std::function<NewtonResult(Thyra::VectorBase<double>&)> solve) { reequilibrate_ = std::move(solve); }
  void setDamagePolicy(DamagePolicy* policy) { damage_ = policy; }
  /// The model's history commit (HistoryCommit), for a model whose materials have history.
  void setHistoryCommit(HistoryCommit commit) { commit_ = std::move(commit); }
  void addObserver(StepObserver* observer) { observers_.push_back(observer); }
  /// Start from a checkpoint's state instead of lambda = 0 (the records and path of the steps so
  /// far, the converged state and the one before it).
  void resume(const StepperState& state, std::vector<StepRecord> records, std::vector<double> path,
              const Thyra::VectorBase<double>& x, const Thyra::VectorBase<double>& xPrevious);
  /// Steps to load factor 1 (or until a step fails for good). Returns true when it got there.
  bool run();

  const StepperState& state() const { return state_; }
  const std::vector<StepRecord>& records() const { return records_; }
  const std::vector<double>& path() const { return path_; }   // load factor of every accepted step
  /// Bonds broken over the run (the sum of the records' brokenBonds).
  long long brokenBonds() const {
    long long n = 0;
    for (const auto& r : records_) n += r.brokenBonds;
    return n;
  }
  const Thyra::VectorBase<double>& converged() const { return *xConverged_; }
  const Thyra::VectorBase<double>& previous() const { return *xPrevious_; }
  const std::string& failure() const { return failure_; }
  /// The model's load factor of the last converged step when the run stopped at a limit load
  /// (LoadStepperOptions::limitLoadRatio); NaN otherwise.
  double limitLoad() const { return limitLoad_; }

 private:
  // The named steps of run(), in order.
  Teuchos::RCP<Thyra::VectorBase<double>> firstStepTangent();
  NewtonResult solveWithCutbacks(Thyra::VectorBase<double>& x, StepRecord& rec, int& cut,
                                 const Thyra::VectorBase<double>* firstTangent);
  void breakAtStall(Thyra::VectorBase<double>& x, StepRecord& rec, NewtonResult& nr, double stepIncrement);
  void retryWithoutPredictor(Thyra::VectorBase<double>& x, StepRecord& rec, NewtonResult& nr, int& cut,
                             double stepIncrement);
  bool breakAfterConvergence(Thyra::VectorBase<double>& x, StepRecord& rec, NewtonResult& nr, double tStep);
  bool vetted(const StepRecord& rec, const NewtonResult& nr, const Thyra::VectorBase<double>& x, double previous);
  void accept(const Thyra::VectorBase<double>& x, const StepRecord& rec, const NewtonResult& nr, double previous);
  /// The work of the step under way into its record.
  void account(StepRecord& rec) const;
  NewtonResult reequilibrate(Thyra::VectorBase<double>& x, double& lambda, StepRecord& rec);
  /// z = dx/dlambda at the converged state x from J z = -df/dlambda; "" or why it failed.
  std::string tangent(const Thyra::VectorBase<double>& x, Thyra::VectorBase<double>& z);
  void note(const std::string& line);
  void setLoadFactor(double lambda);
  /// Runs a solve and adds its work to the step's.
  NewtonResult counted(const std::function<NewtonResult(Thyra::VectorBase<double>&)>& solve, Thyra::VectorBase<double>& x);

  Teuchos::RCP<LoadFactorModel> model_;
  std::function<NewtonResult(Thyra::VectorBase<double>&)> solve_, reequilibrate_;
  LoadStepperOptions options_;
  DamagePolicy* damage_ = nullptr;
  HistoryCommit commit_;
  std::vector<StepObserver*> observers_;
  StepperState state_;
  std::vector<StepRecord> records_;
  std::vector<double> path_;
  Teuchos::RCP<Thyra::VectorBase<double>> xConverged_, xPrevious_;
  std::string failure_;
  double limitLoad_ = std::numeric_limits<double>::quiet_NaN();
  /// Whether the limit-load check is on (a ratio, and no damage policy: damage has its own
  /// snap-back handling).
  bool checksLimitLoad() const { return options_.limitLoadRatio > 0 && !damage_; }
  /// |x - converged| / |load(to) - load(from)|, the pseudo-times mapped through the load path; 0
  /// when the load does not change.
  double compliance(const Thyra::VectorBase<double>& x, double from, double to) const;
  /// "" when the converged solve x from the converged state at pseudo-time lambda to target
  /// stays within the limit-load ratio, else why not.
  std::string pastLimitLoad(const Thyra::VectorBase<double>& x, double lambda, double target) const;
  // Work of the step under way (every solve call in it).
  long long stepWork_ = 0;
  LinearSolveCounts stepLinear_;
};

}  // namespace perinox
