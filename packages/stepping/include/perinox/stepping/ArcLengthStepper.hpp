#pragma once
// Pseudo-arc-length continuation for any Thyra::ModelEvaluator whose parameter p(0) is the load
// factor (through LoadFactorModel), so that a path can be followed through limit points where
// load stepping fails. Keller's linearised constraint on Riks' normal plane through the predictor,
// with a bordering solve on the model's W_op and W factory. Nothing here knows peridynamics:
// perinox's evaluator is one model it drives (drivers/Simulation.cpp), a snap-through test double
// another (packages/stepping/tests/test_arc_length.cpp). LOCA is not used: see
// docs/trilinos-notes.md.
//
// Unknowns (x, lambda); equations
//   f(x, lambda) = 0
//   N(x, lambda) = w t_x . (x - x_pred) + t_l (lambda - l_pred) = 0
// with (t_x, t_l) the unit direction of the predictor in the metric |(dx, dl)|^2 = w |dx|^2 + dl^2,
// w = 1 / |dx/dlambda|^2 at the start (displacement and load factor weigh equally in the first arc).
// Each corrector iteration evaluates f and W = df/dx once and solves J a = -f, J b = df/dlambda:
//   dl = (-N - w t_x . a) / (t_l - w t_x . b),  dx = a - dl b.
// N is linear, so after the first iteration it vanishes up to round-off. Each step predicts along
// the secant of the last two converged points (the first along the tangent J z = -df/dlambda); the
// arc is halved on failure and grows by 1.5 after easy steps; a step that would cross the target
// load factor (or monitored value) is redone with its arc shortened by secant iteration until it
// ends on the target to 1e-9.
#include <Teuchos_ParameterList.hpp>
#include <Teuchos_RCP.hpp>
#include <Thyra_VectorBase.hpp>
#include <functional>
#include <string>
#include <vector>

#include "perinox/solver/NewtonSolver.hpp"
#include "perinox/stepping/LoadStepper.hpp"

namespace perinox {

/// The continuation controls (validated; validParameters() documents them).
struct ArcLengthStepperOptions {
  double initialArcLength = 0.05;  // arc of the first step, in the metric above
  double minArcLength = 1e-4;      // a step whose halved arc would fall below this fails
  double maxArcLength = 0.5;       // growth after easy steps stops here
  int maxSteps = 100;              // converged steps allowed before the target
  double targetLoadFactor = 1.0;   // stop when the load factor reaches it
  double targetMonitor = 0.0;      // stop when |monitor(x)| reaches it (0: off; needs setMonitor)
  int maxCutbacks = 4;             // halvings of a failing step's arc
  int easyIterations = 4;          // a step of at most this many corrector iterations grows the arc
  // The corrector (the seed's test: |f| / scale <= tolerance, or |f| <= floorFactor * roundoff).
  double tolerance = 1e-10;
  int maxIterations = 25;
  double linearTolerance = 1e-12;  // relative residual requested from iterative linear solvers
  double floorFactor = 2.0;
  int stagnationWindow = 5;        // iterations over which "no decrease" means stagnation
  std::string keyPrefix;           // how messages name the keys ("Solver/Arc Length/" in a scene)
  std::string monitorName = "monitored value";  // how messages name the monitor ("deflection")

  /// The parameter list the options are read from: "Initial Arc Length", "Min Arc Length",
  /// "Max Arc Length", "Max Steps", "Target Load Factor", "Target Monitor", "Max Cutbacks",
  /// "Easy Iterations", "Tolerance", "Max Iterations", "Linear Tolerance".
  static Teuchos::RCP<const Teuchos::ParameterList> validParameters();
  /// Reads and checks a list (unknown keys, wrong types, values out of range): throws
  /// std::invalid_argument with one sentence starting with `where`.
  static ArcLengthStepperOptions fromParameterList(const Teuchos::ParameterList& list, const std::string& where);
};

/// A local maximum of the load factor along the path (a limit point passed).
struct PathLimitPoint {
  int step = 0;          // the converged step at which the load factor peaked
  double loadFactor = 0;
  double monitor = 0;    // the monitored value there (0 without a monitor)
};

/// The Riks corrector on its own: Newton on (f, N) with the bordering solve.
class ArcLengthCorrector {
 public:
  ArcLengthCorrector(Teuchos::RCP<LoadFactorModel> model, Teuchos::RCP<const ResidualScale> scale,
                     const ArcLengthStepperOptions& options);
  /// Tangent of the path at an equilibrium: z = dx/dlambda from J z = -df/dlambda (the model at
  /// lambda). Returns "" or the reason it failed.
  std::string tangent(const Thyra::VectorBase<double>& x, double lambda, Thyra::VectorBase<double>& z);
  /// From the predictor (x, lambda) = (xPred, lPred) onto the path, on the plane through it
  /// normal to (tx, tl) in the metric with weight w. Updates x and lambda (the model is left at
  /// the final lambda). `iterations` counts corrector iterations, `residuals` the normalised |f|.
  NewtonResult correct(Thyra::VectorBase<double>& x, double& lambda, const Thyra::VectorBase<double>& tx, double tl,
                       double w, const Thyra::VectorBase<double>& xPred, double lPred);
  /// Linear solves (tangent and bordering) and their Krylov iterations over every call so far.
  const LinearSolveCounts& totalLinear() const { return counts_; }
  /// Corrector iterations (bordering steps begun) over every call so far, failed attempts included.
  long long totalCorrectorIterations() const { return correctorIterations_; }

 private:
  bool solve(const Thyra::LinearOpWithSolveBase<double>& A, const Thyra::VectorBase<double>& b,
             Thyra::VectorBase<double>& y, std::string& why);
  Teuchos::RCP<LoadFactorModel> model_;
  Teuchos::RCP<const ResidualScale> scale_;
  ArcLengthStepperOptions opt_;
  LinearSolveCounts counts_;
  long long correctorIterations_ = 0;
};

class ArcLengthStepper {
 public:
  ArcLengthStepper(Teuchos::RCP<LoadFactorModel> model, Teuchos::RCP<const ResidualScale> scale,
                   const ArcLengthStepperOptions& options);
  /// A scalar of the state that can end the run (targetMonitor) and is reported with limit
  /// points (a deflection).
  void setMonitor(std::function<double(const Thyra::VectorBase<double>&)> monitor) { monitor_ = std::move(monitor); }
  /// Counts the tangent's negative pivots at every converged point (StepRecord::negativePivots).
  void setStabilityCount(std::function<int(const Thyra::VectorBase<double>&)> count) { stability_ = std::move(count); }
  /// Observers see every accepted step (and notes: cut-backs, landing on the target, limit points).
  /// The model's history commit, called once per accepted step before the observers (HistoryCommit).
  void setHistoryCommit(HistoryCommit commit) { commit_ = std::move(commit); }
  void addObserver(StepObserver* observer) { observers_.push_back(observer); }
  /// Follows the path from the equilibrium (x0, lambda0) until the target is reached (true) or a
  /// step fails for good (false, failure() says why).
  bool run(const Thyra::VectorBase<double>& x0, double lambda0);

  const std::vector<StepRecord>& records() const { return records_; }
  const std::vector<double>& path() const { return path_; }          // load factor of every converged step
  const std::vector<double>& monitorHistory() const { return monitors_; }  // initial point first
  const std::vector<PathLimitPoint>& limitPoints() const { return limitPoints_; }
  const Thyra::VectorBase<double>& converged() const { return *xConverged_; }
  double loadFactor() const { return lambda_; }
  const std::string& failure() const { return failure_; }
  const ArcLengthCorrector& corrector() const { return corrector_; }

 private:
  double monitorAt(const Thyra::VectorBase<double>& x) const { return monitor_ ? monitor_(x) : 0.0; }
  bool atTarget() const;
  /// One step from the converged point: predictor, corrector, cut-backs; x and l receive the end.
  NewtonResult stepOnce(int step, double& ds, int& cut, Thyra::VectorBase<double>& x, double& l);
  /// Redoes a converged step that crossed the target with a shorter arc, landing on it.
  void landOnTarget(int step, double& ds, Thyra::VectorBase<double>& x, double& l, NewtonResult& r);
  /// Makes (x, l) the converged point: secant direction, records, limit points, observers.
  void accept(StepRecord& rec, const NewtonResult& r, const Thyra::VectorBase<double>& x, double l, double tStep);
  void note(const std::string& line);

  Teuchos::RCP<LoadFactorModel> model_;
  ArcLengthStepperOptions opt_;
  ArcLengthCorrector corrector_;
  std::function<double(const Thyra::VectorBase<double>&)> monitor_;
  std::function<int(const Thyra::VectorBase<double>&)> stability_;
  HistoryCommit commit_;
  std::vector<StepObserver*> observers_;
  std::vector<StepRecord> records_;
  std::vector<double> path_, monitors_, lambdas_;
  std::vector<PathLimitPoint> limitPoints_;
  Teuchos::RCP<Thyra::VectorBase<double>> xConverged_, tx_, xPred_;
  double lambda_ = 0.0, tl_ = 1.0, w_ = 1.0;
  std::string failure_;
};

}  // namespace perinox
