#pragma once
// Pseudo-arc-length continuation (Keller's linearised constraint, Riks' normal plane through the
// predictor) with a bordering solve on the evaluator's assembled tangent, so that a path can be
// followed through limit points where load control fails. LOCA is not used: see
// docs/trilinos-notes.md.
//
// Unknowns (x, lambda); equations
//   f(x, lambda) = 0
//   N(x, lambda) = w t_x . (x - x0) + t_l (lambda - l0) - ds = 0
// with (t_x, t_l) the unit direction of the predictor in the metric |(dx, dl)|^2 = w |dx|^2 + dl^2.
// Each corrector iteration factors J = df/dx once and solves J a = -f and J b = df/dlambda:
//   dl = (-N - w t_x . a) / (t_l - w t_x . b),  dx = a - dl b.
// N is linear, so after the first iteration it vanishes up to round-off.
#include <Teuchos_RCP.hpp>
#include <Thyra_VectorBase.hpp>
#include <string>
#include <vector>

#include "perinox/solver/NewtonSolver.hpp"

namespace perinox {

class PeridynamicEvaluator;

struct ArcLengthOptions {
  double tolerance = 1e-10;        // on |f| / |lambda f_ext| (or / |reaction| when f_ext = 0)
  int maxIterations = 25;
  double linearTolerance = 1e-12;  // relative residual requested from iterative linear solvers
  double floorFactor = 2.0;        // round-off floor, as in NewtonOptions
  int stagnationWindow = 5;        // iterations over which "no decrease" means stagnation
};

struct ArcLengthResult {
  bool converged = false;
  int iterations = 0;
  std::vector<double> residuals;   // normalised residual per iteration (0 = predictor)
  bool reactionNormalised = false;
  bool atRoundoffFloor = false;
  double floorNormalised = 0.0;
  int linearFailures = 0;          // linear solves that reported SOLVE_STATUS_UNCONVERGED
  std::string failure;
};

class ArcLengthSolver {
 public:
  ArcLengthSolver(Teuchos::RCP<PeridynamicEvaluator> evaluator, const ArcLengthOptions& options);

  /// df/dlambda at (x, lambda): the evaluator's DfDp (PeridynamicEvaluator::loadDerivative).
  /// Leaves the evaluator at lambda.
  void loadDerivative(const Thyra::VectorBase<double>& x, double lambda, Thyra::VectorBase<double>& fl) const;

  /// Tangent of the path at an equilibrium: z = dx/dlambda from J z = -df/dlambda.
  /// Returns "" or the reason it failed.
  std::string tangent(const Thyra::VectorBase<double>& x, double lambda, Thyra::VectorBase<double>& z) const;

  /// Corrector from the predictor (x, lambda) onto the path, on the constraint through the
  /// predictor normal to (tx, tl) in the metric with weight w. Updates x and lambda.
  ArcLengthResult correct(Thyra::VectorBase<double>& x, double& lambda, const Thyra::VectorBase<double>& tx,
                          double tl, double w, const Thyra::VectorBase<double>& xPred, double lPred) const;

  /// Linear solves (tangent and bordering) and their Krylov iterations over every call so far.
  const LinearSolveCounts& totalLinear() const { return counts_; }
  /// Corrector iterations (bordering steps begun) over every call so far, failed attempts included.
  long long totalCorrectorIterations() const { return correctorIterations_; }

 private:
  mutable LinearSolveCounts counts_;
  mutable long long correctorIterations_ = 0;
  Teuchos::RCP<PeridynamicEvaluator> ev_;
  ArcLengthOptions opt_;
};

}  // namespace perinox
