#pragma once
// perinox's extensions of NOX, for host applications that set up their own NOX solve (on
// perinox's evaluator or any Thyra model) and want perinox's convergence test and accounting:
//   CountingGroup          NOX::Thyra::Group that counts linear solves, Krylov iterations and the
//                          solves its linear solver did not converge (NOX goes on with the inexact
//                          direction), computes J^T F for the trust-region solvers, and applies
//                          J and J^T with its own last Jacobian;
//   NormalizedResidualTest the seed's test |R| / scale <= tol with a round-off floor and an
//                          optional stagnation stop, recording the normalised residual history.
//   newtonStatusTests      FiniteValue OR NormalizedResidualTest OR MaxIters, ready for
//                          NOX::Solver::buildSolver.
// NewtonSolver (NewtonSolver.hpp) is built from these.
#include <NOX_Solver_Generic.H>
#include <NOX_StatusTest_Combo.H>
#include <NOX_StatusTest_FiniteValue.H>
#include <NOX_StatusTest_Generic.H>
#include <NOX_StatusTest_MaxIters.H>
#include <NOX_Thyra_Group.H>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "perinox/solver/NewtonSolver.hpp"

namespace perinox {

class CountingGroup final : public NOX::Thyra::Group {
 public:
  using NOX::Thyra::Group::Group;
  /// Copies (the trust-region solvers compute directions on them) share the counts.
  CountingGroup(const CountingGroup& source, NOX::CopyType type);
  NOX::Abstract::Group::ReturnType computeNewton(Teuchos::ParameterList& p) override;
  NOX::Abstract::Group::ReturnType computeGradient() override;
  NOX::Abstract::Group::ReturnType applyJacobian(const NOX::Abstract::Vector& in, NOX::Abstract::Vector& out) const override;
  NOX::Abstract::Group::ReturnType applyJacobianTranspose(const NOX::Abstract::Vector& in,
                                                          NOX::Abstract::Vector& out) const override;
  Teuchos::RCP<NOX::Abstract::Group> clone(NOX::CopyType type) const override;
  /// The relative residual a linear solve must reach to count as converged.
  void setTolerance(double t) { tolerance_ = t; }
  /// A lower bound on each solve's relative tolerance, asked before the solve: a Newton system
  /// is not solved more tightly than this even when the forcing term asks it (NewtonSolver uses
  /// it with Eisenstat-Walker so the last system of a step is solved only as far as the Newton
  /// tolerance needs). Empty: the forcing term's tolerance as it is.
  void setForcingFloor(std::function<double()> floor) { floor_ = std::move(floor); }
  int failures() const { return stats_->failures; }
  double lastAchieved() const { return stats_->lastTol; }
  int lastIterations() const { return stats_->lastIters; }
  const LinearSolveCounts& counts() const { return stats_->counts; }

 private:
  struct Stats {
    int failures = 0;
    double lastTol = 0;
    int lastIters = 0;
    LinearSolveCounts counts;
  };
  double tolerance_ = 0;
  std::function<double()> floor_;
  std::shared_ptr<Stats> stats_ = std::make_shared<Stats>();
};

/// Converged when |R| / scale <= tol or |R| <= floorFactor * roundoff (the residual's round-off
/// level), with the scale from a ResidualScale at the current iterate. With stagnationStop > 0 it
/// fails once the residual has not halved over that many iterations.
class NormalizedResidualTest final : public NOX::StatusTest::Generic {
 public:
  NormalizedResidualTest(Teuchos::RCP<const ResidualScale> scale, double tol, double floorFactor, int stagnationStop);
  NOX::StatusTest::StatusType checkStatus(const NOX::Solver::Generic& solver, NOX::StatusTest::CheckType) override;
  NOX::StatusTest::StatusType getStatus() const override { return status_; }
  std::ostream& print(std::ostream& os, int indent = 0) const override;
  /// The normalised residual of every iterate checked, in order.
  std::vector<double> history() const;
  bool reactionNormalised() const { return reaction_; }
  double scale() const { return scale_; }
  /// The normalised residual of the iterate checked last (NaN before the first check).
  double last() const { return history_.empty() ? std::nan("") : history_.rbegin()->second; }
  double tolerance() const { return tol_; }
  bool atFloor() const { return atFloor_; }
  double floorNormalised() const { return floor_ / scale_; }
  const std::string& stagnation() const { return stagnation_; }

 private:
  Teuchos::RCP<const ResidualScale> residualScale_;
  double floor_ = 0.0;
  bool atFloor_ = false;
  double tol_;
  int stagnationStop_ = 0;
  std::string stagnation_;
  NOX::StatusTest::StatusType status_ = NOX::StatusTest::Unevaluated;
  std::map<int, double> history_;
  bool reaction_ = false;
  double scale_ = 1.0;
};

/// perinox's status tests for a NOX solve, as NewtonSolver uses them: combo = FiniteValue OR
/// residual OR maxIters (the parts kept to tell afterwards which one stopped the solve).
struct NewtonStatusTests {
  Teuchos::RCP<NOX::StatusTest::Combo> combo;
  Teuchos::RCP<NormalizedResidualTest> residual;
  Teuchos::RCP<NOX::StatusTest::FiniteValue> finite;
  Teuchos::RCP<NOX::StatusTest::MaxIters> maxIters;
};
NewtonStatusTests newtonStatusTests(Teuchos::RCP<const ResidualScale> scale, double tolerance, int maxIterations,
                                    double floorFactor = 2.0, int stagnationStop = 0);

// A Newton solve set up the way NewtonSolver sets it up, for a host that runs NOX itself:
//   auto group = countingGroup(model, x, options.linearTolerance);
//   auto tests = newtonStatusTests(scale, options.tolerance, options.maxIterations, ...);
//   auto solver = NOX::Solver::buildSolver(group, tests.combo, newtonParameters(options));
//   return solveNox(*solver, tests, group.get(), x, options.maxIterations);

/// NOX's parameters: options.lineSearch (a line search, or "Trust Region" / "Inexact Trust
/// Region"), Newton directions with the constant forcing term options.linearTolerance and
/// "Rescue Bad Newton Solve", NOX's output at options.verbosity on rank 0.
Teuchos::RCP<Teuchos::ParameterList> newtonParameters(const NewtonOptions& options);
/// For a host that hands NOX (or Piro, as its "NOX" sublist) the whole list and lets NOX build the
/// status tests: newtonParameters(options) with "Status Tests" = RelativeNormF (|F| <=
/// relativeTolerance |F(x0)|) OR NormF (|F| <= options.floorFactor * roundoff, where |F| cannot
/// fall further; PeridynamicEvaluator::roundoffScale) OR MaxIters (options.maxIterations) OR
/// FiniteValue. (NOX's default, |F| < 1e-8, means nothing for forces of 1e7 N.)
Teuchos::RCP<Teuchos::ParameterList> newtonParametersWithStatusTests(const NewtonOptions& options, double relativeTolerance,
                                                                    double roundoff);
/// A CountingGroup at the initial guess x (copied), with the model's W_prec when it supports one
/// (matrix-free W_op); linear solves above linearTolerance count as unconverged.
Teuchos::RCP<CountingGroup> countingGroup(const Teuchos::RCP<const Thyra::ModelEvaluator<double>>& model,
                                          const Thyra::VectorBase<double>& x, double linearTolerance);
/// The outcome of a NOX solve as NewtonSolver reports it: convergence (NOX's status and the
/// residual test's), iterations and the residual history, the linear work of group (may be
/// null), and for a failed solve without `failure` (why it threw) the most specific cause.
NewtonResult newtonResult(const NewtonStatusTests& tests, const CountingGroup* group, NOX::StatusTest::StatusType status,
                          int iterations, const std::string& failure, int maxIterations);
/// Why the NOX solve being handled threw, as NewtonSolver reports it ("model evaluation failed: ...",
/// the linear solver's reason, "nonlinear solver error: ..."). Call it inside a catch block.
std::string noxFailure();
/// Runs solver (built on group and tests), copies its solution into x and returns newtonResult;
/// an exception becomes the result's failure (the load stepper then cuts back).
NewtonResult solveNox(NOX::Solver::Generic& solver, const NewtonStatusTests& tests, const CountingGroup* group,
                      Thyra::VectorBase<double>& x, int maxIterations);

}  // namespace perinox
