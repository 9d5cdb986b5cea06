// NOX set-up. One translation unit holds all NOX/Thyra solver headers.
#include "perinox/solver/NewtonSolver.hpp"

#include <NOX.H>
#include <NOX_Solver_Factory.H>
#include <NOX_StatusTest_Combo.H>
#include <NOX_StatusTest_FiniteValue.H>
#include <NOX_StatusTest_MaxIters.H>
#include <NOX_Thyra.H>
#include <NOX_Thyra_Group.H>
#include <NOX_Thyra_Vector.H>
#include <Thyra_VectorStdOps.hpp>
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <sstream>

#include "perinox/evaluator/PeridynamicEvaluator.hpp"
#include "perinox/solver/NoxExtensions.hpp"

namespace perinox {

std::string stagnationDiagnosis(const std::vector<double>& r, int window) {
  // Stagnation: the last `window` residuals all stay above half of the best residual reached
  // before them. Comparing with the best earlier value (not the one just before the window)
  // keeps round-off noise around a floor from hiding the stagnation.
  if (window < 1 || static_cast<int>(r.size()) < window + 1) return "";
  const std::size_t n = r.size();
  double best = r[0];
  for (std::size_t k = 0; k + window < n; ++k) best = std::min(best, r[k]);
  double lo = r[n - 1], hi = r[n - 1];
  for (std::size_t k = n - window; k < n; ++k) {
    if (!std::isfinite(r[k])) return "";
    lo = std::min(lo, r[k]);
    hi = std::max(hi, r[k]);
  }
  if (!(lo > 0.5 * best)) return "";
  std::ostringstream s;
  s << "residual stagnation: in the last " << window << " iterations the normalised residual stayed between " << lo
    << " and " << hi << ", never below half of the best earlier value " << best;
  return s.str();
}

/// NOX's Thyra group, counting the Newton systems its linear solver did not solve (Belos
/// reports SOLVE_STATUS_UNCONVERGED at its iteration limit or on breakdown; NOX then carries
/// on with the inexact direction because of "Rescue Bad Newton Solve").
CountingGroup::CountingGroup(const CountingGroup& source, NOX::CopyType type)
    : NOX::Thyra::Group(source, type), tolerance_(source.tolerance_), floor_(source.floor_), stats_(source.stats_) {}

NOX::Abstract::Group::ReturnType CountingGroup::computeNewton(Teuchos::ParameterList& p) {
  last_linear_solve_num_iters_ = 0;  // direct solvers leave it untouched
  if (floor_) {
    const double floor = floor_();
    if (floor > p.get<double>("Tolerance", tolerance_)) p.set("Tolerance", floor);
  }
  const auto st = NOX::Thyra::Group::computeNewton(p);
  ++stats_->counts.solves;
  stats_->counts.krylovIterations += std::max(0, last_linear_solve_num_iters_);
  // A solve counts as failed when its status is not Ok and its achieved relative residual is
  // above the request (Belos may flag "unconverged" after reaching it; see ArcLength.cpp).
  // The request is this solve's: NOX's forcing term sets p's "Tolerance" before each solve.
  const double asked = std::max(tolerance_, p.get<double>("Tolerance", tolerance_));
  const bool bad = st != NOX::Abstract::Group::Ok || last_linear_solve_status_ != NOX::Abstract::Group::Ok;
  if (bad && !(last_linear_solve_achieved_tol_ >= 0 && last_linear_solve_achieved_tol_ <= asked)) {
    ++stats_->failures;
    stats_->lastTol = last_linear_solve_achieved_tol_;
    stats_->lastIters = last_linear_solve_num_iters_;
  }
  return st;
}

/// Steepest-descent direction for the trust-region solvers: g = J^T F. NOX's Thyra group
/// does not implement it; the assembled Jacobian supports the transpose product.
NOX::Abstract::Group::ReturnType CountingGroup::computeGradient() {
  if (is_valid_gradient_dir_) return NOX::Abstract::Group::Ok;
  if (!is_valid_f_ || !is_valid_jacobian_ || !::Thyra::opSupported(*lop_, ::Thyra::TRANS))
    return NOX::Abstract::Group::BadDependency;
  ::Thyra::apply(*lop_, ::Thyra::TRANS, f_vec_->getThyraVector(), gradient_vec_->getThyraRCPVector().ptr());
  is_valid_gradient_dir_ = true;
  return NOX::Abstract::Group::Ok;
}

/// J v with the Jacobian operator of this group's last computeJacobian. NOX's version refuses
/// when another group copy holds the shared solver object, which the trust-region solvers
/// provoke by copying groups between the Newton and Cauchy directions.
NOX::Abstract::Group::ReturnType CountingGroup::applyJacobian(const NOX::Abstract::Vector& in,
                                                              NOX::Abstract::Vector& out) const {
  if (!is_valid_jacobian_) return NOX::Abstract::Group::BadDependency;
  ::Thyra::apply(*lop_, ::Thyra::NOTRANS, dynamic_cast<const NOX::Thyra::Vector&>(in).getThyraVector(),
                 dynamic_cast<NOX::Thyra::Vector&>(out).getThyraRCPVector().ptr());
  return NOX::Abstract::Group::Ok;
}

NOX::Abstract::Group::ReturnType CountingGroup::applyJacobianTranspose(const NOX::Abstract::Vector& in,
                                                                       NOX::Abstract::Vector& out) const {
  if (!is_valid_jacobian_ || !::Thyra::opSupported(*lop_, ::Thyra::TRANS)) return NOX::Abstract::Group::BadDependency;
  ::Thyra::apply(*lop_, ::Thyra::TRANS, dynamic_cast<const NOX::Thyra::Vector&>(in).getThyraVector(),
                 dynamic_cast<NOX::Thyra::Vector&>(out).getThyraRCPVector().ptr());
  return NOX::Abstract::Group::Ok;
}

Teuchos::RCP<NOX::Abstract::Group> CountingGroup::clone(NOX::CopyType type) const {
  return Teuchos::rcp(new CountingGroup(*this, type));
}

NormalizedResidualTest::NormalizedResidualTest(Teuchos::RCP<const ResidualScale> scale, double tol, double floorFactor,
                                               int stagnationStop)
    : residualScale_(std::move(scale)), floor_(floorFactor * residualScale_->roundoff()), tol_(tol),
      stagnationStop_(stagnationStop) {}

NOX::StatusTest::StatusType NormalizedResidualTest::checkStatus(const NOX::Solver::Generic& solver,
                                                                NOX::StatusTest::CheckType) {
  const auto& grp = solver.getSolutionGroup();
  if (!grp.isF()) {  // some NOX solvers check before evaluating F
    status_ = NOX::StatusTest::Unevaluated;
    return status_;
  }
  const double normF = grp.getNormF();
  const auto& x = dynamic_cast<const NOX::Thyra::Vector&>(grp.getX()).getThyraVector();
  double scale = residualScale_->scale(x, reaction_);
  if (!(scale > 0)) scale = 1.0;  // nothing loaded: absolute residual
  scale_ = scale;
  const double r = normF / scale;
  history_[solver.getNumIterations()] = r;
  atFloor_ = std::isfinite(r) && r > tol_ && normF <= floor_;
  status_ = (std::isfinite(r) && (r <= tol_ || atFloor_)) ? NOX::StatusTest::Converged : NOX::StatusTest::Unconverged;
  if (status_ == NOX::StatusTest::Unconverged && stagnationStop_ > 0) {
    stagnation_ = stagnationDiagnosis(history(), stagnationStop_);
    if (!stagnation_.empty()) status_ = NOX::StatusTest::Failed;
  }
  return status_;
}

std::ostream& NormalizedResidualTest::print(std::ostream& os, int indent) const {
  for (int i = 0; i < indent; ++i) os << ' ';
  return os << "normalised residual <= " << tol_ << "\n";
}

std::vector<double> NormalizedResidualTest::history() const {
  std::vector<double> h;
  for (const auto& kv : history_) h.push_back(kv.second);
  return h;
}

double EvaluatorResidualScale::scale(const Thyra::VectorBase<double>& x, bool& reaction) const {
  const double fext = ev_->externalForceNorm();
  reaction = !(fext > 0);
  return reaction ? ev_->reactionNorm(x) : fext;
}

double EvaluatorResidualScale::roundoff() const { return ev_->roundoffScale(); }

std::string linearSolverFailure(const std::exception& e) {
  // Trilinos exceptions carry the source location and the throw test before the reason;
  // keep the reason (the last non-empty line).
  std::string reason, line;
  std::stringstream ss(e.what());
  while (std::getline(ss, line))
    if (line.find_first_not_of(" \t") != std::string::npos) reason = line;
  if (reason.find("factorization failed") != std::string::npos)
    reason += " (the tangent is singular: an unstable or unconstrained mode)";
  return "linear solver error: " + reason;
}

NewtonStatusTests newtonStatusTests(Teuchos::RCP<const ResidualScale> scale, double tolerance, int maxIterations,
                                    double floorFactor, int stagnationStop) {
  NewtonStatusTests t;
  t.residual = Teuchos::rcp(new NormalizedResidualTest(std::move(scale), tolerance, floorFactor, stagnationStop));
  t.maxIters = Teuchos::rcp(new NOX::StatusTest::MaxIters(maxIterations));
  t.finite = Teuchos::rcp(new NOX::StatusTest::FiniteValue);
  t.combo = Teuchos::rcp(new NOX::StatusTest::Combo(NOX::StatusTest::Combo::OR));
  t.combo->addStatusTest(t.finite);
  t.combo->addStatusTest(t.residual);
  t.combo->addStatusTest(t.maxIters);
  return t;
}

NewtonSolver::NewtonSolver(Teuchos::RCP<const Thyra::ModelEvaluator<double>> model,
                           Teuchos::RCP<const ResidualScale> scale, const NewtonOptions& options)
    : model_(std::move(model)), scale_(std::move(scale)), options_(options) {}

NewtonSolver::NewtonSolver(Teuchos::RCP<PeridynamicEvaluator> evaluator, const NewtonOptions& options)
    : NewtonSolver(evaluator, Teuchos::rcp(new EvaluatorResidualScale(evaluator)), options) {}

namespace {
/// Eisenstat-Walker's loosest relative tolerance for a Newton system (NOX's "Forcing Term Initial /
/// Maximum Tolerance"), also the cap of the forcing floor in NewtonSolver::solve.
double forcingTermMaximum(const NewtonOptions& options) { return std::max(1e-4, options.linearTolerance); }
}  // namespace

Teuchos::RCP<Teuchos::ParameterList> newtonParameters(const NewtonOptions& options) {
  auto params = Teuchos::rcp(new Teuchos::ParameterList("NOX"));
  if (options.lineSearch == "Trust Region") {
    params->set("Nonlinear Solver", "Trust Region Based");
  } else if (options.lineSearch == "Inexact Trust Region") {
    params->set("Nonlinear Solver", "Inexact Trust Region Based");
  } else {
    params->set("Nonlinear Solver", "Line Search Based");
    params->sublist("Line Search").set("Method", options.lineSearch);
  }
  auto& dir = params->sublist("Direction");
  dir.set("Method", "Newton");
  auto& newton = dir.sublist("Newton");
  if (options.forcingTerm == "Eisenstat-Walker") {
    newton.set("Forcing Term Method", "Type 2");
    // At most 1e-4: looser solves (NOX's 0.9) cost the strongly nonlinear cantilever 40 % more
    // Newton iterations and changed its adaptive load path; 1e-4 keeps both and still saves
    // about 60 % of the Krylov iterations (docs/performance.md, "The cost of a Newton iteration").
    newton.set("Forcing Term Initial Tolerance", forcingTermMaximum(options));
    newton.set("Forcing Term Minimum Tolerance", options.linearTolerance);
    newton.set("Forcing Term Maximum Tolerance", forcingTermMaximum(options));
    newton.set("Forcing Term Alpha", 2.0);
    newton.set("Forcing Term Gamma", 0.9);
  } else if (options.forcingTerm == "Constant") {
    newton.set("Forcing Term Method", "Constant");
  } else {
    throw std::invalid_argument("NewtonOptions::forcingTerm must be Constant or Eisenstat-Walker, not '" + options.forcingTerm + "'");
  }
  newton.sublist("Linear Solver").set("Tolerance", options.linearTolerance);
  newton.set("Rescue Bad Newton Solve", true);
  auto& print = params->sublist("Printing");
  print.set("Output Information", options.verbosity > 0
                                      ? NOX::Utils::Error + NOX::Utils::Warning + NOX::Utils::OuterIteration +
                                            NOX::Utils::LinearSolverDetails
                                      : NOX::Utils::Error);
  print.set("Output Processor", 0);
  return params;
}

Teuchos::RCP<Teuchos::ParameterList> newtonParametersWithStatusTests(const NewtonOptions& options, double relativeTolerance,
                                                                    double roundoff) {
  auto params = newtonParameters(options);
  auto& tests = params->sublist("Status Tests");
  tests.set("Test Type", "Combo");
  tests.set("Combo Type", "OR");
  tests.set("Number of Tests", 4);
  tests.sublist("Test 0").set("Test Type", "RelativeNormF");
  tests.sublist("Test 0").set("Tolerance", relativeTolerance);
  tests.sublist("Test 1").set("Test Type", "NormF");
  tests.sublist("Test 1").set("Tolerance", options.floorFactor * roundoff);
  tests.sublist("Test 2").set("Test Type", "MaxIters");
  tests.sublist("Test 2").set("Maximum Iterations", options.maxIterations);
  tests.sublist("Test 3").set("Test Type", "FiniteValue");
  return params;
}

Teuchos::RCP<CountingGroup> countingGroup(const Teuchos::RCP<const Thyra::ModelEvaluator<double>>& model,
                                          const Thyra::VectorBase<double>& x, double linearTolerance) {
  NOX::Thyra::Vector guess(x.clone_v());
  Teuchos::RCP<CountingGroup> group;
  if (!model->createOutArgs().supports(Thyra::ModelEvaluatorBase::OUT_ARG_W_prec)) {
    group = Teuchos::rcp(new CountingGroup(guess, model));
  } else {
    // A model that builds its own preconditioner (perinox's matrix-free W_op, the analytic
    // product or a finite difference of f, preconditioned from an assembled matrix).
    group = Teuchos::rcp(new CountingGroup(guess, model, model->create_W_op(), model->get_W_factory(),
                                           model->create_W_prec(), Teuchos::RCP<Thyra::PreconditionerFactoryBase<double>>()));
  }
  group->setTolerance(linearTolerance);
  return group;
}

NewtonResult newtonResult(const NewtonStatusTests& tests, const CountingGroup* group, NOX::StatusTest::StatusType status,
                          int iterations, const std::string& failure, int maxIterations) {
  NewtonResult result;
  const auto& residualTest = tests.residual;
  result.iterations = iterations;
  result.failure = failure;
  result.residuals = residualTest->history();
  result.reactionNormalised = residualTest->reactionNormalised();
  result.normaliser = residualTest->scale();
  result.atRoundoffFloor = residualTest->atFloor();
  result.floorNormalised = residualTest->floorNormalised();
  result.converged = result.failure.empty() && status == NOX::StatusTest::Converged &&
                     residualTest->getStatus() == NOX::StatusTest::Converged;
  result.linearFailures = group ? group->failures() : 0;
  if (group) result.linear = group->counts();
  result.linear.failures = result.linearFailures;
  // When NOX threw, getNumIterations was never read: the residual history (one entry per
  // iterate) counts the iterations it ran.
  result.work = result.iterations > 0 ? result.iterations
                                      : std::max<long long>(0, static_cast<long long>(result.residuals.size()) - 1);
  if (result.converged || !result.failure.empty()) return result;
  // The most specific cause first: a linear solver that did not solve the Newton systems makes
  // every later symptom (stagnation, iteration limit) a consequence.
  std::ostringstream s;
  const double last = result.residuals.empty() ? NAN : result.residuals.back();
  const std::string stagnation =
      !residualTest->stagnation().empty() ? residualTest->stagnation() : stagnationDiagnosis(result.residuals, 5);
  if (tests.finite->getStatus() == NOX::StatusTest::Failed)
    s << "the residual became NaN or infinite";
  else if (result.linearFailures > 0)
    s << "the linear solver did not converge in " << result.linearFailures
      << " Newton iteration(s) (Krylov iteration limit or breakdown; last achieved relative residual "
      << group->lastAchieved() << " after " << group->lastIterations()
      << " iterations): the Newton directions were inexact (last normalised residual " << last << ")";
  else if (!stagnation.empty())
    s << stagnation;
  else if (tests.maxIters->getStatus() == NOX::StatusTest::Failed)
    s << "no convergence in " << maxIterations << " Newton iterations (last normalised residual " << last << ")";
  else
    s << "the nonlinear solver stopped without convergence (line search or linear solve failed; last "
         "normalised residual " << last << ")";
  result.failure = s.str();
  return result;
}

std::string noxFailure() {
  try {
    throw;
  } catch (const EvaluationError& e) {
    return std::string("model evaluation failed: ") + e.what();
  } catch (const std::exception& e) {
    return linearSolverFailure(e);
  } catch (const char* e) {
    return std::string("nonlinear solver error: ") + e;
  }
}

NewtonResult solveNox(NOX::Solver::Generic& solver, const NewtonStatusTests& tests, const CountingGroup* group,
                      Thyra::VectorBase<double>& x, int maxIterations) {
  NOX::StatusTest::StatusType status = NOX::StatusTest::Failed;
  int iterations = 0;
  std::string failure;
  try {
    status = solver.solve();
    const auto& sol = dynamic_cast<const NOX::Thyra::Vector&>(solver.getSolutionGroup().getX());
    Thyra::copy(sol.getThyraVector(), Teuchos::ptrFromRef(x));
    iterations = solver.getNumIterations();
  } catch (const std::exception&) {
    failure = noxFailure();
  } catch (const char*) {
    failure = noxFailure();
  }
  return newtonResult(tests, group, status, iterations, failure, maxIterations);
}

NewtonResult NewtonSolver::solve(Thyra::VectorBase<double>& x) {
  const auto params = newtonParameters(options_);
  const NewtonStatusTests tests =
      newtonStatusTests(scale_, options_.tolerance, options_.maxIterations, options_.floorFactor, options_.stagnationStop);
  Teuchos::RCP<CountingGroup> group;
  NOX::StatusTest::StatusType status = NOX::StatusTest::Failed;
  int iterations = 0;
  std::string failure;
  try {
    group = countingGroup(model_, x, options_.linearTolerance);
    if (options_.forcingTerm == "Eisenstat-Walker") {
      // Eisenstat-Walker asks for 0.9 (|R_k| / |R_k-1|)^2, which at the last iteration of a
      // step solves far beyond the Newton tolerance (|R| 1e-7 -> 1e-12 for a tolerance of 1e-10).
      // A linear residual of a tenth of the tolerance is enough there: the system is solved to
      // at least 0.1 tol / r_k, capped at the forcing term's maximum (Kelley's safeguard,
      // "Iterative Methods for Linear and Nonlinear Equations", 6.3; docs/performance.md,
      // "The auxiliary cycle from level 1, and the last Newton system").
      const double cap = forcingTermMaximum(options_);
      group->setForcingFloor([residual = tests.residual, cap] {
        const double r = residual->last();
        if (!(r > 0) || !std::isfinite(r)) return 0.0;
        return std::min(cap, 0.1 * residual->tolerance() / r);
      });
    }
    group->computeF();  // the inexact trust-region solver asks for |F| before computing it
    auto solver = NOX::Solver::buildSolver(group, tests.combo, params);
    status = solver->solve();
    const auto& sol = dynamic_cast<const NOX::Thyra::Vector&>(solver->getSolutionGroup().getX());
    Thyra::copy(sol.getThyraVector(), Teuchos::ptrFromRef(x));
    iterations = solver->getNumIterations();
  } catch (const std::exception&) {
    failure = noxFailure();
  } catch (const char*) {  // NOX throws string literals in places
    failure = noxFailure();
  }
  const NewtonResult result = newtonResult(tests, group.get(), status, iterations, failure, options_.maxIterations);
  totalNewton_ += result.work;
  totalLinear_.solves += result.linear.solves;
  totalLinear_.krylovIterations += result.linear.krylovIterations;
  totalLinear_.failures += result.linear.failures;
  return result;
}

}  // namespace perinox
