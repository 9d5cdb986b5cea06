#pragma once
// Full Newton for one load step through NOX (line search selectable), with the seed's
// convergence test |R| / |f_ext| <= tol (reaction-normalised when f_ext = 0).
#include <Teuchos_ParameterList.hpp>
#include <Teuchos_RCP.hpp>
#include <Thyra_LinearOpWithSolveFactoryBase.hpp>
#include <Thyra_ModelEvaluator.hpp>
#include <Thyra_VectorBase.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace perinox {

class PeridynamicEvaluator;

/// Work done by the linear solver: Newton (or corrector) systems solved, and the Krylov
/// iterations spent on them (0 for direct solvers, which report none).
struct LinearSolveCounts {
  long long solves = 0;
  long long krylovIterations = 0;
  long long failures = 0;  // solves the linear solver reported unconverged (an inexact direction)
};

struct NewtonOptions {
  double tolerance = 1e-10;        // on the normalised residual
  int maxIterations = 25;
  std::string lineSearch = "Full Step";  // "Full Step", "Backtrack", "Polynomial"
  double linearTolerance = 1e-12;  // relative tolerance handed to iterative linear solvers
  // How that tolerance is set per Newton iteration: "Constant" (linearTolerance every time) or
  // "Eisenstat-Walker" (NOX's Type 2 forcing term: eta_k = 0.9 (|F_k| / |F_k-1|)^2, first 1e-4,
  // never below linearTolerance nor above 1e-4: looser solves far from the solution, tight ones
  // near it, so Newton keeps its quadratic rate for fewer Krylov iterations). Direct solvers
  // solve exactly either way.
  std::string forcingTerm = "Constant";
  int verbosity = 0;               // NOX's own output (0 = quiet)
  double floorFactor = 10.0;       // also converged when |R| <= floorFactor * roundoffScale (0: off)
  int stagnationStop = 0;          // > 0: stop early with "residual stagnation" when the residual
                                   // has not halved over this many iterations (0: only diagnose a
                                   // failed solve afterwards, over 5 iterations)
};

struct NewtonResult {
  bool converged = false;
  int iterations = 0;
  long long work = 0;              // iterations done, counted also when the solver threw (the
                                   // residual history's length); ADR: its explicit iterations
  std::vector<double> residuals;   // normalised residual at iterations 0..iterations
  bool reactionNormalised = false; // true when f_ext = 0 and the reaction norm was the scale
  double normaliser = 1.0;
  bool atRoundoffFloor = false;    // converged on the round-off floor, not on the tolerance
  double floorNormalised = 0.0;    // the floor, normalised like the residuals
  int linearFailures = 0;          // Newton solves whose linear solver reported no convergence
  LinearSolveCounts linear;        // linear solves and Krylov iterations of this call
  std::string failure;             // why it failed (empty when converged)
};

/// "residual stagnation: ..." when the last `window` normalised residuals all stayed above half of
/// the best residual before them (Newton near a solution halves it every iteration), else "".
std::string stagnationDiagnosis(const std::vector<double>& residuals, int window);

/// "linear solver error: <reason>" from an exception a Trilinos solve threw: the last non-empty
/// line of its message, with a hint when a factorisation found the tangent singular.
std::string linearSolverFailure(const std::exception& e);

/// What the seed's convergence test divides |R| by (|R| / scale <= tolerance), and the round-off
/// level below which |R| cannot be resolved. Implement it for any model; perinox's evaluator has
/// EvaluatorResidualScale.
class ResidualScale {
 public:
  virtual ~ResidualScale() = default;
  /// The scale at the state x (the model's current load factor); set `reaction` when it is a
  /// reaction norm (reported per step). A scale <= 0 makes the test absolute.
  virtual double scale(const Thyra::VectorBase<double>& x, bool& reaction) const = 0;
  /// |R| at or below floorFactor times this also counts as converged (0: no floor).
  virtual double roundoff() const { return 0.0; }
};

/// perinox's scale (seed 000): |lambda f_ext|, or, when no external force acts, the reaction
/// norm at x; the round-off level is PeridynamicEvaluator::roundoffScale.
class EvaluatorResidualScale final : public ResidualScale {
 public:
  explicit EvaluatorResidualScale(Teuchos::RCP<const PeridynamicEvaluator> evaluator) : ev_(std::move(evaluator)) {}
  double scale(const Thyra::VectorBase<double>& x, bool& reaction) const override;
  double roundoff() const override;

 private:
  Teuchos::RCP<const PeridynamicEvaluator> ev_;
};

/// Newton's method through NOX on any Thyra::ModelEvaluator, with perinox's convergence test and
/// linear-solve accounting (NoxExtensions.hpp). The Jacobian comes from the model's W_op and
/// W factory; a model that supports W_prec builds the preconditioner (matrix-free W_op).
class NewtonSolver {
 public:
  NewtonSolver(Teuchos::RCP<const Thyra::ModelEvaluator<double>> model, Teuchos::RCP<const ResidualScale> scale,
               const NewtonOptions& options);
  /// perinox's evaluator with its own scale.
  NewtonSolver(Teuchos::RCP<PeridynamicEvaluator> evaluator, const NewtonOptions& options);
  /// Solves f(x) = 0 at the model's current load factor (its nominal p), starting from and
  /// updating x. On failure x keeps the last iterate; the caller restores a converged state.
  NewtonResult solve(Thyra::VectorBase<double>& x);
  /// Totals over every call of solve, failed ones included (the cost of cut-backs and retries):
  /// Newton iterations and linear work.
  long long totalNewtonIterations() const { return totalNewton_; }
  const LinearSolveCounts& totalLinear() const { return totalLinear_; }

 private:
  Teuchos::RCP<const Thyra::ModelEvaluator<double>> model_;
  Teuchos::RCP<const ResidualScale> scale_;
  NewtonOptions options_;
  long long totalNewton_ = 0;
  LinearSolveCounts totalLinear_;
};

}  // namespace perinox
